// One exit-status convention for every program a user runs (docs/tools.md, "Exit status";
// docs/architecture.md, rule 7): --help exits 0 with the usage on standard output, citing only
// files that exist in the repository; a bad option exits 2 with a message on standard error.
// The list of programs comes from the build (every executable target outside tests/), plus the
// scripts and the Python reader, so a new program is checked without editing this file.
// Also: a misspelt key in each program's configuration fails its start, naming the closest key.
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "process.hpp"

namespace {

namespace fs = std::filesystem;
using tactile::testing::Process;
using tactile::testing::ProcessResult;

const fs::path kSource = TACTILE_SOURCE_DIR;

struct Program {
  std::string name;
  std::vector<std::string> argv;  // how to start it, before the options
  std::vector<std::string> env;   // extra environment
  std::vector<std::string> bad;   // a usage error
};

// gtest names the parameter in test names and failures by its name, not its bytes.
void PrintTo(const Program& p, std::ostream* os) {
  *os << p.name;
}

std::vector<Program> programs() {
  std::vector<Program> out;
  std::ifstream in(TACTILE_PROGRAMS_LIST);
  for (std::string line; std::getline(in, line);) {
    const auto eq = line.find('=');
    if (eq == std::string::npos) continue;
    out.push_back({line.substr(0, eq), {line.substr(eq + 1)}, {}, {"--no-such-option"}});
  }
  std::vector<fs::path> scripts;
  for (const auto& e : fs::directory_iterator(kSource / "scripts")) {
    if (e.is_regular_file()) scripts.push_back(e.path());
  }
  std::sort(scripts.begin(), scripts.end());
  for (const fs::path& s : scripts) {
    Program p{s.filename().string(), {"bash", s.string()}, {}, {"--no-such-option"}};
    // bench-latency hands every option it does not know to the benchmark, after a build: its own
    // usage error is --build without a folder (the benchmark's bad option is checked above).
    if (p.name == "bench-latency") p.bad = {"--build"};
    out.push_back(std::move(p));
  }
  out.push_back({"python3_m_tactile_reader",
                 {TACTILE_PYTHON3, "-m", "tactile_reader"},
                 {std::string("PYTHONPATH=") + TACTILE_PYTHON_PATH},
                 {"--no-such-option"}});
  return out;
}

ProcessResult run_with(const Program& p, const std::vector<std::string>& args) {
  std::vector<std::string> argv = p.argv;
  argv.insert(argv.end(), args.begin(), args.end());
  Process proc(argv, p.env);
  return proc.wait(std::chrono::seconds(30));
}

// Words of `text` that look like paths in this repository ("docs/rig.md#anchor",
// "rig/scenarios/default.yaml"): a top-level folder of the repository followed by a slash, not
// part of a longer path ("BUILD/tests/..." is a build folder) or of a URL.
std::vector<std::string> repo_paths(const std::string& text) {
  std::vector<std::string> tops;
  for (const auto& e : fs::directory_iterator(kSource)) {
    if (e.is_directory() && e.path().filename().string()[0] != '.')
      tops.push_back(e.path().filename().string() + "/");
  }
  // The build folder is not part of the repository, whatever its name.
  std::erase_if(tops, [](const std::string& t) { return t.starts_with("build"); });
  const auto path_char = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.' ||
           c == '/';
  };
  std::vector<std::string> out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (i > 0 && (path_char(text[i - 1]) || text[i - 1] == ':')) continue;
    for (const std::string& t : tops) {
      if (text.compare(i, t.size(), t) != 0) continue;
      std::size_t j = i;
      while (j < text.size() && path_char(text[j]))
        ++j;
      std::string p = text.substr(i, j - i);
      while (!p.empty() && (p.back() == '.' || p.back() == '/'))
        p.pop_back();  // a full stop ends the sentence, a slash the folder
      out.push_back(p);
    }
  }
  return out;
}

