// tactile::cli::run, the exit status of every program (docs/architecture.md#rule-7): a real
// program built on it, run as a process, its standard output and error read apart.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "process.hpp"

namespace {

using tactile::testing::ProcessResult;

ProcessResult example(std::vector<std::string> args) {
  args.insert(args.begin(), TACTILE_CLI_RUN_EXAMPLE);
  return tactile::testing::run(std::move(args));
}

TEST(CliRun, HelpExitsZeroWithTheUsageOnStandardOutput) {
  for (const char* help : {"--help", "-h"}) {
    const ProcessResult r = example({help, "--fail", "never run"});
    EXPECT_EQ(r.exit_code, 0) << help;
    EXPECT_NE(r.out.find("cli_run_example: exits with --status"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("--status"), std::string::npos) << r.out;
    EXPECT_EQ(r.err, "") << help;  // and the body did not run
  }
}

TEST(CliRun, UnknownOptionExitsTwoWithTheMessageOnStandardError) {
  const ProcessResult r = example({"--no-such-option", "--print", "body ran"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.out, "");  // nothing printed, the body did not run
  EXPECT_EQ(r.err.rfind("cli_run_example: ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("--no-such-option"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(" (try --help)\n"), std::string::npos) << r.err;
}

TEST(CliRun, BadValueAndMissingValueExitTwo) {
  for (const std::vector<std::string>& args :
       std::vector<std::vector<std::string>>{{"--count", "12"}, {"--status"}}) {
    const ProcessResult r = example(args);
    EXPECT_EQ(r.exit_code, 2) << args.front();
    EXPECT_EQ(r.err.rfind("cli_run_example: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find("(try --help)"), std::string::npos) << r.err;
  }
}

TEST(CliRun, UsageErrorFromTheBodyExitsTwo) {
  const ProcessResult r = example({"--usage", "give at least one endpoint"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "cli_run_example: give at least one endpoint (try --help)\n");
}

TEST(CliRun, BodyThrowingExitsOneWithTheMessageOnOneLine) {
  const ProcessResult r = example({"--print", "started", "--fail", "run.tlog: truncated\nat 12"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.out, "started\n");
  EXPECT_EQ(r.err, "cli_run_example: run.tlog: truncated\\x0aat 12\n");
}

TEST(CliRun, BodysStatusIsPassedThrough) {
  for (const int status : {0, 1, 3, 7}) {
    const ProcessResult r = example({"--status", std::to_string(status)});
    EXPECT_EQ(r.exit_code, status);
    EXPECT_EQ(r.err, "");
  }
}

}  // namespace
