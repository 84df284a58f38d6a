#include "viewer.hpp"

#include <algorithm>

#include "tactile/cli/run.hpp"
#include "tactile/config/calibration_file.hpp"
#include "tactile/util/log.hpp"
#include "tactile/wire/envelope.hpp"

namespace tactile::live {

void add_viewer_options(CLI::App& app, ViewerOptions& o, const std::string& f2_help) {
  app.add_option("endpoints", o.endpoints,
                 "publishers: sensor_node (frames, stats) and hand_node's events endpoint");
  app.add_option("--curve", o.curve,
                 "ENDPOINT=SERVER.pub: subscribe with CURVE (repeatable; docs/security.md)")
      ->allow_extra_args(false);
  app.add_option("--client-key", o.client_key, "this program's CURVE key pair (.key)");
  app.add_option("--calibration", o.calibrations,
                 "calibration files: draw the elements where their disks are (default: rings of "
                 "1, 8, 16, 16); the list ends at the first endpoint (TRANSPORT://...)")
      ->type_name("FILE");
  app.add_option("--f1", o.f1_n, "F1 [N] for TOUCH with --recompute")->capture_default_str();
  app.add_option("--f2", o.f2_n, f2_help)->capture_default_str();
  app.add_option("--dr", o.dr_mm, "dr [mm] for SLIP with --recompute")->capture_default_str();
  add_recompute_option(app, o.recompute, "no arm motion known");
}

bool looks_like_endpoint(std::string_view text) {
  return text.find("://") != std::string_view::npos;
}

void settle_endpoints(ViewerOptions& o) {
  const auto first = std::find_if(o.calibrations.begin(), o.calibrations.end(),
                                  [](const std::string& c) { return looks_like_endpoint(c); });
  o.endpoints.insert(o.endpoints.begin(), first, o.calibrations.end());
  o.calibrations.erase(first, o.calibrations.end());
  if (o.endpoints.empty() && o.curve.empty())
    throw cli::UsageError("give at least one endpoint to subscribe to");
}

CLI::Option* add_recompute_option(CLI::App& app, std::string& detector, const std::string& note) {
  return app
      .add_option("--recompute", detector,
                  "decide TOUCH, SLIP and OVER here with this slip detector (paper, field or "
                  "learned; " +
                      note +
                      ") instead of showing hand_node's decisions (topic decision), and say so")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            if (control::slip_detector_from_string(text)) return {};
            return "must be " + std::string(control::kSlipDetectorNames);
          },
          "DETECTOR", "slip detector"));
}

std::optional<control::SlipDetectorKind> recompute_detector(const std::string& detector) {
  if (detector.empty()) return std::nullopt;
  return control::slip_detector_from_string(detector);
}

std::vector<Calibration> load_calibrations(const ViewerOptions& o) {
  std::vector<Calibration> cals;
  std::vector<std::string> warnings;
  for (const auto& c : o.calibrations)
    cals.push_back(config::load_calibration(c, &warnings));
  for (const auto& w : warnings)
    util::log_warn("{}", w);
  return cals;
}

control::Config flag_thresholds(const ViewerOptions& o) {
  control::Config cc;
  cc.f1_n = o.f1_n;
  cc.f2_n = o.f2_n;
  cc.dr_mm = o.dr_mm;
  return cc;
}

recording::SourceOptions viewer_sources(const ViewerOptions& o) {
  recording::SourceOptions so;
  so.endpoints = o.endpoints;
  for (const auto& c : o.curve)
    so.curve.push_back(recording::parse_curve_source(c));
  so.client_key = o.client_key;
  so.topics = {wire::kFrameTopicPrefix, wire::kStatsTopicPrefix, wire::kEventTopic,
               wire::kDecisionTopic};
  so.max_message_bytes = std::int64_t{4} << 20;
  so.receive_hwm = 10000;
  return so;
}

std::vector<std::string> endpoints_of(const recording::Sources& sources) {
  std::vector<std::string> eps;
  for (std::size_t i = 0; i < sources.size(); ++i)
    eps.push_back(sources.endpoint(i));
  return eps;
}

}  // namespace tactile::live
