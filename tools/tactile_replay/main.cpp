// tactile_replay: plays a tactile log back on a PUB endpoint, or measures its recorded raw frames
// again and checks the TactileFrames bit for bit (docs/recording.md, docs/tools.md).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "player.hpp"
#include "remeasure.hpp"
#include "tactile/cli/run.hpp"
#include "tactile/config/calibration_file.hpp"
#include "tactile/recording/log_reader.hpp"
#include "tactile/recording/read_progress.hpp"
#include "tactile/util/clock.hpp"
#include "tactile/util/log.hpp"
#include "tactile/util/stop.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/security.hpp"

namespace {

using tactile::recording::LogReader;
using tactile::recording::ReadStatus;

struct Options {
  std::string log;
  std::string publish = "tcp://*:5555";
  double speed = 1.0;
  bool fast = false;
  std::vector<std::string> topics;
  int wait_subscriptions = 0;
  double wait_timeout_s = 10.0;
  std::string secret_key;
  double from_s = 0;
  double to_s = 0;
  std::vector<std::string> remeasure;
  std::string estimator;
  bool info = false;
  std::string log_level = "info";
};

bool wanted(const std::vector<std::string>& topics, const std::string& topic) {
  if (topics.empty()) return true;
  for (const auto& t : topics) {
    if (topic.starts_with(t)) return true;
  }
  return false;
}

// Ends a read: a truncated tail is a warning (a recorder that was killed), damage is an error.
int report_end(ReadStatus s, const LogReader& r) {
  if (s == ReadStatus::kTruncated) {
    tactile::util::log_warn("{}", r.problem());
    return 0;
  }
  if (s == ReadStatus::kCorrupt) {
    std::fprintf(stderr, "tactile_replay: %s\n", r.problem().c_str());
    return 1;
  }
  return 0;
}

int info(const Options& opt) {
  LogReader r(opt.log);
  const auto& h = r.header();
  std::printf("%s: %s written by %s on %s\n", opt.log.c_str(), h.format().c_str(),
              h.writer().c_str(), h.host().empty() ? "?" : h.host().c_str());
  for (const auto& s : h.sources()) {
    std::string topics;
    for (const auto& t : s.topics())
      topics += (topics.empty() ? "" : " ") + (t.empty() ? std::string("(all)") : t);
    std::printf("  source %s%s: %s\n", s.endpoint().c_str(), s.curve() ? " (CURVE)" : "",
                topics.c_str());
  }
  if (!h.note().empty()) std::printf("  note: %s\n", h.note().c_str());
  std::map<std::string, std::uint64_t> counts;
  std::int64_t first = 0;
  std::int64_t last = 0;
  std::uint64_t n = 0;
  tactile::v1::LogRecord rec;
  tactile::recording::ReadProgress progress(r);
  ReadStatus s;
  while ((s = r.next(rec)) == ReadStatus::kRecord) {
    if (tactile::util::stop_requested()) return tactile::util::interrupted_exit_status();
    if (n == 0) first = rec.receive_time_ns();
    last = rec.receive_time_ns();
    ++counts[rec.topic()];
    ++n;
    progress.tick(n);
  }
  std::printf("  %llu records over %.3f s in %llu zstd frames, %llu bytes\n",
              static_cast<unsigned long long>(n), static_cast<double>(last - first) * 1e-9,
              static_cast<unsigned long long>(r.frames()),
              static_cast<unsigned long long>(r.file_size()));
  for (const auto& [topic, count] : counts)
    std::printf("  %-24s %llu\n", topic.c_str(), static_cast<unsigned long long>(count));
  std::printf("  end: %s%s%s\n", tactile::recording::to_string(s), r.problem().empty() ? "" : ": ",
              r.problem().c_str());
  std::fflush(stdout);
  return s == ReadStatus::kCorrupt ? 1 : 0;
}

int remeasure(const Options& opt) {
  std::vector<tactile::Calibration> cals;
  std::vector<std::string> warnings;
  for (const auto& c : opt.remeasure)
    cals.push_back(tactile::config::load_calibration(c, &warnings));
  for (const auto& w : warnings)
    tactile::util::log_warn("{}", w);
  tactile::replay::RemeasureOptions ro;
  if (!opt.estimator.empty()) {
    ro.estimator = tactile::parse_estimator(opt.estimator);
    if (!ro.estimator) {
      throw std::invalid_argument(std::string("--estimator must be ") + tactile::kEstimatorNames +
                                  ", is '" + opt.estimator + "'");
    }
  }
  tactile::replay::Remeasurer rm(std::move(cals), ro);
  LogReader r(opt.log);
  tactile::v1::LogRecord rec;
  tactile::recording::ReadProgress progress(r);
  ReadStatus s;
  std::uint64_t n = 0;
  while ((s = r.next(rec)) == ReadStatus::kRecord) {
    if (tactile::util::stop_requested()) {
      tactile::util::log_info("stopped after {} records", n);
      return tactile::util::interrupted_exit_status();
    }
    rm.add(rec);
    progress.tick(++n);
  }
  rm.finish();
  int code = report_end(s, r);
  for (const auto& id : rm.uncalibrated())
    tactile::util::log_warn("sensor '{}' is in the log but no calibration was given", id);
  std::uint64_t checked = 0;
  for (const auto& rep : rm.reports()) {
    checked += rep.checked;
    std::printf("%s: %llu frames measured again, %llu identical bit for bit, %llu differ",
                rep.sensor_id.c_str(), static_cast<unsigned long long>(rep.checked),
                static_cast<unsigned long long>(rep.identical),
                static_cast<unsigned long long>(rep.checked - rep.identical));
    if (rep.unchecked > 0)
      std::printf("; %llu measured frames without a raw frame",
                  static_cast<unsigned long long>(rep.unchecked));
    if (rep.no_reference > 0)
      std::printf("; %llu raw frames before any reference",
                  static_cast<unsigned long long>(rep.no_reference));
    if (rep.unmatched_raw > 0)
      std::printf("; %llu raw frames without their TactileFrame",
                  static_cast<unsigned long long>(rep.unmatched_raw));
    std::printf("\n");
    if (!rep.problem.empty()) {
      std::fprintf(stderr, "tactile_replay: %s: %s\n", rep.sensor_id.c_str(), rep.problem.c_str());
      code = 1;
    }
  }
  std::fflush(stdout);
  if (const auto& d = rm.first_difference()) {
    std::fprintf(
        stderr,
        "tactile_replay: first difference: sensor %s, TactileFrame %llu (camera frame %llu): "
        "%s (%llu frames differ)\n",
        d->sensor_id.c_str(), static_cast<unsigned long long>(d->sequence),
        static_cast<unsigned long long>(d->camera_frame_id), d->what.c_str(),
        static_cast<unsigned long long>(rm.differing()));
    return 1;
  }
  if (checked == 0) {
    std::fprintf(stderr,
                 "tactile_replay: %s: no frame could be measured again (record raw frames and the "
                 "reference with tactile_record --raw-frames)\n",
                 opt.log.c_str());
    return 1;
  }
  return code;
}

int play(const Options& opt) {
  if (!opt.fast && !(opt.speed > 0)) throw std::invalid_argument("--speed must be positive");
  if (opt.from_s < 0 || opt.to_s < 0)
    throw std::invalid_argument("--from and --to must not be negative");
  std::optional<tactile::wire::ServerSecurity> security;
  if (!opt.secret_key.empty())
    security = tactile::wire::ServerSecurity{tactile::wire::load_key_pair(opt.secret_key), {}};
  LogReader r(opt.log);
  zmq::context_t ctx;
  tactile::replay::PlayerOptions po;
  po.endpoint = opt.publish;
  po.security = security ? &*security : nullptr;
  po.wait_subscriptions = opt.wait_subscriptions;
  po.wait_timeout = std::chrono::milliseconds(static_cast<std::int64_t>(opt.wait_timeout_s * 1000));
  tactile::replay::Player player(ctx, po);
  tactile::util::log_info("publishing on {}{}", player.endpoint(), security ? " (CURVE)" : "");
  if (opt.wait_subscriptions > 0) {
    if (!player.wait_for_subscribers()) {
      if (tactile::util::stop_requested()) return tactile::util::interrupted_exit_status();
      throw std::runtime_error(fmt::format("no {} subscriptions within {} s (got {})",
                                           opt.wait_subscriptions, opt.wait_timeout_s,
                                           player.subscriptions()));
    }
  }
  tactile::v1::LogRecord rec;
  ReadStatus s;
  std::uint64_t sent = 0;
  std::int64_t first_ns = 0;
  bool have_first = false;
  std::int64_t t0_mono = 0;
  std::int64_t t0_log = 0;
  bool started = false;
  const std::int64_t from_ns = static_cast<std::int64_t>(opt.from_s * 1e9);
  const std::int64_t to_ns = opt.to_s > 0 ? static_cast<std::int64_t>(opt.to_s * 1e9) : INT64_MAX;
  std::int64_t next_progress = tactile::util::monotonic_ns() + 10'000'000'000;
  const std::int64_t start = tactile::util::monotonic_ns();
  bool stopped = false;
  while ((s = r.next(rec)) == ReadStatus::kRecord) {
    if (!have_first) {
      first_ns = rec.receive_time_ns();
      have_first = true;
    }
    const std::int64_t at = rec.receive_time_ns() - first_ns;
    if (at < from_ns) continue;
    if (at > to_ns) break;
    if (!wanted(opt.topics, rec.topic())) continue;
    if (!opt.fast) {
      if (!started) {
        t0_mono = tactile::util::monotonic_ns();
        t0_log = rec.receive_time_ns();
        started = true;
      }
      const auto due =
          t0_mono + static_cast<std::int64_t>(static_cast<double>(rec.receive_time_ns() - t0_log) /
                                              opt.speed);
      if (player.wait_until(due) == tactile::replay::SendStatus::kStopped) {
        stopped = true;
        break;
      }
    }
    if (player.send(rec.topic(), tactile::wire::bytes_of(rec.payload())) ==
        tactile::replay::SendStatus::kStopped) {
      stopped = true;
      break;
    }
    ++sent;
    const std::int64_t now = tactile::util::monotonic_ns();
    if (now >= next_progress) {
      next_progress = now + 10'000'000'000;
      tactile::util::log_info("{} messages sent, {:.0f} % of the log", sent,
                              100.0 * static_cast<double>(r.position()) /
                                  static_cast<double>(std::max<std::uint64_t>(r.file_size(), 1)));
    }
    if (tactile::util::stop_requested()) {
      stopped = true;
      break;
    }
  }
  tactile::util::log_info("replayed {} messages in {:.2f} s{}", sent,
                          static_cast<double>(tactile::util::monotonic_ns() - start) * 1e-9,
                          stopped ? " (stopped)" : "");
  // Cut short by a signal before the log's end: 128 + its number (docs/reliability.md#signals).
  if (stopped) return tactile::util::interrupted_exit_status();
  if (s == ReadStatus::kRecord) return 0;
  return report_end(s, r);
}

}  // namespace

