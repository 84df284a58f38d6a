// A program built on tactile::cli::run for cli_run_test: its body does what the options say.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "tactile/cli/run.hpp"
#include "tactile/util/log.hpp"

int main(int argc, char** argv) {
  tactile::util::set_program_name("cli_run_example");
  int status = 0;
  std::string fail;
  std::string usage;
  std::string print;
  CLI::App app{"cli_run_example: exits with --status, or fails as told."};
  app.add_option("--status", status, "return this status from the body");
  app.add_option("--fail", fail, "throw std::runtime_error with this message");
  app.add_option("--usage", usage, "throw cli::UsageError with this message");
  app.add_option("--print", print, "print this line on standard output in the body");
  app.add_option("--count", status, "a number (for a bad value)")->check(CLI::Range(0, 9));
  return tactile::cli::run(app, argc, argv, [&] {
    if (!print.empty()) std::printf("%s\n", print.c_str());
    if (!fail.empty()) throw std::runtime_error(fail);
    if (!usage.empty()) throw tactile::cli::UsageError(usage);
    return status;
  });
}
