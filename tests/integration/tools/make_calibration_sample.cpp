// Writes the sample calibration set bundled in tests/data/calibration/ (the walk-through of
// docs/calibration.md runs on it): frames of the rig's simulated sensor through the rig's optics,
// no-load references, a light press and frames under known normal and shear loads, the loads CSV
// that names them, and the sensor's true calibration to check the result against.
//
//   make_calibration_sample OUT_DIR
//
// A 352 x 352 camera (the rig's sensor scaled to it, so the set stays small), 8 bits, read noise
// 2 gray levels, the cameras' live background. Deterministic (fixed seeds); a test checks that
// the bundled files are exactly what this program writes.
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "calibrate_scene.hpp"
#include "tactile/config/calibration_file.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/pgm.hpp"

namespace {

using namespace tactile;

int run(const std::filesystem::path& out) {
  rig::CameraParams cam;
  cam.width = 352;
  cam.height = 352;
  const rig::SensorOpticsParams optics;
  Calibration truth = rig::make_calibration("left", cam, optics, testing::calib::rig_normals());
  rig::Renderer renderer(truth, cam, optics, 1901);
  util::Random rng(1902);
  Image image;
  std::filesystem::create_directories(out / "loaded");
  const auto frame = [&](const std::vector<rig::ElementLoad>& loads, const std::string& name) {
    renderer.render(loads, rng, image);
    util::write_pgm(out / name, image.view());
  };
  const std::size_t n = truth.elements.size();
  for (int i = 0; i < 4; ++i)
    frame(std::vector<rig::ElementLoad>(n), "reference-" + std::to_string(i) + ".pgm");
  frame(std::vector<rig::ElementLoad>(n, rig::ElementLoad{0.3, 0, 0}), "press.pgm");
  // Every element sees 9 normal loads and 7 shear loads along x and along y over the frames.
  const double fz[] = {0.1, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 1.75, 2.0};
  const double fs[] = {-0.25, -0.15, -0.05, 0.0, 0.05, 0.15, 0.25};
  std::string loads =
      "# Applied loads (N) per frame and element; shear along the image's x (columns) and y "
      "(rows).\nframe,element,fz_N,fx_N,fy_N\n";
  for (std::size_t j = 0; j < 9; ++j) {
    std::vector<rig::ElementLoad> l(n);
    char name[32];
    std::snprintf(name, sizeof name, "loaded/f%02zu.pgm", j);
    for (std::size_t k = 0; k < n; ++k) {
      const double z = fz[(k + j) % 9];
      const double x = fs[(k + 2 * j) % 7];
      const double y = fs[(3 * k + j) % 7];
      l[k] = {z, testing::calib::shear_mm(truth, x), testing::calib::shear_mm(truth, y)};
      char row[96];
      std::snprintf(row, sizeof row, "%s,%u,%g,%g,%g\n", name, truth.elements[k].id, z, x, y);
      loads += row;
    }
    frame(l, name);
  }
  util::write_file_atomic(out / "loads.csv", loads);
  config::save_calibration(out / "truth.yaml", truth);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_calibration_sample OUT_DIR\n");
    return 2;
  }
  try {
    return run(argv[1]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "make_calibration_sample: %s\n", e.what());
    return 1;
  }
}
