#include "server.hpp"

#include <arpa/inet.h>
#include <httplib.h>
#include <pthread.h>
#include <signal.h>

#include <charconv>
#include <stdexcept>

#include "page_assets.hpp"
#include "tactile/util/files.hpp"

namespace tactile::web {

UpdateSlot::UpdateSlot() {
  for (auto& p : points_)
    p.reserve(kPointRoom);
}

void UpdateSlot::publish(std::string& update, const std::string& point) {
  {
    std::lock_guard lock(mutex_);
    latest_.swap(update);
    points_[version_ % kHistory] = point;  // into the slot's own capacity once warm
    ++version_;
  }
  changed_.notify_all();
}

UpdateSlot::Wait UpdateSlot::wait_newer(std::uint64_t& seen, std::string& out,
                                        std::chrono::milliseconds timeout, std::string* history) {
  std::unique_lock lock(mutex_);
  if (!changed_.wait_for(lock, timeout, [&] { return closed_ || version_ > seen; }))
    return Wait::kTimeout;
  if (closed_) return Wait::kClosed;
  if (seen > 0) coalesced_ += version_ - seen - 1;
  if (seen == 0 && history != nullptr) {
    // The points of the updates before the latest, oldest first (the latest comes in `out`).
    history->assign("[");
    const std::uint64_t kept = std::min<std::uint64_t>(version_ - 1, kHistory - 1);
    for (std::uint64_t v = version_ - kept; v < version_; ++v) {
      if (v > version_ - kept) *history += ',';
      *history += points_[(v - 1) % kHistory];
    }
    *history += ']';
  }
  seen = version_;
  if (out.capacity() < latest_.capacity()) out.reserve(latest_.capacity());
  out = latest_;
  return Wait::kNew;
}

std::string UpdateSlot::latest() const {
  std::lock_guard lock(mutex_);
  return latest_;
}

void UpdateSlot::close() {
  {
    std::lock_guard lock(mutex_);
    closed_ = true;
  }
  changed_.notify_all();
}

Listen parse_listen(const std::string& text) {
  const auto colon = text.rfind(':');
  const std::string bad = "--listen '" + text + "': ";
  if (colon == std::string::npos || colon == 0)
    throw std::invalid_argument(bad + "expected HOST:PORT, e.g. 127.0.0.1:8080");
  Listen l;
  l.host = text.substr(0, colon);
  const std::string port = text.substr(colon + 1);
  const auto [end, ec] = std::from_chars(port.data(), port.data() + port.size(), l.port);
  if (ec != std::errc() || end != port.data() + port.size() || l.port < 0 || l.port > 65535)
    throw std::invalid_argument(bad + "the port must be a number from 0 to 65535");
  in_addr a{};
  if (l.host != "localhost" && inet_pton(AF_INET, l.host.c_str(), &a) != 1)
    throw std::invalid_argument(bad + "the host must be an IPv4 address or localhost");
  return l;
}

WebServer::WebServer(const ServerOptions& o, UpdateSlot& slot)
    : slot_(slot), server_(std::make_unique<httplib::Server>()), max_viewers_(o.max_viewers) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(o.chart_js, ec)) {
    throw std::runtime_error(o.chart_js.string() +
                             ": not found; the page's charts come from Debian's package "
                             "libjs-chart.js (apt-get install libjs-chart.js)");
  }
  chart_js_ = util::read_file(o.chart_js);
  auto& s = *server_;
  // One thread per event stream and two for everything else: a bounded number of threads.
  const auto threads = static_cast<std::size_t>(max_viewers_ + 2);
  s.new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
  // SO_REUSEADDR only: httplib's default adds SO_REUSEPORT, with which a second tactile_web on
  // the same port would start and share the connections instead of failing.
  s.set_socket_options([](socket_t sock) {
    const int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  s.set_write_timeout(2, 0);  // a browser that stops reading is let go
  s.set_keep_alive_timeout(2);
  auto asset = [&s](const char* path, std::string_view body, const char* type) {
    s.Get(path, [body, type](const httplib::Request&, httplib::Response& res) {
      res.set_content(body.data(), body.size(), type);
    });
  };
  asset("/", page::kIndexHtml, "text/html; charset=utf-8");
  asset("/app.js", page::kAppJs, "text/javascript; charset=utf-8");
  asset("/style.css", page::kStyleCss, "text/css; charset=utf-8");
  s.Get("/chart.js", [this](const httplib::Request&, httplib::Response& res) {
    res.set_content(chart_js_, "text/javascript; charset=utf-8");
  });
  s.Get("/state", [this](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    res.set_content(slot_.latest(), "application/json");
  });
  s.Get("/stream", [this](const httplib::Request&, httplib::Response& res) {
    if (streams_.fetch_add(1) >= static_cast<std::uint64_t>(max_viewers_)) {
      --streams_;
      res.status = 503;
      res.set_content("tactile_web: too many viewers\n", "text/plain");
      return;
    }
    struct Stream {
      std::uint64_t seen = 0;
      std::string update;
      std::string history;
      std::string message;
    };
    auto st = std::make_shared<Stream>();
    res.set_header("Cache-Control", "no-store");
    res.set_chunked_content_provider(
        "text/event-stream",
        [this, st](std::size_t, httplib::DataSink& sink) {
          const bool first = st->seen == 0;
          switch (slot_.wait_newer(st->seen, st->update, std::chrono::milliseconds(500),
                                   first ? &st->history : nullptr)) {
            case UpdateSlot::Wait::kClosed: {
              // Tells the page the program stopped, so that it stops reconnecting.
              static constexpr std::string_view kEnd = "event: end\ndata: {}\n\n";
              sink.write(kEnd.data(), kEnd.size());
              sink.done();
              return true;
            }
            case UpdateSlot::Wait::kTimeout:
              return sink.write(": idle\n\n", 8);  // finds a closed connection
            case UpdateSlot::Wait::kNew:
              break;
          }
          // A page that joins late gets the charts' recent points before its first update.
          st->message.clear();
          if (first) {
            st->message += "event: history\ndata: ";
            st->message += st->history;
            st->message += "\n\n";
          }
          st->message += "data: ";
          st->message += st->update;
          st->message += "\n\n";
          ++sent_;
          return sink.write(st->message.data(), st->message.size());
        },
        [this](bool) { --streams_; });
  });
  if (o.listen.port == 0) {
    port_ = s.bind_to_any_port(o.listen.host);
  } else {
    port_ = s.bind_to_port(o.listen.host, o.listen.port) ? o.listen.port : -1;
  }
  if (port_ <= 0) {
    throw std::runtime_error("cannot listen on " + o.listen.host + ":" +
                             std::to_string(o.listen.port) + " (in use, or not this host's)");
  }
}

WebServer::~WebServer() {
  stop();
}

void WebServer::start() {
  sigset_t block, old;
  sigemptyset(&block);
  sigaddset(&block, SIGINT);
  sigaddset(&block, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &block, &old);
  thread_ = std::thread([this] { server_->listen_after_bind(); });
  pthread_sigmask(SIG_SETMASK, &old, nullptr);
}

void WebServer::stop() {
  slot_.close();
  if (server_) server_->stop();
  if (thread_.joinable()) thread_.join();
}

}  // namespace tactile::web
