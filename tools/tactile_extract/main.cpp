// tactile_extract: the measurement core as a command (docs/calibration.md, "tactile_extract").
//
// Reads a calibration, a no-load reference (the mean of one or more PGM frames) and a sequence
// of PGM frames; prints one JSON object per frame on standard output.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>
#include <vector>

#include "tactile/cli/run.hpp"
#include "tactile/config/calibration_file.hpp"
#include "tactile/extractor.hpp"
#include "tactile/util/json.hpp"
#include "tactile/util/log.hpp"
#include "tactile/util/pgm.hpp"

namespace {

using tactile::util::json_number;

struct Options {
  std::string calibration;
  std::vector<std::string> references;
  std::vector<std::string> frames;
  double fps = 100.0;
  std::string estimator = "gaussian";
  std::string format = "json";
  bool no_reference_check = false;
};

std::string describe(const tactile::ImageView& v) {
  return std::to_string(v.width) + "x" + std::to_string(v.height) + " " +
         std::to_string(tactile::bit_depth(v.format)) + "-bit";
}

std::string describe(const tactile::Calibration& c) {
  return std::to_string(c.width) + "x" + std::to_string(c.height) + " " +
         std::to_string(c.bit_depth) + "-bit";
}

void append_frame_json(std::string& out, std::size_t index, double time_s,
                       std::span<const tactile::ElementReading> readings) {
  out += "{\"frame\": " + std::to_string(index) + ", \"time_s\": ";
  json_number(out, time_s);
  out += ", \"elements\": [";
  bool first = true;
  for (const auto& r : readings) {
    if (!first) out += ", ";
    first = false;
    out += "{\"id\": " + std::to_string(r.id) + ", \"contact\": " + (r.contact ? "true" : "false");
    out += ", \"G\": ";
    json_number(out, r.G);
    if (r.contact) {
      out += ", \"x_px\": ";
      json_number(out, r.x_px);
      out += ", \"y_px\": ";
      json_number(out, r.y_px);
    } else {
      out += ", \"x_px\": null, \"y_px\": null";
    }
    const std::pair<const char*, double> rest[] = {
        {"dx_mm", r.dx_mm}, {"dy_mm", r.dy_mm}, {"ux_mm", r.ux_mm}, {"uy_mm", r.uy_mm},
        {"fx", r.fx},       {"fy", r.fy},       {"fz", r.fz}};
    for (const auto& [key, value] : rest) {
      out += ", \"";
      out += key;
      out += "\": ";
      json_number(out, value);
    }
    out += "}";
  }
  out += "]}\n";
}

void append_frame_table(std::string& out, std::size_t index, double time_s,
                        std::span<const tactile::ElementReading> readings) {
  std::size_t touching = 0;
  for (const auto& r : readings)
    touching += r.contact ? 1 : 0;
  out += fmt::format("frame {} at {:.3f} s: {} of {} elements in contact\n", index, time_s,
                     touching, readings.size());
  if (touching == 0) return;
  out +=
      "     id        G     x_px     y_px   dx_mm   dy_mm   ux_mm   uy_mm    fx_N    fy_N    "
      "fz_N\n";
  for (const auto& r : readings) {
    if (!r.contact) continue;
    out += fmt::format(
        "  {:5d} {:8.0f} {:8.3f} {:8.3f} {:7.4f} {:7.4f} {:7.4f} {:7.4f} {:7.3f} {:7.3f} {:7.3f}\n",
        r.id, r.G, r.x_px, r.y_px, r.dx_mm, r.dy_mm, r.ux_mm, r.uy_mm, r.fx, r.fy, r.fz);
  }
}

int run(const Options& opt) {
  tactile::ExtractorOptions xo;
  const auto estimator = tactile::parse_estimator(opt.estimator);
  if (!estimator) {
    throw std::invalid_argument(std::string("--estimator must be ") + tactile::kEstimatorNames +
                                ", is '" + opt.estimator + "'");
  }
  xo.estimator = *estimator;
  xo.reference_frames = static_cast<int>(opt.references.size());
  xo.reference_spot_check = !opt.no_reference_check;
  if (!(opt.fps > 0)) throw std::invalid_argument("--fps must be positive");

  std::vector<std::string> warnings;
  tactile::Extractor extractor(tactile::config::load_calibration(opt.calibration, &warnings), xo);
  for (const auto& w : warnings)
    tactile::util::log_warn("{}", w);
  const tactile::Calibration& cal = extractor.calibration();

  tactile::ReferenceResult rr;
  for (std::size_t i = 0; i < opt.references.size(); ++i) {
    const std::string& path = opt.references[i];
    const tactile::Image ref = tactile::util::read_pgm(path);
    rr = extractor.add_reference_frame(ref.view());
    if (rr.status == tactile::ReferenceStatus::kWrongSize ||
        rr.status == tactile::ReferenceStatus::kWrongFormat) {
      throw std::runtime_error(path + ": reference is " + describe(ref.view()) +
                               " but the calibration needs " + describe(cal));
    }
    if (rr.status != tactile::ReferenceStatus::kCollecting &&
        rr.status != tactile::ReferenceStatus::kComplete) {
      throw std::runtime_error(path + ": reference " + tactile::to_string(rr.status) +
                               " (element " + std::to_string(rr.element_id) + ", excess G " +
                               std::to_string(rr.value) +
                               "); use --no-reference-check to accept it");
    }
  }
  if (!extractor.has_reference()) throw std::runtime_error("the reference did not complete");

  const double period_s = 1.0 / opt.fps;
  const auto period_ns = static_cast<std::int64_t>(1e9 * period_s);
  std::string line;
  for (std::size_t i = 0; i < opt.frames.size(); ++i) {
    const std::string& path = opt.frames[i];
    const tactile::Image frame = tactile::util::read_pgm(path);
    const auto status =
        extractor.measure(frame.view(), {i, static_cast<std::int64_t>(i) * period_ns});
    if (status == tactile::MeasureStatus::kWrongSize ||
        status == tactile::MeasureStatus::kWrongFormat) {
      throw std::runtime_error(path + ": frame is " + describe(frame.view()) +
                               " but the calibration needs " + describe(cal));
    }
    if (status != tactile::MeasureStatus::kOk) {
      throw std::runtime_error(path + ": " + tactile::to_string(status));
    }
    line.clear();
    if (opt.format == "table") {
      append_frame_table(line, i, static_cast<double>(i) * period_s, extractor.readings());
    } else {
      append_frame_json(line, i, static_cast<double>(i) * period_s, extractor.readings());
    }
    // One whole line per frame: a later failure never leaves half a frame on standard output.
    if (std::fwrite(line.data(), 1, line.size(), stdout) != line.size() ||
        std::fflush(stdout) != 0) {
      throw std::runtime_error("standard output: write failed");
    }
  }
  if (opt.frames.empty())
    tactile::util::log_info("no frames given: calibration and reference are valid");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  tactile::util::set_program_name("tactile_extract");
  Options opt;
  CLI::App app{
      "Measures every sensing element of an optical three-axis tactile sensor in PGM frames: "
      "integrated gray-scale G, centroid, per-frame displacement, shear displacement and forces. "
      "Prints one JSON object per frame on standard output."};
  app.add_option("--calibration", opt.calibration, "calibration file (tactile-calibration/1 YAML)")
      ->required();
  app.add_option("--reference", opt.references,
                 "no-load reference frame (P5 PGM); repeat to average several")
      ->required()
      ->allow_extra_args(false);  // one file per --reference; the rest are frames
  app.add_option("--fps", opt.fps, "frame rate the frames were taken at")->capture_default_str();
  app.add_option("--estimator", opt.estimator,
                 std::string("centroid estimator: ") + tactile::kEstimatorNames)
      ->capture_default_str();
  app.add_option("--format", opt.format,
                 "json: one JSON object per frame (docs/calibration.md, tactile_extract); table: a "
                 "readable table of the elements in contact")
      ->check(CLI::IsMember({"json", "table"}))
      ->capture_default_str();
  app.add_flag("--no-reference-check", opt.no_reference_check,
               "accept a reference that shows a spot on an element");
  app.add_option("frames", opt.frames, "frames to measure (P5 PGM), in order");
  return tactile::cli::run(app, argc, argv, [&] { return run(opt); });
}
