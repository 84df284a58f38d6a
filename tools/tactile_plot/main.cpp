// tactile_plot: figures from a tactile log as PNG files (docs/tools.md): the paper's Fig. 3
// (shear vector field) and Fig. 10 (y centroid change against fingertip x), per-element force
// maps, flag and event timelines, latency histograms.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <set>
#include <string>
#include <vector>

#include "plot_data.hpp"
#include "tactile/cli/run.hpp"
#include "tactile/config/calibration_file.hpp"
#include "tactile/recording/log_reader.hpp"
#include "tactile/util/clock.hpp"
#include "tactile/util/log.hpp"
#include "tactile/util/stop.hpp"
#include "viewer.hpp"

namespace {

using tactile::recording::ReadStatus;

struct Options {
  std::string log;
  std::string out = "plots";
  std::vector<std::string> figures{"all"};
  std::vector<double> at;
  std::vector<std::string> sensors;
  int element = -1;
  std::vector<std::string> calibrations;
  double f1 = tactile::control::Config{}.f1_n;
  double f2 = tactile::control::Config{}.f2_n;
  double dr = tactile::control::Config{}.dr_mm;
  std::string recompute;
  int width = 1000;
  int height = 700;
  std::string log_level = "info";
};

int run(const Options& opt) {
  tactile::util::set_log_level(tactile::util::parse_log_level(opt.log_level));
  const std::set<std::string> known{"all", "shear", "fig10", "forces", "timeline", "latency"};
  std::set<std::string> figures;
  for (const auto& f : opt.figures) {
    if (known.count(f) == 0) {
      throw std::invalid_argument(
          "--figure must be shear, fig10, forces, timeline, latency or all, is '" + f + "'");
    }
    if (f == "all") {
      figures.insert(known.begin(), known.end());
    } else {
      figures.insert(f);
    }
  }
  if (opt.width < 320 || opt.height < 240)
    throw std::invalid_argument("--width/--height: at least 320x240");
  for (const double t : opt.at) {
    if (!(t >= 0)) throw std::invalid_argument("--at must be seconds from the log's start (>= 0)");
  }
  tactile::plots::PlotOptions po;
  po.at_s = opt.at;
  po.sensors = opt.sensors;
  if (opt.element >= 0) po.element = static_cast<std::uint32_t>(opt.element);
  po.control.f1_n = opt.f1;
  po.control.f2_n = opt.f2;
  po.control.dr_mm = opt.dr;
  po.recompute = tactile::live::recompute_detector(opt.recompute);
  po.width = opt.width;
  po.height = opt.height;
  std::vector<std::string> warnings;
  for (const auto& c : opt.calibrations)
    po.calibrations.push_back(tactile::config::load_calibration(c, &warnings));
  for (const auto& w : warnings)
    tactile::util::log_warn("{}", w);

  tactile::recording::LogReader reader(opt.log);
  tactile::plots::PlotData data(po);
  tactile::v1::LogRecord rec;
  ReadStatus s;
  std::uint64_t n = 0;
  std::int64_t next_progress = tactile::util::monotonic_ns() + 2'000'000'000;
  tactile::util::install_stop_handlers();
  while ((s = reader.next(rec)) == ReadStatus::kRecord) {
    if (tactile::util::stop_requested()) {
      tactile::util::log_info("stopped before drawing");
      return tactile::util::interrupted_exit_status();
    }
    data.add(rec);
    if ((++n & 1023) == 0 && tactile::util::monotonic_ns() >= next_progress) {
      next_progress = tactile::util::monotonic_ns() + 2'000'000'000;
      tactile::util::log_info(
          "read {:.0f} % of {} ({} records)",
          100.0 * static_cast<double>(reader.position()) /
              static_cast<double>(std::max<std::uint64_t>(reader.file_size(), 1)),
          opt.log, n);
    }
  }
  data.finish();
  int code = 0;
  if (s == ReadStatus::kTruncated) tactile::util::log_warn("{}", reader.problem());
  if (s == ReadStatus::kCorrupt) {
    std::fprintf(stderr, "tactile_plot: %s (plotting what came before)\n",
                 reader.problem().c_str());
    code = 1;
  }
  bool any_frame = false;
  for (const auto& sd : data.sensors())
    any_frame = any_frame || !sd.frames.empty();
  if (!any_frame) {
    throw std::runtime_error(opt.log + ": no TactileFrames (topic frame/<sensor_id>)" +
                             (opt.sensors.empty() ? std::string() : " of the sensors asked for") +
                             " to plot");
  }
  // A time past the recording would draw its last frame as if asked for: refuse it.
  if (const auto range = data.frame_time_range()) {
    for (const double t : opt.at) {
      if (t > range->second) {
        throw std::invalid_argument(fmt::format(
            "--at {:g}: past the end of {}, whose frames span {:.3f} to {:.3f} s from its start", t,
            opt.log, range->first, range->second));
      }
    }
  }
  std::vector<std::filesystem::path> written;
  auto add = [&](std::vector<std::filesystem::path> files) {
    written.insert(written.end(), files.begin(), files.end());
  };
  if (figures.count("shear") != 0) add(tactile::plots::draw_shear_fields(data, opt.out));
  std::printf("%s\n", data.flag_source_text().c_str());
  if (figures.count("fig10") != 0) {
    add(tactile::plots::draw_fig10(data, opt.out));
    std::printf("Fig. 10 fingertip x: %s\n", data.position_source_text().c_str());
  }
  if (figures.count("forces") != 0) add(tactile::plots::draw_force_maps(data, opt.out));
  if (figures.count("timeline") != 0) add(tactile::plots::draw_timeline(data, opt.out));
  if (figures.count("latency") != 0) add(tactile::plots::draw_latency(data, opt.out));
  for (const auto& p : written)
    std::printf("wrote %s\n", p.string().c_str());
  std::fflush(stdout);
  return code;
}

}  // namespace

