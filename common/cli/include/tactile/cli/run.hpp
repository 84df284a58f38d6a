#pragma once

// The exit status of every program, in one place (docs/architecture.md#rule-7,
// docs/tools.md#exit-status): `--help` prints the usage on standard output and exits 0; a usage
// error (what CLI11 refuses, or a cli::UsageError the program throws after parsing) exits 2 with
// "PROGRAM: message (try --help)" on standard error; any other exception exits 1 with
// "PROGRAM: message". PROGRAM is util::program_name(): a main calls util::set_program_name first.
//
//   int main(int argc, char** argv) {
//     tactile::util::set_program_name("tactile_plot");
//     Options opt;
//     CLI::App app{"..."};
//     app.add_option(...);
//     return tactile::cli::run(app, argc, argv, [&] { return run(opt); });
//   }
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>

#include "tactile/util/log.hpp"
#include "tactile/util/text.hpp"

namespace tactile::cli {

inline constexpr int kFailure = 1;     // a bad file or configuration, or any other failure
inline constexpr int kUsageError = 2;  // an unknown option, a missing value or argument

// A usage error found after parsing (options that exclude each other, a missing endpoint): the
// body throws it and run() reports it as it reports CLI11's own, exit status 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Prints "PROGRAM: message (try --help)" on standard error and returns kUsageError.
inline int report_usage_error(std::string_view message) {
  std::fprintf(stderr, "%s: %s (try --help)\n", util::program_name().c_str(),
               util::one_line(message).c_str());
  return kUsageError;
}

// Prints "PROGRAM: message" on standard error and returns kFailure.
inline int report_failure(std::string_view message) {
  std::fprintf(stderr, "%s: %s\n", util::program_name().c_str(), util::one_line(message).c_str());
  return kFailure;
}

// The --log-level option every program has: debug, info, warn or error (util::parse_log_level);
// another value is a usage error (exit status 2) when the command line is parsed.
inline CLI::Option* add_log_level(CLI::App& app, std::string& level) {
  return app.add_option("--log-level", level, "debug, info, warn or error")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            try {
              util::parse_log_level(text);
              return {};
            } catch (const std::invalid_argument& e) {
              return e.what();
            }
          },
          "LEVEL", "log level"))
      ->capture_default_str();
}

// The command line over a configuration file (hand_node, sensor_node, the rig's scenario): a value
// given replaces the file's and one not given leaves it, and an empty value is never taken for "not
// given". Where empty means something (hand_node's --events: no events publisher), the program
// takes it through override_if_given; elsewhere the option takes non_empty() and "" is a usage
// error (exit status 2) naming the option.
inline CLI::Validator non_empty() {
  return CLI::Validator(
      [](std::string& text) -> std::string { return text.empty() ? "must not be empty" : ""; }, "",
      "non-empty");
}
// `configured` = `given` when `option` was on the command line, even empty.
template <typename T>
void override_if_given(const CLI::Option* option, const T& given, T& configured) {
  if (option->count() > 0) configured = given;
}

// Parses the command line into `app`'s options, then runs `body` (no arguments, returns the exit
// status, passed through). --help (and anything else CLI11 ends with status 0) prints through
// app.exit() and returns 0 without running the body.
template <typename Body>
int run(CLI::App& app, int argc, char** argv, Body&& body) {
  static_assert(std::is_convertible_v<std::invoke_result_t<Body&>, int>,
                "the body returns the exit status");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    return report_usage_error(e.what());
  }
  try {
    return body();
  } catch (const UsageError& e) {
    return report_usage_error(e.what());
  } catch (const std::exception& e) {
    return report_failure(e.what());
  }
}

}  // namespace tactile::cli
