#pragma once

// What the live viewers (tactile_live in a terminal, tactile_web in a browser) share at their
// edge: the subscription options, the calibrations that place the elements, the thresholds of
// the flags, and what they subscribe to.
#include <CLI/CLI.hpp>
#include <string>
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
};

// The endpoints, --curve, --client-key, --calibration, --f1, --f2 and --dr; `f2_help` says what
// this viewer draws with F2.
void add_viewer_options(CLI::App& app, ViewerOptions& options, const std::string& f2_help);

// Throws cli::UsageError when there is nothing to subscribe to.
void require_endpoints(const ViewerOptions& options);

// The calibration files, read (their warnings logged); throws naming a bad file.
std::vector<Calibration> load_calibrations(const ViewerOptions& options);

// The flag analyzer's thresholds: F1, F2 and dr from the options, the rest the defaults.
control::Config flag_thresholds(const ViewerOptions& options);

// Frames, stats and events of every endpoint, plain or CURVE; throws naming a bad --curve.
recording::SourceOptions viewer_sources(const ViewerOptions& options);

// The endpoints as connected, in order (for the model and the screen).
std::vector<std::string> endpoints_of(const recording::Sources& sources);

}  // namespace tactile::live
