#include "viewer.hpp"

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
                 "1, 8, 16, 16)")
      ->allow_extra_args(false);
  app.add_option("--f1", o.f1_n, "F1 [N] for TOUCH")->capture_default_str();
  app.add_option("--f2", o.f2_n, f2_help)->capture_default_str();
  app.add_option("--dr", o.dr_mm, "dr [mm] for SLIP")->capture_default_str();
}

void require_endpoints(const ViewerOptions& o) {
  if (o.endpoints.empty() && o.curve.empty())
    throw cli::UsageError("give at least one endpoint to subscribe to");
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
  so.topics = {wire::kFrameTopicPrefix, wire::kStatsTopicPrefix, wire::kEventTopic};
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
