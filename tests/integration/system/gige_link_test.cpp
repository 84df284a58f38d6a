// scripts/bench-gige-link as a user runs it, as root: two of Aravis's own fake GigE Vision
// cameras behind one veth pair shaped to 1 Gbit/s by tc tbf, sensor_node in another namespace,
// whole frames and the region of interest (issue "Honest GigE"). Whole frames of both cameras at
// 200 fps need 103 % of the link: the shaping holds them under the link's rate; the region needs
// 49 % and arrives whole.
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "process.hpp"

namespace tactile {
namespace {

using namespace std::chrono_literals;
using testing::TempDir;

const std::filesystem::path kSource = TACTILE_SOURCE_DIR;

TEST(GigeLink, TheRegionOfInterestCarriesTwoCamerasThatWholeFramesOverload) {
  ASSERT_EQ(::geteuid(), 0U) << "network namespaces and tc need root (CI runs as root)";
  TempDir dir;
  const auto r = testing::run({"bash", (kSource / "scripts/bench-gige-link").string(), "--build",
                               TACTILE_BUILD_DIR, "--out", (dir / "out").string(), "--topologies",
                               "shared", "--rois", "full,auto", "--seconds", "3"},
                              180s);
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("| shared-auto | left | 382x382 at (129, 49) | 1.23 | 49 % |"),
            std::string::npos)
      << r.out;
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "gige-link.md"));
  std::ifstream in(dir / "out" / "gige-link.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  for (const char* cam : {"left", "right"}) {
    const auto& full = j["runs"]["shared-full"][cam];
    const auto& part = j["runs"]["shared-auto"][cam];
    SCOPED_TRACE(cam);
    EXPECT_EQ(full["region"], nlohmann::json::array({0, 0, 640, 480}));
    EXPECT_NEAR(full["wire_time_ms"].get<double>(), 2.58, 0.01);
    EXPECT_GT(full["link_load_needed"].get<double>() * 2, 1.0) << "two whole frames overload it";
    // The link cannot carry more than its rate: two cameras of whole frames get at most
    // 1 / (2 x wire time) frames per second each (2 % for the measured window's ends).
    EXPECT_LE(full["fps"].get<double>(), 1.02 / (2 * full["wire_time_ms"].get<double>() * 1e-3));
    EXPECT_LT(part["link_load_needed"].get<double>() * 2, 0.55);
    // Whole but for a host's pause, as at MTU 9000 below: a full CI run on a machine slowed by
    // its host (the paper's slip rule at 1.6 times its usual time that hour) had one region frame
    // of one camera incomplete in the 3 s, where every run before had none.
    const int frames = part["frames"].get<int>();
    EXPECT_GT(frames, 100);
    EXPECT_LE(part["incomplete"].get<int>() * 100, frames) << "more than 1 % incomplete";
    EXPECT_GT(part["fps"].get<double>(), full["fps"].get<double>());
    EXPECT_LT(part["camera_to_received_ms"]["p50"].get<double>(),
              full["camera_to_received_ms"]["p50"].get<double>());
  }
}

// The links at MTU 9000 with 8192-byte GVSP packets (docs/deployment.md): the bucket's burst of
// two jumbo packets carries the region (with a burst of one, every frame had arrived
// incomplete), its wire time counted at that packet size. Not every frame: one CI run of this
// test had 2 of about 600 incomplete on one camera, which eight 10 s runs by hand and four of
// this test did not show (docs/benchmarks.md, "GigE links at line rate": not understood yet).
TEST(GigeLink, AtMtu9000JumboPacketsCarryTheRegion) {
  ASSERT_EQ(::geteuid(), 0U) << "network namespaces and tc need root (CI runs as root)";
  TempDir dir;
  const auto r = testing::run({"bash", (kSource / "scripts/bench-gige-link").string(), "--build",
                               TACTILE_BUILD_DIR, "--out", (dir / "out").string(), "--topologies",
                               "separate", "--rois", "auto", "--seconds", "3", "--mtu", "9000"},
                              120s);
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("MTU 9000, 8192-byte GVSP packets"), std::string::npos) << r.out;
  std::ifstream in(dir / "out" / "gige-link.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["mtu"], 9000);
  EXPECT_EQ(j["packet_size"], 8192);
  for (const char* cam : {"left", "right"}) {
    const auto& part = j["runs"]["separate-auto"][cam];
    SCOPED_TRACE(cam);
    // 145,924 image bytes in 18 packets of 8156, 74 bytes of headers each, leader and trailer.
    EXPECT_NEAR(part["wire_time_ms"].get<double>(), 1.180, 0.005);
    const int frames = part["frames"].get<int>();
    EXPECT_GT(frames, 300);
    EXPECT_LE(part["incomplete"].get<int>() * 100, frames) << "more than 1 % incomplete";
  }
}

}  // namespace
}  // namespace tactile
