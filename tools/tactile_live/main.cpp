// tactile_live: a terminal dashboard of a running system (docs/tools.md). Each fingertip's
// elements laid out like the dome (contact, force, slip), flags, phase and the latest events, and
// message rates, redrawn 15 times a second with plain ANSI escape codes; one line per fingertip
// every second when standard output is not a terminal.
#include <sys/ioctl.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "dashboard.hpp"
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
  double refresh_s = 1.0 / 15.0;
  double interval_s = 1.0;
  double duration_s = 0;
  double silence_timeout_s = 5.0;
  bool plain = false;
  bool screen = false;
  bool no_color = false;
  std::string log_level = "warn";
};

bool write_all(const std::string& s) {
  return std::fwrite(s.data(), 1, s.size(), stdout) == s.size() && std::fflush(stdout) == 0;
}

void terminal_size(int& w, int& h) {
  winsize ws{};
  if (ioctl(STDOUT_FILENO, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 0 && ws.ws_row > 0) {
    w = ws.ws_col;
    h = ws.ws_row;
    return;
  }
  const char* c = std::getenv("COLUMNS");
  const char* l = std::getenv("LINES");
  w = c != nullptr ? std::max(20, std::atoi(c)) : 80;
  h = l != nullptr ? std::max(5, std::atoi(l)) : 24;
}

int run(const Options& opt) {
  tactile::util::set_log_level(tactile::util::parse_log_level(opt.log_level));
  if (!(opt.refresh_s > 0)) throw std::invalid_argument("--refresh must be positive");
  if (!(opt.interval_s > 0)) throw std::invalid_argument("--interval must be positive");
  if (opt.duration_s < 0) throw std::invalid_argument("--duration must not be negative");
  if (!(opt.silence_timeout_s >= 0))
    throw std::invalid_argument("--silence-timeout must not be negative");
  if (opt.plain && opt.screen)
    throw std::invalid_argument("--plain and --screen exclude each other");
  const std::vector<tactile::Calibration> cals = tactile::live::load_calibrations(opt.viewer);
  const tactile::recording::SourceOptions so = tactile::live::viewer_sources(opt.viewer);
  tactile::util::install_stop_handlers();
  zmq::context_t ctx;
  tactile::recording::Sources sources(ctx, so);

  const char* term = std::getenv("TERM");
  const bool tty = isatty(STDOUT_FILENO) != 0 && term != nullptr && std::string(term) != "dumb";
  const bool screen = opt.screen || (tty && !opt.plain);
  const bool color = screen && !opt.no_color && std::getenv("NO_COLOR") == nullptr;

  tactile::live::LiveModel model({tactile::live::flag_thresholds(opt.viewer), 8,
                                  tactile::live::recompute_detector(opt.viewer.recompute)},
                                 tactile::live::endpoints_of(sources));
  tactile::live::RenderOptions ro;
  ro.color = color;
  ro.f2_n = opt.viewer.f2_n;

  const std::int64_t start = tactile::util::monotonic_ns();
  const std::int64_t end =
      opt.duration_s > 0 ? start + static_cast<std::int64_t>(opt.duration_s * 1e9) : INT64_MAX;
  const auto period = static_cast<std::int64_t>((screen ? opt.refresh_s : opt.interval_s) * 1e9);
  std::int64_t next_draw = start;
  // A viewer pointed at the wrong address would otherwise show an empty dome forever.
  std::int64_t silence_check = opt.silence_timeout_s > 0
                                   ? start + static_cast<std::int64_t>(opt.silence_timeout_s * 1e9)
                                   : INT64_MAX;
  std::string silent;
  if (screen && !write_all("\x1b[?1049h\x1b[?25l\x1b[2J")) return 1;
  tactile::recording::Sources::Message m;
  std::string frame;
  bool ok = true;
  while (!tactile::util::stop_requested() && ok) {
    std::int64_t now = tactile::util::monotonic_ns();
    if (now >= end) break;
    if (now >= silence_check) {
      silent = sources.unheard();
      if (!silent.empty()) break;
      silence_check = INT64_MAX;
    }
    if (now >= next_draw) {
      model.tick(now, tactile::util::realtime_ns());
      if (screen) {
        terminal_size(ro.width, ro.height);
        frame = "\x1b[H";
        const std::string body = tactile::live::render(model.state(), cals, ro);
        std::size_t from = 0;
        while (from < body.size()) {  // clear each line's rest, then the screen's rest
          const auto nl = body.find('\n', from);
          frame.append(body, from, nl - from);
          frame += "\x1b[K";
          from = nl + 1;
          if (from < body.size()) frame += "\r\n";
        }
        frame += "\x1b[J";
        ok = write_all(frame);
      } else {
        ok = write_all(tactile::live::summary_lines(model.state()));
      }
      next_draw += period;
      if (next_draw < now) next_draw = now + period;
    }
    now = tactile::util::monotonic_ns();
    const auto wait = std::chrono::milliseconds(std::clamp<std::int64_t>(
        (std::min({next_draw, end, silence_check}) - now) / 1'000'000, 0, 100));
    if (sources.receive(m, wait)) {
      const std::string_view topic(static_cast<const char*>(m.topic.data()), m.topic.size());
      const int ev =
          model.add(topic, tactile::wire::bytes_of(m.payload), tactile::util::monotonic_ns());
      if (ev >= 0 && !screen) {
        ok = write_all(
            "event " +
            tactile::live::event_line(model.state().events[static_cast<std::size_t>(ev)]) + "\n");
      }
    }
  }
  if (screen) write_all("\x1b[0m\x1b[?25h\x1b[?1049l");
  if (!silent.empty()) {
    std::fprintf(stderr, "tactile_live: nothing heard from %s within %g s\n", silent.c_str(),
                 opt.silence_timeout_s);
    return 1;
  }
  if (!ok && !tactile::util::stop_requested()) {
    std::fprintf(stderr, "tactile_live: standard output: write failed\n");
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  tactile::util::set_program_name("tactile_live");
  Options opt;
  CLI::App app{
      "A live terminal view of the tactile system: each fingertip's 41 elements laid out like "
      "the dome (contact, force, slip), the flags, hand_node's phase and latest events, and "
      "message rates. Plain ANSI escape codes (works over SSH with TERM=xterm); one line per "
      "fingertip every --interval when standard output is not a terminal."};
  tactile::live::add_viewer_options(app, opt.viewer, "F2 [N] for OVER and the force digits");
  app.add_option("--refresh", opt.refresh_s, "seconds between screen redraws")
      ->capture_default_str();
  app.add_option("--interval", opt.interval_s, "seconds between lines in line mode")
      ->capture_default_str();
  app.add_option("--duration", opt.duration_s, "stop after this many seconds (0: until a signal)");
  app.add_option("--silence-timeout", opt.silence_timeout_s,
                 "exit 1, naming the endpoint, when an endpoint has sent nothing within this many "
                 "seconds of the start (0: wait forever)")
      ->capture_default_str();
  app.add_flag("--plain", opt.plain, "line mode even on a terminal");
  app.add_flag("--screen", opt.screen, "screen mode even when standard output is not a terminal");
  app.add_flag("--no-color", opt.no_color, "no colours (also when NO_COLOR is set)");
  tactile::cli::add_log_level(app, opt.log_level);
  return tactile::cli::run(app, argc, argv, [&] {
    tactile::live::settle_endpoints(opt.viewer);
    return run(opt);
  });
}
