// tactile_web: the live view in a browser (docs/tools.md). Subscribes like tactile_live, keeps
// the same model (flags, phase, events), and serves one page on a local port that draws both
// fingertips as in the paper's Fig. 3, the flags, the phase, the events and rolling plots,
// updated by Server-Sent Events.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "dashboard.hpp"
#include "server.hpp"
#include "snapshot.hpp"
#include "tactile/cli/run.hpp"
#include "tactile/recording/sources.hpp"
#include "tactile/util/clock.hpp"
#include "tactile/util/log.hpp"
#include "tactile/util/stop.hpp"
#include "tactile/wire/envelope.hpp"
#include "tactile/wire/sockets.hpp"
#include "viewer.hpp"

namespace {

struct Options {
  tactile::live::ViewerOptions viewer;
  std::string listen = "127.0.0.1:8080";
  double rate_hz = 30;
  int max_viewers = 4;
  std::size_t events = 50;
  double duration_s = 0;
  bool stats = false;
  std::string chart_js = tactile::web::kChartJsPath;
  std::string log_level = "warn";
};

bool loopback(const std::string& host) {
  return host == "localhost" || host.starts_with("127.");
}

int run(const Options& opt) {
  tactile::util::set_log_level(tactile::util::parse_log_level(opt.log_level));
  if (!(opt.rate_hz >= 0)) throw std::invalid_argument("--rate must not be negative");
  if (opt.duration_s < 0) throw std::invalid_argument("--duration must not be negative");
  if (opt.max_viewers < 1) throw std::invalid_argument("--max-viewers must be at least 1");
  if (opt.events < 1) throw std::invalid_argument("--events must be at least 1");
  tactile::web::ServerOptions web;
  web.listen = tactile::web::parse_listen(opt.listen);
  web.chart_js = opt.chart_js;
  web.max_viewers = opt.max_viewers;
  std::vector<tactile::Calibration> cals = tactile::live::load_calibrations(opt.viewer);
  const tactile::recording::SourceOptions so = tactile::live::viewer_sources(opt.viewer);
  tactile::util::install_stop_handlers();
  zmq::context_t ctx;
  tactile::recording::Sources sources(ctx, so);

  const tactile::control::Config cc = tactile::live::flag_thresholds(opt.viewer);
  tactile::live::LiveModel model(
      {cc, opt.events, tactile::live::recompute_detector(opt.viewer.recompute)},
      tactile::live::endpoints_of(sources));
  tactile::web::SnapshotWriter writer(std::move(cals), cc);
  tactile::web::UpdateSlot slot;
  tactile::web::WebServer server(web, slot);
  if (!loopback(web.listen.host)) {
    tactile::util::log_warn("serving on {}: anyone who reaches this address sees the sensors",
                            web.listen.host);
  }
  server.start();
  std::printf("tactile_web: serving http://%s:%d/\n", web.listen.host.c_str(), server.port());
  std::fflush(stdout);

  const std::int64_t start = tactile::util::monotonic_ns();
  const std::int64_t end =
      opt.duration_s > 0 ? start + static_cast<std::int64_t>(opt.duration_s * 1e9) : INT64_MAX;
  // --rate 0: an update after every message (the benchmark's upper bound).
  const auto period = opt.rate_hz > 0 ? static_cast<std::int64_t>(1e9 / opt.rate_hz) : 0;
  std::int64_t next_update = start;
  std::int64_t last_update = start;
  bool changed = true;
  tactile::web::UpdateCounters counters;
  std::string update;
  std::string point;
  tactile::recording::Sources::Message m;
  while (!tactile::util::stop_requested()) {
    std::int64_t now = tactile::util::monotonic_ns();
    if (now >= end) break;
    // Rates and ages move on without messages: a quiet system is still updated once a second.
    if (now >= next_update && (changed || now - last_update >= 1'000'000'000)) {
      model.tick(now, tactile::util::realtime_ns());
      ++counters.update;
      counters.coalesced = slot.coalesced();
      counters.streams = server.streams();
      writer.write(model.state(), counters, update);
      writer.write_point(model.state(), point);
      slot.publish(update, point);
      changed = false;
      last_update = now;
      next_update += period;
      if (next_update < now) next_update = now + period;
    }
    now = tactile::util::monotonic_ns();
    const std::int64_t wake = std::min(changed ? next_update : last_update + 1'000'000'000, end);
    const auto wait =
        std::chrono::milliseconds(std::clamp<std::int64_t>((wake - now) / 1'000'000, 0, 100));
    if (sources.receive(m, wait)) {
      const std::string_view topic(static_cast<const char*>(m.topic.data()), m.topic.size());
      model.add(topic, tactile::wire::bytes_of(m.payload), tactile::util::monotonic_ns());
      changed = true;
    }
  }
  const double run_s = static_cast<double>(tactile::util::monotonic_ns() - start) * 1e-9;
  server.stop();
  if (opt.stats) {
    std::printf(
        "tactile_web: stats: %.2f s, %llu messages, %llu updates (%.1f/s), %llu sent to viewers "
        "(%.1f/s), %llu coalesced\n",
        run_s, static_cast<unsigned long long>(model.state().messages),
        static_cast<unsigned long long>(counters.update),
        static_cast<double>(counters.update) / run_s,
        static_cast<unsigned long long>(server.sent()), static_cast<double>(server.sent()) / run_s,
        static_cast<unsigned long long>(slot.coalesced()));
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  tactile::util::set_program_name("tactile_web");
  Options opt;
  CLI::App app{
      "A live view of the tactile system in a browser: serves one page that draws each "
      "fingertip's elements as in the paper's Fig. 3 (force as colour and size, shear as arrows, "
      "slip marked), the flags, hand_node's phase and events, and rolling plots of force and "
      "slip, updated by Server-Sent Events. Bound to localhost unless --listen says otherwise."};
  tactile::live::add_viewer_options(app, opt.viewer, "F2 [N] for OVER and the colour scale");
  app.add_option("--listen", opt.listen,
                 "HOST:PORT to serve on (port 0: any free one, printed at start)")
      ->capture_default_str()
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            try {
              tactile::web::parse_listen(text);
              return {};
            } catch (const std::invalid_argument& e) {
              return e.what();
            }
          },
          "HOST:PORT", "listen address"));
  app.add_option("--rate", opt.rate_hz, "updates per second at most (0: one after every message)")
      ->capture_default_str();
  app.add_option("--max-viewers", opt.max_viewers, "browsers served at a time")
      ->capture_default_str();
  app.add_option("--events", opt.events, "latest events kept for a page that joins")
      ->capture_default_str();
  app.add_option("--duration", opt.duration_s, "stop after this many seconds (0: until a signal)");
  app.add_flag("--stats", opt.stats,
               "print updates made and sent to viewers, per second, and coalesced, at the end");
  app.add_option("--chart-js", opt.chart_js, "Chart.js (UMD build) to serve")
      ->capture_default_str();
  tactile::cli::add_log_level(app, opt.log_level);
  return tactile::cli::run(app, argc, argv, [&] {
    tactile::live::settle_endpoints(opt.viewer);
    return run(opt);
  });
}
