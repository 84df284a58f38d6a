// Writes the small sample bundled in tests/data/extract/ (and used by the README's first run):
// a calibration, no-load reference frames and frames in which one element is pressed and then
// slides while another is touched lightly, with the true spot positions beside them.
//
//   make_extract_sample OUT_DIR
//
// The output is deterministic (fixed seeds), and a test checks that the bundled files are
// exactly what this program writes.
#include <cstdio>
#include <string>

#include "synthetic.hpp"
#include "tactile/config/calibration_file.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/json.hpp"
#include "tactile/util/pgm.hpp"

namespace {

using tactile::Calibration;
using tactile::ElementCalibration;
using tactile::Vec2;
using tactile::testing::SceneOptions;
using tactile::testing::Spot;

Calibration sample_calibration(const SceneOptions& o) {
  Calibration cal = tactile::testing::grid_calibration(o, 1, 1, 0, 12);
  cal.sensor_id = o.bit_depth == 8 ? "sample8" : "sample16";
  const double c = 0.5;
  const double z = std::sqrt(1 - c * c);
  const struct {
    Vec2 at;
    tactile::Vec3 normal;
  } layout[] = {{{63.5, 47.5}, {0, 0, 1}},
                {{33.5, 47.5}, {-c, 0, z}},
                {{93.5, 47.5}, {c, 0, z}},
                {{63.5, 17.5}, {0, -c, z}},
                {{63.5, 77.5}, {0, c, z}}};
  cal.elements.clear();
  std::uint32_t id = 0;
  for (const auto& l : layout) {
    ElementCalibration e;
    e.id = id++;
    e.center_px = l.at;
    e.radius_px = 12;
    e.zero_px = l.at + Vec2{0.25, -0.5};
    e.normal = l.normal;
    cal.elements.push_back(e);
  }
  return cal;
}

void write_set(const std::filesystem::path& dir, int bit_depth, int references, int frames) {
  SceneOptions o;
  o.width = 128;
  o.height = 96;
  o.bit_depth = bit_depth;
  o.noise_sigma = 2.0;
  const Calibration cal = sample_calibration(o);
  tactile::config::save_calibration(dir / "calibration.yaml", cal);

  tactile::util::Random rng(bit_depth == 8 ? 2024 : 2025);
  tactile::Image img;
  for (int i = 0; i < references; ++i) {
    tactile::testing::render(o, {}, rng, img);
    tactile::util::write_pgm(dir / ("reference-" + std::to_string(i) + ".pgm"), img.view());
  }
  std::string truth = "[";
  for (int f = 0; f < frames; ++f) {
    std::vector<Spot> spots;
    // Element 0: pressed harder for three frames, then slides +0.4 px per frame along x.
    const double slide = f < 3 ? 0.0 : 0.4 * (f - 2);
    spots.push_back(
        {cal.elements[0].zero_px + Vec2{slide, 0.1}, 40.0 + 30.0 * std::min(f, 3), 2.2});
    // Element 1: touched lightly from frame 2 on.
    if (f >= 2) spots.push_back({cal.elements[1].zero_px + Vec2{-0.3, 0.2}, 60.0, 1.8});
    tactile::testing::render(o, spots, rng, img);
    tactile::util::write_pgm(dir / ("frame-" + std::to_string(f) + ".pgm"), img.view());
    truth += f == 0 ? "" : ", ";
    truth += "{\"frame\": " + std::to_string(f) + ", \"spots\": [";
    for (std::size_t i = 0; i < spots.size(); ++i) {
      truth += i == 0 ? "" : ", ";
      truth += "{\"id\": " + std::to_string(i) + ", \"x_px\": ";
      tactile::util::json_number(truth, spots[i].center.x);
      truth += ", \"y_px\": ";
      tactile::util::json_number(truth, spots[i].center.y);
      truth += "}";
    }
    truth += "]}";
  }
  truth += "]\n";
  tactile::util::write_file_atomic(dir / "truth.json", truth);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2 || std::string(argv[1]) == "--help") {
    std::fprintf(
        stderr,
        "usage: make_extract_sample OUT_DIR\n"
        "Writes OUT_DIR/mono8 and OUT_DIR/mono16: calibration, references, frames, truth.\n");
    return argc == 2 ? 0 : 2;
  }
  try {
    const std::filesystem::path out = argv[1];
    write_set(out / "mono8", 8, 4, 6);
    write_set(out / "mono16", 16, 2, 3);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "make_extract_sample: %s\n", e.what());
    return 1;
  }
  return 0;
}
