// The latency benchmark's report (latency.json and the tables) of the recorded capture's analysis
// (tests/data/latency/capture.tlog; latency_analysis_test.cpp gives its figures by hand).
#include "latency_report.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "recorded_capture.hpp"

namespace {

namespace fs = std::filesystem;
using tactile::bench::json;
using tactile::bench::RateResult;
using tactile::bench::Settings;

RateResult rate_result() {
  RateResult rr;
  rr.pipe = tactile::bench::testing::recorded_analysis();
  return rr;
}

Settings one_rate() {
  Settings s;
  s.rates = {100};
  s.rois = {"auto"};
  s.skip_transport = true;
  return s;
}

std::string tables(const std::vector<RateResult>& rs, const Settings& s) {
  ::testing::internal::CaptureStdout();
  tactile::bench::print_tables(rs, s);
  return ::testing::internal::GetCapturedStdout();
}

TEST(LatencyReport, TheStagesTableGivesEachStagesP50AndP99) {
  const std::string out = tables({rate_result()}, one_rate());
  EXPECT_NE(out.find("| 100 | 1.240 / 1.500 | 1.500 / 1.500 | 0.300 / 0.300 | 0.200 / 0.200 | "
                     "0.100 / 0.100 | 0.040 / 0.040 | 1.940 / 1.940 | 1.940 / 1.940 | "
                     "1.940 / 1.940 | 18 (1) |\n"),
            std::string::npos)
      << out;
}

TEST(LatencyReport, TheDecisionsTableCountsEveryWholeFrame) {
  const std::string out = tables({rate_result()}, one_rate());
  EXPECT_NE(out.find("| 100 | 36 | 2 | 1.930 / 1.930 / 1.930 | 0.030 / 0.480 |"), std::string::npos)
      << out;
}

TEST(LatencyReport, RegionsAndRunsNameTheirRows) {
  Settings s = one_rate();
  s.rois = {"auto", "full"};
  s.runs = 2;
  RateResult a = rate_result();
  RateResult b = a;
  b.roi = "full";
  b.run = 2;
  const std::string out = tables({a, b}, s);
  EXPECT_NE(out.find("| 100, roi auto #1 |"), std::string::npos) << out;
  EXPECT_NE(out.find("| 100, roi full #2 |"), std::string::npos) << out;
}

TEST(LatencyReport, TheJsonHoldsTheStagesAndNothingForATransportNotRun) {
  const json j = tactile::bench::result_json(rate_result());
  ASSERT_TRUE(j.is_object());
  const std::string text = j.dump();
  EXPECT_NE(text.find("\"p50_ms\":1.94"), std::string::npos) << text;
  EXPECT_TRUE(std::isnan(tactile::bench::transport_alone_p50(rate_result())));
}

TEST(LatencyReport, LinkRatesInTcsForm) {
  EXPECT_EQ(tactile::bench::rate_bps("1gbit"), 1e9);
  EXPECT_EQ(tactile::bench::rate_bps("500mbit"), 500e6);
  EXPECT_EQ(tactile::bench::rate_bps("100kbit"), 100e3);
  EXPECT_TRUE(std::isnan(tactile::bench::rate_bps("1 gbit")));
  EXPECT_TRUE(std::isnan(tactile::bench::rate_bps("0mbit")));
}

TEST(LatencyReport, AFramesGvspPacketsAtThePacketSize) {
  // 1500-byte packets carry 1464 image bytes; a leader and a trailer of 84 bytes each.
  EXPECT_EQ(tactile::bench::gvsp_frame_packets(3000, 1500),
            (std::vector<std::size_t>{84, 1500, 1500, 108, 84}));
}

// A real run's capture (tests/data/latency/run-100fps.tlog, kept by the benchmark) gives, analysed
// again, every capture-derived figure its run reported in latency.json (run-100fps.json).
TEST(LatencyReport, ARealRunsCaptureGivesTheFiguresItsRunReported) {
  const fs::path dir = fs::path(TACTILE_TEST_DATA) / "latency";
  const json expected = json::parse(std::ifstream(dir / "run-100fps.json"));
  tactile::bench::Window w;
  w.begin_ns = expected.at("window_begin_ns").get<std::int64_t>();
  w.end_ns = expected.at("window_end_ns").get<std::int64_t>();
  RateResult rr;
  rr.pipe.fps = expected.at("fps").get<double>();
  tactile::bench::analyse_capture(tactile::bench::read_capture(dir / "run-100fps.tlog"), w,
                                  rr.pipe.fps, rr.pipe);
  const json j = tactile::bench::result_json(rr);
  ASSERT_GT(expected.at("figures").size(), 10U);
  for (const auto& [key, figure] : expected.at("figures").items())
    EXPECT_EQ(j.at(key), figure) << key;
}

}  // namespace