int main(int argc, char** argv) {
  tactile::util::set_program_name("tactile_plot");
  Options opt;
  CLI::App app{
      "Draws figures from a tactile log (tactile_record) as PNG files: the paper's Fig. 3 shear "
      "vector field (shear), Fig. 10 y centroid change against fingertip x (fig10), element "
      "force maps (forces), forces/slip/flags/events over time (timeline) and latency "
      "histograms (latency)."};
  app.add_option("log", opt.log, "the log file")->required();
  app.add_option("-o,--out", opt.out, "folder for the PNG files")->capture_default_str();
  app.add_option("--figure", opt.figures,
                 "shear, fig10, forces, timeline, latency or all (repeatable)")
      ->capture_default_str()
      ->allow_extra_args(false);
  app.add_option("--at", opt.at,
                 "seconds from the log's start of a shear field / force map (repeatable; default: "
                 "the frame with the largest total shear)")
      ->allow_extra_args(false);
  app.add_option("--sensor", opt.sensors, "plot only this fingertip (repeatable)")
      ->allow_extra_args(false);
  app.add_option("--element", opt.element,
                 "Fig. 10: this element's dy instead of the element moving most");
  // One file per --calibration, as --help shows it; files given as a list after one flag are
  // taken too (CLI11 keeps the last argument for the log).
  app.add_option("--calibration", opt.calibrations,
                 "calibration file: element positions for the maps (default: mean centroids in "
                 "the log); repeatable")
      ->type_name("FILE")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  app.add_option("--f1", opt.f1, "F1 [N]: drawn as a line; TOUCH with --recompute")
      ->capture_default_str();
  app.add_option("--f2", opt.f2, "F2 [N]: drawn as a line; OVER with --recompute")
      ->capture_default_str();
  app.add_option("--dr", opt.dr, "dr [mm]: drawn as a band; SLIP with --recompute")
      ->capture_default_str();
  tactile::live::add_recompute_option(app, opt.recompute, "no arm motion used; titles say so");
  app.add_option("--width", opt.width, "picture width in pixels")->capture_default_str();
  app.add_option("--height", opt.height,
                 "picture height in pixels (shear fields: as tall as their panels need)")
      ->capture_default_str();
  tactile::cli::add_log_level(app, opt.log_level);
  return tactile::cli::run(app, argc, argv, [&] { return run(opt); });
}
