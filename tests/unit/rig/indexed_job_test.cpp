// The sweep's Kubernetes Indexed Job (docker/k8s/sweep-indexed-job.yaml; docs/docker.md): no
// cluster runs it here, so its arithmetic is checked from the file itself. Pod i's command, run by
// /bin/sh with JOB_COMPLETION_INDEX=i and a `rig` that prints its arguments, must be the
// `rig --sweep --shard i+1/N` command, and the N pods together must run every scenario once.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "process.hpp"
#include "tactile/rig/sweep.hpp"

namespace {

namespace fs = std::filesystem;
namespace sweep = tactile::rig::sweep;

const fs::path kSource = TACTILE_SOURCE_DIR;

// The arguments pod `index`'s command passes to rig, one per element.
std::vector<std::string> pod_arguments(const std::string& script,
                                       const std::map<std::string, std::string>& env, int index,
                                       const fs::path& dir) {
  const fs::path bin = dir / "bin";
  fs::create_directories(bin);
  {
    std::ofstream rig(bin / "rig");
    rig << "#!/bin/sh\nfor a in \"$@\"; do printf '%s\\n' \"$a\"; done\n";
  }
  fs::permissions(bin / "rig", fs::perms::owner_all);
  std::vector<std::string> vars{"PATH=" + bin.string() + ":/usr/bin:/bin",
                                "JOB_COMPLETION_INDEX=" + std::to_string(index)};
  for (const auto& [name, value] : env)
    vars.push_back(name + "=" + value);
  const tactile::testing::ProcessResult r =
      tactile::testing::Process({"/bin/sh", "-c", script}, vars).wait(std::chrono::seconds(10));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  std::vector<std::string> args;
  std::istringstream lines(r.out);
  for (std::string line; std::getline(lines, line);)
    args.push_back(line);
  return args;
}

TEST(IndexedJob, PodIRunsShardIPlusOneOfNAndTogetherEveryScenarioOnce) {
  const YAML::Node job = YAML::LoadFile((kSource / "docker/k8s/sweep-indexed-job.yaml").string());
  ASSERT_EQ(job["kind"].as<std::string>(), "Job");
  ASSERT_EQ(job["spec"]["completionMode"].as<std::string>(), "Indexed");
  const int completions = job["spec"]["completions"].as<int>();
  const YAML::Node container = job["spec"]["template"]["spec"]["containers"][0];

  // The compose rig's image: every service's, from `x-service` (yaml-cpp does not apply `<<:`).
  const YAML::Node compose = YAML::LoadFile((kSource / "docker/compose.yaml").string());
  EXPECT_EQ(container["image"].as<std::string>(), compose["x-service"]["image"].as<std::string>());

  std::map<std::string, std::string> env;
  for (const YAML::Node& e : container["env"])
    env[e["name"].as<std::string>()] = e["value"].as<std::string>();
  const auto command = container["command"].as<std::vector<std::string>>();
  ASSERT_EQ(command.size(), 3U);
  ASSERT_EQ(command[0], "/bin/sh");
  ASSERT_EQ(command[1], "-c");
  const std::uint64_t scenarios = std::stoull(env.at("SCENARIOS"));

  tactile::testing::TempDir dir;
  std::multiset<std::uint64_t> ran;
  std::set<std::string> outs;
  for (int i = 0; i < completions; ++i) {
    const std::vector<std::string> args = pod_arguments(command[2], env, i, dir.path());
    const std::string shard = std::to_string(i + 1) + "/" + std::to_string(completions);
    const std::vector<std::string> expected{"--sweep", env.at("SCENARIOS"),
                                            "--seed",  env.at("SEED"),
                                            "--shard", shard,
                                            "--out",   "/results/shard-" + std::to_string(i + 1),
                                            "--resume"};
    ASSERT_EQ(args, expected) << "pod " << i;
    const sweep::Shard k = sweep::parse_shard(args[5]);
    for (const std::uint64_t s : sweep::shard_indices(scenarios, k.shard, k.shards))
      ran.insert(s);
    outs.insert(args[7]);
  }
  EXPECT_EQ(outs.size(), static_cast<std::size_t>(completions)) << "one folder per pod";
  ASSERT_EQ(ran.size(), scenarios);
  std::uint64_t next = 0;
  for (const std::uint64_t s : ran)
    EXPECT_EQ(s, next++) << "every scenario once";
}

}  // namespace
