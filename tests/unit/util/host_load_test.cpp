#include "tactile/util/host_load.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace {

using tactile::util::CpuTimes;
using tactile::util::explains_latency;
using tactile::util::latency_explanation;
using tactile::util::MachineLoad;
using tactile::util::parse_load_average_1m;
using tactile::util::parse_proc_stat;
using tactile::util::steal_percent;

// Two readings of a 2-CPU virtual machine's /proc/stat one second apart (guest columns last).
const std::string kBefore =
    "cpu  1000 10 500 8000 100 0 20 70 0 0\n"
    "cpu0 500 5 250 4000 50 0 10 35 0 0\n"
    "cpu1 500 5 250 4000 50 0 10 35 0 0\n"
    "intr 123456 0 0\n"
    "ctxt 987654\n";
const std::string kAfter =
    "cpu  1080 10 540 8040 100 0 20 110 5 0\n"
    "cpu0 540 5 270 4020 50 0 10 55 5 0\n"
    "cpu1 540 5 270 4020 50 0 10 55 0 0\n"
    "intr 123999 0 0\n";

TEST(ProcStat, ReadsTheAggregateLineAndCountsTheCpus) {
  const auto t = parse_proc_stat(kBefore);
  ASSERT_TRUE(t.has_value());
  EXPECT_EQ(t->steal, 70);
  EXPECT_EQ(t->total, 1000 + 10 + 500 + 8000 + 100 + 0 + 20 + 70);  // guest not counted twice
  EXPECT_EQ(t->cores, 2);
}

TEST(ProcStat, StealShareIsStealOverAllTimeBetweenTwoReadings) {
  const auto before = parse_proc_stat(kBefore);
  const auto after = parse_proc_stat(kAfter);
  ASSERT_TRUE(before && after);
  // 80 user + 40 system + 40 idle + 40 steal = 200 ticks, 40 of them stolen.
  EXPECT_DOUBLE_EQ(steal_percent(*before, *after), 20.0);
  EXPECT_TRUE(std::isnan(steal_percent(*before, *before)));  // no time passed
}

TEST(ProcStat, RefusesTextWithoutAWholeCpuLine) {
  EXPECT_FALSE(parse_proc_stat("").has_value());
  EXPECT_FALSE(parse_proc_stat("intr 1 2 3\n").has_value());
  EXPECT_FALSE(parse_proc_stat("cpu  1 2 3 4\n").has_value());  // an old kernel: no steal
}

TEST(LoadAverage, IsTheFirstNumberOfTheLine) {
  EXPECT_EQ(parse_load_average_1m("2.57 1.20 0.80 3/412 12345"), 2.57);
  EXPECT_FALSE(parse_load_average_1m("").has_value());
  EXPECT_FALSE(parse_load_average_1m("x 1 2").has_value());
}

// The thresholds: steal above 5 %, or a load average above the number of cores.
TEST(LatencyExplanation, OnlyWhenStealOrLoadIsHighEnough) {
  struct Case {
    MachineLoad m;
    bool explains;
    const char* names;  // a figure the sentence must name
  };
  const Case cases[] = {
      {{0.4, 1.10, 2}, false, ""},     {{5.0, 2.00, 2}, false, ""},  // at the thresholds: not above
      {{7.5, 0.50, 2}, true, "7.5 %"}, {{0.0, 3.25, 2}, true, "3.25 tasks"},
      {{12.0, 4.00, 2}, true, "and"},  {{std::nan(""), std::nan(""), 0}, false, ""},  // not known
  };
  for (const Case& c : cases) {
    const std::string why = latency_explanation(c.m);
    EXPECT_EQ(explains_latency(c.m), c.explains) << c.m.steal_pct << " " << c.m.load_average_1m;
    EXPECT_EQ(!why.empty(), c.explains) << why;
    if (c.explains) {
      EXPECT_NE(why.find(c.names), std::string::npos) << why;
      EXPECT_NE(why.find("explain a high latency"), std::string::npos) << why;
    }
  }
  EXPECT_NE(latency_explanation({7.5, 0.5, 2}).find("steal above 5 %"), std::string::npos);
  EXPECT_NE(latency_explanation({0, 3.25, 2}).find("load above the number of cores"),
            std::string::npos);
}

}  // namespace