// The folders .gitignore names ("/docker/out/"): where programs write, so a help text may name
// them before they exist.
std::vector<std::string> ignored_outputs() {
  std::vector<std::string> out;
  std::ifstream in(kSource / ".gitignore");
  for (std::string line; std::getline(in, line);) {
    if (line.size() > 2 && line.front() == '/' && line.back() == '/' &&
        line.find('*') == std::string::npos)
      out.push_back(line.substr(1));
  }
  return out;
}

bool cites_existing(const std::string& path) {
  if (fs::exists(kSource / path)) return true;
  for (const std::string& ignored : ignored_outputs()) {
    if ((path + "/").starts_with(ignored)) return true;
  }
  return false;
}

class EveryProgram : public ::testing::TestWithParam<Program> {};

TEST_P(EveryProgram, HelpExitsZeroWithUsageOnStandardOutputCitingFilesThatExist) {
  const Program& p = GetParam();
  const ProcessResult r = run_with(p, {"--help"});
  ASSERT_FALSE(r.timed_out);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find_first_not_of(" \n"), std::string::npos) << "no usage on standard output";
  // Usage, not code: a script's help is its comment, not the lines after it.
  EXPECT_EQ(r.out.find("set -e"), std::string::npos) << r.out;
  for (const std::string& path : repo_paths(r.out))
    EXPECT_TRUE(cites_existing(path))
        << p.name << " --help cites '" << path << "', which is not in the repository";
}

TEST_P(EveryProgram, ABadOptionExitsTwoWithAMessageOnStandardError) {
  const Program& p = GetParam();
  const ProcessResult r = run_with(p, p.bad);
  ASSERT_FALSE(r.timed_out);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  // The message may name a missing required option first: CLI11 checks requirements before
  // unexpected arguments.
  EXPECT_NE(r.err.find_first_not_of(" \n"), std::string::npos) << "nothing on standard error";
  EXPECT_TRUE(r.out.empty()) << r.out;
}

std::string test_name(const ::testing::TestParamInfo<Program>& info) {
  std::string n = info.param.name;
  for (char& c : n) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  return n;
}

INSTANTIATE_TEST_SUITE_P(Cli, EveryProgram, ::testing::ValuesIn(programs()), test_name);

TEST_P(EveryProgram, ABadLogLevelIsAUsageError) {
  // Every program whose help offers --log-level refuses a level it does not know while parsing
  // (tactile::cli::add_log_level): exit 2, as for any other bad value; the others refuse the
  // option itself, exit 2 too.
  const Program& p = GetParam();
  const ProcessResult help = run_with(p, {"--help"});
  const ProcessResult r = run_with(p, {"--log-level", "loud"});
  ASSERT_FALSE(r.timed_out);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  if (help.out.find("--log-level") != std::string::npos) {
    EXPECT_NE(r.err.find("log level must be debug, info, warn or error, is 'loud'"),
              std::string::npos)
        << r.err;
  }
}

TEST(CliList, HoldsTheProgramsTheScriptsAndThePythonReader) {
  std::vector<std::string> names;
  for (const Program& p : programs())
    names.push_back(p.name);
  for (const char* must :
       {"sensor_node", "hand_node", "rig", "tactile_extract", "tactile_live", "tactile_record",
        "run-system", "install-deps", "python3_m_tactile_reader"})
    EXPECT_NE(std::find(names.begin(), names.end(), must), names.end()) << must;
}

TEST(RepoPaths, FindsTheRepositorysPathsButNotBuildFoldersOrUrls) {
  const std::vector<std::string> found = repo_paths(
      "see docs/rig.md#scenario-files and rig/scenarios/. Writes BUILD/tests/x, "
      "https://example.org/docs/x.md and (docs/no-such-page.md)");
  EXPECT_EQ(found,
            (std::vector<std::string>{"docs/rig.md", "rig/scenarios", "docs/no-such-page.md"}));
}

