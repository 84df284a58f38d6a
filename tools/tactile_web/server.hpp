#pragma once

// tactile_web's HTTP side: the page, Debian's Chart.js, and the updates as Server-Sent Events.
// The subscriber hands each update to an UpdateSlot and goes on; every viewer's connection takes
// the newest update when it is ready for one, so a slow browser gets fewer updates (counted as
// coalesced) and never holds up the subscriber.
#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

namespace httplib {
class Server;
}

namespace tactile::web {

class UpdateSlot {
 public:
  // Chart points kept for a page that joins late: the page's rolling charts hold as many.
  static constexpr std::size_t kHistory = 300;
  // Room for a chart point of a few fingertips in every slot of the history at once, so that
  // publishing allocates nothing from the first update on (docs/architecture.md, rule 4).
  static constexpr std::size_t kPointRoom = 512;
  UpdateSlot();

  // Puts `update` in the slot and gives back the buffer it replaced (its capacity reused by the
  // next update), and keeps `point` (SnapshotWriter::write_point) among the latest kHistory: no
  // allocation once the buffers have grown to an update's size.
  void publish(std::string& update, const std::string& point);

  enum class Wait { kNew, kTimeout, kClosed };
  // Waits up to `timeout` for an update newer than `seen`; copies it into `out` and moves
  // `seen` to it. Updates skipped on the way are counted in coalesced(). With `history`, a
  // viewer's first update (`seen` 0) comes with the chart points of the updates before it, as one
  // JSON array in *history, so that a page that joins late fills its charts at once.
  Wait wait_newer(std::uint64_t& seen, std::string& out, std::chrono::milliseconds timeout,
                  std::string* history = nullptr);
  // The latest update, or an empty string before the first one.
  std::string latest() const;
  void close();
  std::uint64_t coalesced() const { return coalesced_.load(); }

 private:
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::string latest_;
  std::array<std::string, kHistory> points_;  // a ring: points_[(version_ - 1) % kHistory] newest
  std::uint64_t version_ = 0;
  bool closed_ = false;
  std::atomic<std::uint64_t> coalesced_{0};
};

struct Listen {
  std::string host;
  int port = 0;  // 0: any free port
};
// "HOST:PORT" (an IPv4 address or localhost); throws std::invalid_argument naming the text.
Listen parse_listen(const std::string& text);

// Where Debian's libjs-chart.js puts the UMD build the page loads.
inline constexpr const char* kChartJsPath = "/usr/share/javascript/chart.js/chart.min.js";

struct ServerOptions {
  Listen listen{"127.0.0.1", 8080};
  std::filesystem::path chart_js = kChartJsPath;
  int max_viewers = 4;  // event streams at a time; more are refused (503)
};

class WebServer {
 public:
  // Reads Chart.js and binds; throws std::runtime_error naming the file and its package, or the
  // address, when either fails.
  WebServer(const ServerOptions& options, UpdateSlot& slot);
  ~WebServer();
  WebServer(const WebServer&) = delete;
  WebServer& operator=(const WebServer&) = delete;

  int port() const { return port_; }
  // Serves on a thread of its own that, like the threads it starts, leaves SIGINT and SIGTERM to
  // the subscriber's thread.
  void start();
  // Closes the event streams and joins the server's threads.
  void stop();

  std::uint64_t streams() const { return streams_.load(); }
  std::uint64_t sent() const { return sent_.load(); }

 private:
  UpdateSlot& slot_;
  std::unique_ptr<httplib::Server> server_;
  std::string chart_js_;
  int port_ = 0;
  int max_viewers_ = 4;
  std::thread thread_;
  std::atomic<std::uint64_t> streams_{0};
  std::atomic<std::uint64_t> sent_{0};
};

}  // namespace tactile::web