int main(int argc, char** argv) {
  tactile::util::set_program_name("tactile_replay");
  Options opt;
  CLI::App app{
      "Plays a tactile log (tactile_record) back on a PUB endpoint byte for byte, at the recorded "
      "pace or as fast as possible; or measures its recorded raw frames again with the "
      "measurement core and checks the TactileFrames bit for bit (--remeasure); or describes it "
      "(--info)."};
  app.add_option("log", opt.log, "the log file");
  app.add_option("--publish", opt.publish, "PUB endpoint to play on")->capture_default_str();
  app.add_option("--speed", opt.speed, "pace: 1 is the recorded speed, 2 twice as fast")
      ->capture_default_str();
  app.add_flag("--as-fast-as-possible", opt.fast,
               "no pacing: as fast as the subscribers take the messages (none is dropped)");
  app.add_option("--topic", opt.topics, "play only topics with this prefix (repeatable)")
      ->allow_extra_args(false);
  app.add_option("--wait-subscriptions", opt.wait_subscriptions,
                 "start once this many subscriptions arrived (a subscriber sends one per topic "
                 "prefix)");
  app.add_option("--wait-timeout", opt.wait_timeout_s, "seconds to wait for them")
      ->capture_default_str();
  app.add_option("--secret-key", opt.secret_key,
                 "publish with CURVE using this key pair (a .key file of tactile_keygen)");
  app.add_option("--from", opt.from_s, "start this many seconds after the log's first record");
  app.add_option("--to", opt.to_s, "stop this many seconds after the log's first record");
  app.add_option("--remeasure", opt.remeasure,
                 "CALIBRATION...: measure the recorded raw frames again with these calibrations "
                 "and check the TactileFrames bit for bit; exit 0 only when all are identical");
  app.add_option(
      "--estimator", opt.estimator,
      "with --remeasure: measure with this centroid estimator instead of the recorded one");
  app.add_flag("--info", opt.info,
               "describe the log: header, topics, counts, time span, integrity");
  tactile::cli::add_log_level(app, opt.log_level);
  return tactile::cli::run(app, argc, argv, [&] {
    // "--remeasure A.yaml B.yaml LOG": the option takes every file; the log is the one that is
    // not a calibration.
    if (opt.log.empty() && opt.remeasure.size() >= 2 && !opt.remeasure.back().ends_with(".yaml") &&
        !opt.remeasure.back().ends_with(".yml")) {
      opt.log = opt.remeasure.back();
      opt.remeasure.pop_back();
    }
    if (opt.log.empty()) throw tactile::cli::UsageError("give the log file");
    if (opt.info && !opt.remeasure.empty())
      throw tactile::cli::UsageError("--info and --remeasure exclude each other");
    tactile::util::set_log_level(tactile::util::parse_log_level(opt.log_level));
    tactile::util::install_stop_handlers();
    if (opt.info) return info(opt);
    if (!opt.remeasure.empty()) return remeasure(opt);
    return play(opt);
  });
}