// A misspelt key fails the start: configuration error status 1, one line naming the file, the
// line, the key and the closest known key.
class MisspeltKey : public ::testing::Test {
 protected:
  ProcessResult start(std::vector<std::string> argv) {
    Process proc(std::move(argv));
    return proc.wait(std::chrono::seconds(20));
  }
  void write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
  }
  tactile::testing::TempDir dir_;
};

TEST_F(MisspeltKey, FailsSensorNodesStart) {
  fs::copy_file(kSource / "docker" / "config" / "left.yaml", dir_ / "left.yaml");
  write("sensor_node.yaml",
        "format: tactile-sensor/1\n"
        "publish: tcp://127.0.0.1:0\n"
        "cameras:\n"
        "  - sensor_id: left\n"
        "    camera: 127.0.0.2\n"
        "    calibration: left.yaml\n"
        "    fsp: 100\n");
  const fs::path cfg = dir_ / "sensor_node.yaml";
  const ProcessResult r = start({TACTILE_SENSOR_NODE_PATH, "--config", cfg.string()});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(
      r.err.find(cfg.string() + ":7: unknown key 'fsp' in 'cameras[0]' (did you mean 'fps'?)"),
      std::string::npos)
      << r.err;
}

TEST_F(MisspeltKey, FailsHandNodesStart) {
  for (const char* f : {"left.yaml", "right.yaml"})
    fs::copy_file(kSource / "docker" / "config" / f, dir_ / f);
  write("hand_node.yaml",
        "format: tactile-hand/1\n"
        "fingertips:\n"
        "  - {sensor_id: left, calibration: left.yaml}\n"
        "  - {sensor_id: right, calibration: right.yaml}\n"
        "controller:\n"
        "  dr_mm: 0.004\n"
        "  f2_nn: 1.5\n");
  const fs::path cfg = dir_ / "hand_node.yaml";
  const ProcessResult r = start({TACTILE_HAND_NODE_PATH, "--config", cfg.string()});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(
      r.err.find(cfg.string() + ":7: unknown key 'f2_nn' in 'controller' (did you mean 'f2_n'?)"),
      std::string::npos)
      << r.err;
}

TEST_F(MisspeltKey, FailsTheRigsStart) {
  std::ifstream in(kSource / "tests" / "data" / "scenarios" / "quick.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  const auto at = s.find("\ncap:");
  ASSERT_NE(at, std::string::npos);
  s.insert(at + 1, "sede: 3\n");
  const auto line = 1 + std::count(s.begin(), s.begin() + static_cast<long>(at + 1), '\n');
  write("scenario.yaml", s);
  const fs::path scenario = dir_ / "scenario.yaml";
  const ProcessResult r = start({TACTILE_RIG_PATH, "--lockstep", "--scenario", scenario.string(),
                                 "--report", (dir_ / "report.json").string()});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find(scenario.string() + ":" + std::to_string(line) +
                       ": unknown key 'sede' (did you mean 'seed'?)"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "report.json"));
}

// A run names its controller: the rig in lockstep says which slip detector (here the one
// --slip-detector gives) and which grip it runs in its first lines and in its report.
TEST_F(MisspeltKey, RigInLockstepNamesItsSlipDetectorAndGrip) {
  std::ifstream in(kSource / "tests" / "data" / "scenarios" / "quick.yaml");
  std::stringstream text;
  text << in.rdbuf();
  write("scenario.yaml", text.str() + "sim: {max_time_s: 0.2}\n");
  const fs::path report = dir_ / "report.json";
  // A run that ends well and names its controller in its first line.
  const auto names = [&](const std::vector<std::string>& options, const std::string& controller) {
    std::vector<std::string> argv{TACTILE_RIG_PATH, "--lockstep",
                                  "--scenario",     (dir_ / "scenario.yaml").string(),
                                  "--report",       report.string()};
    argv.insert(argv.end(), options.begin(), options.end());
    const ProcessResult r = start(argv);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("scenario.yaml (lockstep): " + controller + "\n"), std::string::npos)
        << r.err;
  };
  names({"--slip-detector", "field"}, "slip detector: field, grip: paper");
  std::ifstream json(report);
  std::stringstream written;
  written << json.rdbuf();
  // The report's key, pretty-printed as the report writes it.
  EXPECT_NE(written.str().find("\"controller\": {\n    \"slip_detector\": \"field\",\n    "
                               "\"grip\": \"paper\"\n  },\n"),
            std::string::npos)
      << written.str();
  // --grip overrides the scenario's grip; a grip it does not know is a usage error.
  names({"--grip", "margin"}, "slip detector: learned, grip: margin");
  const ProcessResult firm = start({TACTILE_RIG_PATH, "--lockstep", "--scenario",
                                    (dir_ / "scenario.yaml").string(), "--grip", "firm"});
  EXPECT_EQ(firm.exit_code, 2) << firm.err;
  EXPECT_NE(firm.err.find("--grip must be paper or margin; got 'firm'"), std::string::npos)
      << firm.err;
}

