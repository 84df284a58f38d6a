#include "child_process.hpp"

namespace tactile::camera::testing {

namespace {

util::ProcessOptions options(std::vector<std::string> argv) {
  util::ProcessOptions o;
  o.argv = std::move(argv);
  o.stdout_to = util::Redirect::pipe();
  o.stderr_to = util::Redirect::standard_output();
  return o;
}

}  // namespace

ChildProcess::ChildProcess(std::vector<std::string> argv) : process_(options(std::move(argv))) {}

RunResult run_program(std::vector<std::string> argv, std::chrono::milliseconds timeout) {
  ChildProcess child(std::move(argv));
  RunResult result;
  const auto status = child.wait_exit(timeout);
  if (status) {
    result.status = *status;
  } else {
    result.timed_out = true;
    result.status = child.stop(std::chrono::milliseconds(500));
  }
  result.output = child.output();
  return result;
}

}  // namespace tactile::camera::testing
