// tactile_calibrate: makes a sensor's calibration file (docs/calibration.md, "Calibration
// workflow"): `layout` finds the elements in frames of a light press, `measure` turns frames
// taken under known loads into a samples CSV with the real measurement core, `fit` fits the
// normal and shear curves and writes the finished calibration.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "calibrate.hpp"
#include "tactile/cli/run.hpp"
#include "tactile/config/calibration_file.hpp"
#include "tactile/util/clock.hpp"
#include "tactile/util/files.hpp"
#include "tactile/util/log.hpp"
#include "tactile/util/pgm.hpp"

namespace {

namespace cal = tactile::calibrate;
namespace fs = std::filesystem;
using tactile::util::log_info;
using tactile::util::log_warn;

// A bad option or option value: exit status 2.
using tactile::cli::UsageError;

// Logs "N of M frames" every two seconds while long work goes on, and once at the end.
class ProgressLog {
 public:
  explicit ProgressLog(std::string step) : step_(std::move(step)) {}
  cal::Progress callback() {
    return [this](std::size_t done, std::size_t total, const char* what) {
      const std::int64_t now = tactile::util::monotonic_ns();
      if (done < total && now - last_ns_ < 2'000'000'000) return;
      if (done == total && done == last_done_) return;
      last_ns_ = now;
      last_done_ = done;
      log_info("{}: {} of {} {}", step_, done, total, what);
    };
  }

 private:
  std::string step_;
  std::int64_t last_ns_ = tactile::util::monotonic_ns();
  std::size_t last_done_ = 0;
};

void check_output(const std::string& path, bool overwrite) {
  if (path.empty()) throw UsageError("-o FILE is required");
  if (!overwrite && fs::exists(path))
    throw std::runtime_error(path + " exists: give --overwrite to replace it");
}

std::vector<tactile::Image> read_frames(const std::vector<std::string>& paths, const char* step) {
  std::vector<tactile::Image> out;
  out.reserve(paths.size());
  ProgressLog log(std::string(step) + " reading");
  const auto progress = log.callback();
  for (const std::string& p : paths) {
    out.push_back(tactile::util::read_pgm(p));
    progress(out.size(), paths.size(), "frames");
  }
  return out;
}

tactile::CentroidEstimator estimator_of(const std::string& name) {
  const auto e = tactile::parse_estimator(name);
  if (!e) {
    throw UsageError(std::string("--estimator must be ") + tactile::kEstimatorNames + ", is '" +
                     name + "'");
  }
  return *e;
}

// --- layout --------------------------------------------------------------------------------------

struct LayoutArgs {
  cal::LayoutOptions opt;
  std::vector<std::string> frames;
  std::vector<std::string> references;
  std::string output;
  std::string marks;
  std::string order = "rings";
  std::string estimator = "gaussian";
  std::vector<double> center;
  double noise_floor = -1;
  double contact_on = -1;
  double contact_off = -1;
  std::size_t expect = 41;
  bool overwrite = false;
};

void add_layout(CLI::App& app, LayoutArgs& a) {
  CLI::App* c = app.add_subcommand(
      "layout",
      "Finds the sensing elements in frames of a light press and writes the layout of a "
      "calibration file: disks, zero positions, ids (rings by radius, then azimuth) and normals. "
      "With --reference, each frame's increment over the no-load reference shows the spots (a "
      "sequence of presses: every element pressed in at least one frame); without, the mean of "
      "the frames is one light-press image and its background is estimated from it.");
  c->add_option("frames", a.frames, "frames of the light press (P5 PGM)")->required();
  c->add_option("--reference", a.references, "no-load frame (P5 PGM); repeat to average several")
      ->allow_extra_args(false);
  c->add_option("--sensor-id", a.opt.sensor_id, "sensor id written into the file")->required();
  c->add_option("--mm-per-px", a.opt.mm_per_px, "scale at the element plane (mm per pixel)")
      ->required();
  c->add_option("-o,--output", a.output, "calibration file to write")->required();
  c->add_option("--expect", a.expect, "refuse unless this many elements are found (0: any)")
      ->capture_default_str();
  c->add_option("--radius", a.opt.radius_px,
                "radius of every measurement disk, px (0: 0.45 x the smallest element distance)")
      ->capture_default_str();
  c->add_option("--order", a.order,
                "ids by rings (radius from the centre, then azimuth) or rows (top to bottom, "
                "then left to right)")
      ->check(CLI::IsMember({"rings", "rows"}))
      ->capture_default_str();
  c->add_option("--rings", a.opt.ring_counts,
                "elements per ring (or row), innermost first, to check, e.g. 1,8,16,16")
      ->delimiter(',');
  c->add_option("--ring-gap", a.opt.ring_gap_px,
                "radii (or rows) further apart than this start a new ring, px (0: the disk radius)")
      ->capture_default_str();
  c->add_option("--center", a.center,
                "layout centre X,Y in pixels (the dome's apex; default: mean of the elements)")
      ->delimiter(',')
      ->expected(2);
  c->add_option("--ring-polar-deg", a.opt.ring_polar_deg,
                "polar angle of each ring on the hemispherical dome, innermost first, e.g. "
                "0,10,20,30: normals from the dome model (without: [0, 0, 1] to fill in)")
      ->delimiter(',');
  c->add_option("--azimuth-offset-deg", a.opt.azimuth_offset_deg,
                "fingertip azimuth = image azimuth (+x toward +y) + this")
      ->capture_default_str();
  c->add_flag("--mirror", a.opt.mirror, "the image is mirrored: negate the image azimuth");
  c->add_option("--noise-floor", a.noise_floor,
                "noise_floor to write, gray levels (default: max(4, 3 sigma) from the frames)");
  c->add_option("--contact-on", a.contact_on,
                "contact.on to write (default 400, x257 for 16-bit, scaled up with the noise)");
  c->add_option("--contact-off", a.contact_off, "contact.off to write (default 250, likewise)");
  c->add_option("--detect-sigmas", a.opt.detect_sigmas,
                "a spot needs a pixel this many noise sigmas above the background")
      ->capture_default_str();
  c->add_option("--min-area", a.opt.min_area, "a spot covers at least this many pixels")
      ->capture_default_str();
  c->add_option("--merge-px", a.opt.merge_px,
                "detections in different frames this close are one element, px")
      ->capture_default_str();
  c->add_option("--estimator", a.estimator,
                "centroid estimator the positions are measured with (use sensor_node's)")
      ->capture_default_str();
  c->add_option("--marks", a.marks,
                "also write an 8-bit PGM of the increment with every disk and position drawn");
  c->add_flag("--overwrite", a.overwrite, "replace an existing output file");
}

int run_layout(LayoutArgs& a) {
  a.opt.expect = a.expect;
  a.opt.order = a.order == "rows" ? cal::ElementOrder::kRows : cal::ElementOrder::kRings;
  a.opt.estimator = estimator_of(a.estimator);
  if (!a.center.empty()) a.opt.center = tactile::Vec2{a.center[0], a.center[1]};
  if (a.noise_floor >= 0) a.opt.noise_floor = a.noise_floor;
  if (a.contact_on >= 0) a.opt.contact_on = a.contact_on;
  if (a.contact_off >= 0) a.opt.contact_off = a.contact_off;
  check_output(a.output, a.overwrite);
  cal::LayoutInput in;
  in.references = read_frames(a.references, "layout");
  in.frames = read_frames(a.frames, "layout");
  ProgressLog log("layout");
  const cal::LayoutResult r = cal::find_layout(in, a.opt, log.callback());
  const tactile::Calibration& c = r.calibration;
  std::string out = fmt::format(
      "{} elements in {} {} ({}) around ({:.2f}, {:.2f}); disk radius {} px; pixel noise {:.2f} "
      "gray levels\nnoise_floor {:.4g}, contact on {:.4g} off {:.4g}; normals: {}\n",
      c.elements.size(), r.group_counts.size(), a.order, fmt::join(r.group_counts, ", "),
      r.center.x, r.center.y, c.elements.front().radius_px, r.noise_sigma, c.noise_floor,
      c.contact_on, c.contact_off,
      r.dome_normals ? fmt::format("dome model, ring polar angles {} deg",
                                   fmt::join(a.opt.ring_polar_deg, ", "))
                     : std::string("[0, 0, 1] for every element: fill them in"));
  out += "   id ring     x_px     y_px  azimuth  frames  spread_px         G\n";
  for (const cal::FoundElement& e : r.elements) {
    out += fmt::format("{:5d} {:4d} {:8.3f} {:8.3f} {:8.2f} {:7d} {:10.4f} {:9.0f}\n", e.id, e.ring,
                       e.position.x, e.position.y, e.azimuth_deg, e.frames, e.spread_px, e.G);
  }
  std::fputs(out.c_str(), stdout);
  std::fflush(stdout);
  tactile::config::save_calibration(a.output, c);
  log_info("wrote {}; its curves are placeholders until `tactile_calibrate fit`", a.output);
  if (!r.dome_normals) {
    log_warn(
        "every normal is [0, 0, 1]: write each element's inward normal into {} (hand_node "
        "re-compresses along them), or give --ring-polar-deg",
        a.output);
  }
  if (!a.marks.empty()) {
    tactile::util::write_pgm(a.marks, cal::mark_layout(r).view());
    log_info("wrote {}", a.marks);
  }
  return 0;
}

// --- measure -------------------------------------------------------------------------------------

struct MeasureArgs {
  std::string calibration;
  std::vector<std::string> references;
  std::string loads;
  std::string output;
  std::string estimator = "gaussian";
  bool no_reference_check = false;
  bool overwrite = false;
};

void add_measure(CLI::App& app, MeasureArgs& a) {
  CLI::App* c = app.add_subcommand(
      "measure",
      "Measures frames taken under known loads with the real measurement core and writes the "
      "samples CSV that `fit` reads: one row per row of the loads CSV (frame, element, fz_N, "
      "fx_N, fy_N), with the measured G, contact and u.");
  c->add_option("--calibration", a.calibration, "the sensor's calibration (from `layout`)")
      ->required();
  c->add_option("--reference", a.references, "no-load frame (P5 PGM); repeat to average several")
      ->required()
      ->allow_extra_args(false);
  c->add_option("--loads", a.loads, "loads CSV: frame,element,fz_N[,fx_N][,fy_N]")->required();
  c->add_option("-o,--output", a.output, "samples CSV to write")->required();
  c->add_option("--estimator", a.estimator, "centroid estimator (use sensor_node's)")
      ->capture_default_str();
  c->add_flag("--no-reference-check", a.no_reference_check,
              "accept a reference that shows a spot on an element");
  c->add_flag("--overwrite", a.overwrite, "replace an existing output file");
}

int run_measure(const MeasureArgs& a) {
  cal::MeasureOptions mo;
  mo.estimator = estimator_of(a.estimator);
  mo.reference_spot_check = !a.no_reference_check;
  check_output(a.output, a.overwrite);
  std::vector<std::string> warnings;
  const tactile::Calibration c = tactile::config::load_calibration(a.calibration, &warnings);
  for (const auto& w : warnings)
    log_warn("{}", w);
  const auto loads = cal::parse_loads(tactile::util::read_file(a.loads), a.loads);
  const std::vector<tactile::Image> refs = read_frames(a.references, "measure");
  const fs::path base = fs::path(a.loads).parent_path();
  ProgressLog log("measure");
  const auto samples = cal::measure_samples(
      c, refs, loads,
      [&base](const std::string& name) {
        const fs::path p(name);
        return tactile::util::read_pgm(p.is_absolute() ? p : base / p);
      },
      mo, log.callback());
  std::size_t in_contact = 0;
  for (const auto& s : samples)
    in_contact += s.contact ? 1 : 0;
  tactile::util::write_file_atomic(a.output, cal::format_samples(samples));
  log_info("wrote {}: {} samples, {} in contact", a.output, samples.size(), in_contact);
  if (in_contact < samples.size()) {
    log_warn("{} samples are out of contact (G below contact.on): they serve the normal curve only",
             samples.size() - in_contact);
  }
  return 0;
}

// --- fit -----------------------------------------------------------------------------------------

struct FitArgs {
  std::string calibration;
  std::vector<std::string> samples;
  std::string output;
  cal::CurveFitOptions normal{4, 0, 0.02, {}};
  cal::CurveFitOptions shear{3, 0, 0.02, {}};
  double monotone_tolerance = 0.02;
  bool normal_only = false;
  bool shear_only = false;
  bool overwrite = false;
};

void add_fit(CLI::App& app, FitArgs& a) {
  CLI::App* c = app.add_subcommand(
      "fit",
      "Fits the normal curve F_z = g(G) and the shear curve F = f(u) (piecewise linear, through "
      "0, non-decreasing) to the samples, reports the error per element, and writes the "
      "calibration with them; refuses non-monotone data, too few points and an error above the "
      "limits.");
  c->add_option("--calibration", a.calibration, "the sensor's calibration (from `layout`)")
      ->required();
  c->add_option("--samples", a.samples,
                "samples CSV: element,fz_N,G[,fx_N,ux_mm][,fy_N,uy_mm][,contact]; repeatable")
      ->required()
      ->allow_extra_args(false);
  c->add_option("-o,--output", a.output, "calibration file to write")->required();
  c->add_option("--normal-knots", a.normal.knots, "knots of g after 0 (at quantiles of G)")
      ->capture_default_str();
  c->add_option("--shear-knots", a.shear.knots, "knots of f after 0 (at quantiles of |u|)")
      ->capture_default_str();
  c->add_option("--max-rms-normal", a.normal.max_rms_n,
                "refuse when an element's RMS error of F_z exceeds this, N (0: 5 % of the "
                "largest applied F_z)")
      ->capture_default_str();
  c->add_option("--max-rms-shear", a.shear.max_rms_n,
                "refuse when an element's RMS error of F_x/F_y exceeds this, N (0: 5 % of the "
                "largest applied shear)")
      ->capture_default_str();
  c->add_option("--monotone-tolerance", a.monotone_tolerance,
                "refuse when an element's mean measured value falls by more than this fraction "
                "of its range as the load rises")
      ->capture_default_str();
  c->add_flag("--normal-only", a.normal_only, "fit g only; keep the calibration's shear curve");
  c->add_flag("--shear-only", a.shear_only, "fit f only; keep the calibration's normal curve");
  c->add_flag("--overwrite", a.overwrite, "replace an existing output file");
}

std::string report(const char* title, const cal::CurveFit& f, const char* x_name) {
  std::string out = fmt::format("{}: {} [{}], newton [{}]\n", title, x_name,
                                fmt::join(f.curve.x(), ", "), fmt::join(f.curve.y(), ", "));
  out += "  element      N    RMS_N    max_N\n";
  for (const cal::ElementError& e : f.per_element)
    out += fmt::format("  {:7d} {:6d} {:8.4f} {:8.4f}\n", e.element, e.n, e.rms_n, e.max_n);
  out += fmt::format("  {:>7} {:6d} {:8.4f} {:8.4f}   (limit: RMS {:.4g} N per element)\n", "all",
                     f.all.n, f.all.rms_n, f.all.max_n, f.max_rms_n);
  return out;
}

int run_fit(FitArgs& a) {
  if (a.normal_only && a.shear_only)
    throw UsageError("give --normal-only or --shear-only, not both");
  a.normal.monotone_tolerance = a.monotone_tolerance;
  a.shear.monotone_tolerance = a.monotone_tolerance;
  check_output(a.output, a.overwrite);
  std::vector<std::string> warnings;
  tactile::Calibration c = tactile::config::load_calibration(a.calibration, &warnings);
  for (const auto& w : warnings)
    log_warn("{}", w);
  std::vector<cal::Sample> samples;
  for (const std::string& path : a.samples) {
    auto more = cal::read_samples(path);
    samples.insert(samples.end(), more.begin(), more.end());
  }
  for (const cal::Sample& s : samples) {
    bool known = false;
    for (const auto& e : c.elements)
      known = known || e.id == s.element;
    if (!known) {
      throw std::runtime_error(fmt::format("{}: element {} is not in the calibration of '{}'",
                                           s.where, s.element, c.sensor_id));
    }
  }
  // A refusal names the samples it was made from and the calibration that was not written.
  const std::string from = fmt::format("{}", fmt::join(a.samples, ", "));
  const auto refuse = [&](const std::string& why) {
    return std::runtime_error(fmt::format("{}: {}; {} not written", from, why, a.output));
  };
  const auto fitted = [&](auto&& fit_curve, const cal::CurveFitOptions& o) {
    try {
      return fit_curve(samples, o);
    } catch (const std::runtime_error& e) {  // a bad option (invalid_argument) passes: status 2
      throw refuse(e.what());
    }
  };
  a.normal.present_curve = c.normal_curve;
  a.shear.present_curve = c.shear_curve;
  std::string problem;
  if (!a.shear_only) {
    const cal::CurveFit g = fitted(cal::fit_normal_curve, a.normal);
    std::fputs(report("normal curve F_z = g(G)", g, "G").c_str(), stdout);
    c.normal_curve = g.curve;
    if (problem.empty()) problem = g.problem;
  }
  if (!a.normal_only) {
    const cal::CurveFit f = fitted(cal::fit_shear_curve, a.shear);
    std::fputs(report("shear curve F = f(u)", f, "mm").c_str(), stdout);
    c.shear_curve = f.curve;
    if (problem.empty()) problem = f.problem;
  }
  std::fflush(stdout);
  if (!problem.empty()) throw refuse(problem);
  tactile::config::save_calibration(a.output, c);
  log_info("wrote {}", a.output);
  return 0;
}

int run(int argc, char** argv) {
  CLI::App app{
      "tactile_calibrate: makes the calibration file of an optical three-axis tactile sensor. "
      "`layout` finds the elements in frames of a light press; `measure` measures frames taken "
      "under known loads into a samples CSV; `fit` fits the normal and shear curves and writes "
      "the calibration (docs/calibration.md, \"Calibration workflow\")."};
  app.require_subcommand(1);
  LayoutArgs layout;
  MeasureArgs measure;
  FitArgs fit;
  add_layout(app, layout);
  add_measure(app, measure);
  add_fit(app, fit);
  return tactile::cli::run(app, argc, argv, [&] {
    // The calibration code checks its option values as it starts (a bad --min-area,
    // --monotone-tolerance...): its std::invalid_argument is a usage error too.
    try {
      if (app.got_subcommand("layout")) return run_layout(layout);
      if (app.got_subcommand("measure")) return run_measure(measure);
      return run_fit(fit);
    } catch (const std::invalid_argument& e) {
      throw UsageError(e.what());
    }
  });
}

}  // namespace

int main(int argc, char** argv) {
  tactile::util::set_program_name("tactile_calibrate");
  return run(argc, argv);
}