// An empty value on the command line is never taken for "not given": it clears the file's value
// where empty means something (hand_node's --events: no events publisher) and is a usage error
// naming the option elsewhere (docs/tools.md, "Exit status").
TEST_F(MisspeltKey, AnEmptyEventsEndpointClearsHandNodesFile) {
  for (const char* f : {"left.yaml", "right.yaml"})
    fs::copy_file(kSource / "docker" / "config" / f, dir_ / f);
  const std::string events = "ipc://" + (dir_ / "events").string();
  write("hand_node.yaml",
        "format: tactile-hand/1\n"
        "fingertips:\n"
        "  - {sensor_id: left, calibration: left.yaml}\n"
        "  - {sensor_id: right, calibration: right.yaml}\n"
        "events: " +
            events + "\n");
  Process hand({TACTILE_HAND_NODE_PATH, "--config", (dir_ / "hand_node.yaml").string(),
                "--subscribe", "ipc://" + (dir_ / "sensors").string(), "--arm",
                "ipc://" + (dir_ / "arm").string(), "--events", ""});
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (hand.err_so_far().find("subscribing to") == std::string::npos && hand.running() &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  hand.signal(SIGTERM);
  const ProcessResult r = hand.wait(std::chrono::seconds(20));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("subscribing to"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("events on"), std::string::npos) << r.err;
}

TEST_F(MisspeltKey, AnEmptyValueThatMeansNothingIsAUsageError) {
  const std::string scenario = (kSource / "tests" / "data" / "scenarios" / "quick.yaml").string();
  const std::string calibration = (kSource / "docker" / "config" / "left.yaml").string();
  const std::string hand = (kSource / "docker" / "config" / "hand_node.yaml").string();
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases{
      {"--arm", {TACTILE_HAND_NODE_PATH, "--config", hand, "--arm", ""}},
      {"--subscribe", {TACTILE_HAND_NODE_PATH, "--config", hand, "--subscribe", ""}},
      {"--camera", {TACTILE_SENSOR_NODE_PATH, "--camera", "", "--calibration", calibration}},
      {"--publish",
       {TACTILE_SENSOR_NODE_PATH, "--camera", "127.0.0.201", "--calibration", calibration,
        "--publish", ""}},
      {"--slip-detector",
       {TACTILE_RIG_PATH, "--lockstep", "--scenario", scenario, "--slip-detector", ""}},
      {"--grip", {TACTILE_RIG_PATH, "--lockstep", "--scenario", scenario, "--grip", ""}},
      {"--cameras", {TACTILE_RIG_PATH, "--scenario", scenario, "--cameras", ""}},
  };
  for (const auto& [option, argv] : cases) {
    const ProcessResult r = start(argv);
    EXPECT_EQ(r.exit_code, 2) << option << ": " << r.err;
    EXPECT_NE(r.err.find(option), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("must not be empty"), std::string::npos) << r.err;
  }
}

}  // namespace
