#pragma once

// What the live viewers (tactile_live in a terminal, tactile_web in a browser) share at their
// edge: the subscription options, the calibrations that place the elements, the thresholds of
// the flags, and what they subscribe to.
#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tactile/calibration.hpp"
#include "tactile/control/config.hpp"
#include "tactile/recording/sources.hpp"

namespace tactile::live {

struct ViewerOptions {
  std::vector<std::string> endpoints;
  std::vector<std::string> curve;  // ENDPOINT=SERVER.pub
  std::string client_key;
  std::vector<std::string> calibrations;
  double f1_n = control::Config{}.f1_n;
  double f2_n = control::Config{}.f2_n;
  double dr_mm = control::Config{}.dr_mm;
  std::string recompute;  // --recompute: "paper", "field" or "learned"; "" shows hand_node's
};

// The endpoints, --curve, --client-key, --calibration, --f1, --f2, --dr and --recompute;
// `f2_help` says what this viewer draws with F2.
void add_viewer_options(CLI::App& app, ViewerOptions& options, const std::string& f2_help);

// `--calibration A B ENDPOINT...` as --help shows it: the list of files ends at the first
// ZeroMQ endpoint (it names its transport, "tcp://..."), which with the rest joins the endpoints.
// Then throws cli::UsageError when there is nothing to subscribe to.
void settle_endpoints(ViewerOptions& options);

// The calibration files, read (their warnings logged); throws naming a bad file.
std::vector<Calibration> load_calibrations(const ViewerOptions& options);

// The flag analyzer's thresholds: F1, F2 and dr from the options, the rest the defaults.
control::Config flag_thresholds(const ViewerOptions& options);

// --recompute DETECTOR (paper, field or learned) into `detector`, checked when parsed; every
// viewer (tactile_plot too) takes it. `note` says what the detector lacks in this viewer.
CLI::Option* add_recompute_option(CLI::App& app, std::string& detector, const std::string& note);

// The detector --recompute names; nullopt ("") : show hand_node's decisions.
std::optional<control::SlipDetectorKind> recompute_detector(const std::string& detector);

// Whether `text` is a ZeroMQ endpoint ("TRANSPORT://ADDRESS") rather than a file.
bool looks_like_endpoint(std::string_view text);

// Frames, stats and events of every endpoint, plain or CURVE; throws naming a bad --curve.
recording::SourceOptions viewer_sources(const ViewerOptions& options);

// The endpoints as connected, in order (for the model and the screen).
std::vector<std::string> endpoints_of(const recording::Sources& sources);

}  // namespace tactile::live
