// GigE Vision fill -> receive latency and CPU, in one process on a private loopback network:
// FakeGvCamera(s) send 640x480 frames, AravisCamera(s) receive them. For each frame the camera
// thread's fill time (CLOCK_REALTIME, just before the packets go out) is matched by block id
// to the receiver's times: "done" is the stream callback's BUFFER_DONE stamp (the frame's
// receive_timestamp_ns), "wait" is when wait_frame returned it to the caller. CPU is read per
// thread from /proc/self/task/*/schedstat and split into the cameras' side and the receivers'.
//
//   tactile_camera_latency_bench [--seconds 3] [--fps 100,200,500] [--cameras 1,2]
//                                [--format Mono8] [--packet-size 65000]
#include <dirent.h>
#include <fmt/core.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <atomic>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "tactile/camera/aravis_camera.hpp"
#include "tactile/camera/fake_gv_camera.hpp"
#include "tactile/camera/private_network.hpp"
#include "tactile/cli/run.hpp"
#include "tactile/util/clock.hpp"
#include "tactile/util/log.hpp"
#include "tactile/util/percentile.hpp"

namespace tactile::camera {
namespace {

struct Settings {
  double seconds = 3.0;
  std::vector<double> rates{100.0, 200.0, 500.0};
  std::vector<int> camera_counts{1, 2};
  std::string format = "Mono8";
  int packet_size = 65000;
  int width = 640;
  int height = 480;
};

// Fill time of each 16-bit block id, written on the camera thread, read by the receiver.
struct FillLog {
  std::array<std::atomic<std::int64_t>, 65536> fill_ns{};
  std::atomic<pid_t> camera_thread{0};  // the fake camera's thread, seen from its callback
};

struct Samples {
  std::vector<double> done_ms;
  std::vector<double> wait_ms;
  std::uint64_t frames = 0;
  std::uint64_t complete = 0;
  std::uint64_t lost = 0;
};

// Nanoseconds the threads of this process have run: the fake cameras' threads (found by
// their id, seen from the fill callback) against all others but the idle main thread.
struct ThreadTimes {
  std::int64_t camera_ns = 0;    // fill, send, GVCP answers
  std::int64_t receiver_ns = 0;  // Aravis stream and control threads, the waiting threads
};

ThreadTimes thread_times(const std::vector<pid_t>& camera_threads) {
  ThreadTimes t;
  DIR* dir = opendir("/proc/self/task");
  if (dir == nullptr) return t;
  const pid_t main_thread = getpid();
  while (const dirent* entry = readdir(dir)) {
    if (entry->d_name[0] == '.') continue;
    const pid_t tid = static_cast<pid_t>(std::stol(entry->d_name));
    std::int64_t run_ns = 0;
    std::ifstream(std::string("/proc/self/task/") + entry->d_name + "/schedstat") >> run_ns;
    if (std::find(camera_threads.begin(), camera_threads.end(), tid) != camera_threads.end()) {
      t.camera_ns += run_ns;
    } else if (tid != main_thread) {
      t.receiver_ns += run_ns;
    }
  }
  closedir(dir);
  return t;
}

struct Row {
  int cameras;
  double fps;
  Samples samples;
  double receiver_cpu;  // percent of one core
  double camera_cpu;
};

Row run_case(const Settings& s, int cameras, double fps) {
  const PixelFormat format = parse_pixel_format(s.format);
  const char* addresses[] = {"127.0.0.2", "127.0.0.3"};
  std::vector<std::unique_ptr<FillLog>> logs;
  std::vector<std::unique_ptr<FakeGvCamera>> fakes;
  std::vector<std::unique_ptr<AravisCamera>> receivers;
  Image image(s.width, s.height, format);
  for (int y = 0; y < s.height; ++y) {
    for (int x = 0; x < s.width; ++x)
      image.set(x, y, static_cast<std::uint32_t>(x + 3 * y));
  }
  for (int c = 0; c < cameras; ++c) {
    FakeGvCameraOptions fo;
    fo.address = addresses[c];
    fo.serial = fmt::format("BENCH{}", c);
    fo.width = s.width;
    fo.height = s.height;
    fo.pixel_format = format;
    fo.frame_rate_hz = fps;
    fakes.push_back(std::make_unique<FakeGvCamera>(fo));
    logs.push_back(std::make_unique<FillLog>());
    FillLog* log = logs.back().get();
    fakes.back()->set_sent_observer([log](const SentFrame& sent) {
      log->fill_ns[sent.block_id & 0xFFFF].store(sent.fill_time_ns, std::memory_order_release);
      log->camera_thread.store(static_cast<pid_t>(syscall(SYS_gettid)), std::memory_order_relaxed);
    });
    if (!fakes.back()->publish(image.view(), 0, 1)) throw std::logic_error("publish refused");

    AravisCameraOptions ro;
    ro.camera = addresses[c];
    ro.width = s.width;
    ro.height = s.height;
    ro.pixel_format = format;
    ro.frame_rate_hz = fps;
    ro.packet_size_bytes = s.packet_size;
    receivers.push_back(std::make_unique<AravisCamera>(ro));
    receivers.back()->start();
  }

  std::vector<Samples> per_camera(static_cast<std::size_t>(cameras));
  const std::int64_t warmup_ns = 300'000'000;
  const auto measure_ns = static_cast<std::int64_t>(s.seconds * 1e9);
  ThreadTimes before;
  std::vector<pid_t> camera_threads;
  std::int64_t measure_start = 0;
  {
    std::vector<std::jthread> threads;
    const std::int64_t begin = util::monotonic_ns();
    for (int c = 0; c < cameras; ++c) {
      threads.emplace_back([&, c] {
        AravisCamera& camera = *receivers[static_cast<std::size_t>(c)];
        Samples& out = per_camera[static_cast<std::size_t>(c)];
        out.done_ms.reserve(static_cast<std::size_t>(fps * s.seconds * 1.2) + 16);
        out.wait_ms.reserve(out.done_ms.capacity());
        const FillLog& log = *logs[static_cast<std::size_t>(c)];
        const std::int64_t end = begin + warmup_ns + measure_ns;
        while (util::monotonic_ns() < end) {
          const Frame f = camera.wait_frame(std::chrono::milliseconds(200));
          const std::int64_t returned = util::realtime_ns();
          if (!f.received || util::monotonic_ns() < begin + warmup_ns) continue;
          ++out.frames;
          out.lost += f.frames_lost;
          if (f.status != FrameStatus::kComplete) continue;
          ++out.complete;
          const std::int64_t fill =
              log.fill_ns[f.camera_frame_id & 0xFFFF].load(std::memory_order_acquire);
          out.done_ms.push_back(static_cast<double>(f.receive_timestamp_ns - fill) / 1e6);
          out.wait_ms.push_back(static_cast<double>(returned - fill) / 1e6);
        }
      });
    }
    // CPU over the measured window only.
    while (util::monotonic_ns() < begin + warmup_ns) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    for (const auto& log : logs)
      camera_threads.push_back(log->camera_thread.load());
    before = thread_times(camera_threads);
    measure_start = util::monotonic_ns();
    while (util::monotonic_ns() < begin + warmup_ns + measure_ns) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  const ThreadTimes after = thread_times(camera_threads);
  const auto wall = static_cast<double>(util::monotonic_ns() - measure_start);

  Row row{cameras, fps, {}, 0.0, 0.0};
  for (auto& p : per_camera) {
    row.samples.done_ms.insert(row.samples.done_ms.end(), p.done_ms.begin(), p.done_ms.end());
    row.samples.wait_ms.insert(row.samples.wait_ms.end(), p.wait_ms.begin(), p.wait_ms.end());
    row.samples.frames += p.frames;
    row.samples.complete += p.complete;
    row.samples.lost += p.lost;
  }
  row.receiver_cpu = 100.0 * static_cast<double>(after.receiver_ns - before.receiver_ns) / wall;
  row.camera_cpu = 100.0 * static_cast<double>(after.camera_ns - before.camera_ns) / wall;
  for (auto& r : receivers)
    r->stop();
  receivers.clear();  // controllers go before their cameras
  fakes.clear();
  return row;
}

int run(const Settings& s) {
  enter_private_network({"127.0.0.2", "127.0.0.3"});
  std::printf("GigE Vision fill -> receive, %dx%d %s, packets %d B, %.1f s per row, %u cores\n",
              s.width, s.height, s.format.c_str(), s.packet_size, s.seconds,
              std::thread::hardware_concurrency());
  std::printf(
      "latency in ms: done = stream callback (receive_timestamp_ns), wait = wait_frame "
      "returned; CPU in %% of one core\n\n");
  std::string load;
  std::getline(std::ifstream("/proc/loadavg"), load);
  std::printf("load average at start: %s\n\n", load.c_str());
  std::printf(
      "| cameras | fps | sent fps | frames | complete | lost | done p50 | done p99 | done max | "
      "wait p50 | wait p99 | wait max | receiver CPU | camera CPU |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const int cameras : s.camera_counts) {
    for (const double fps : s.rates) {
      const Row r = run_case(s, cameras, fps);
      const auto& d = r.samples.done_ms;
      const auto& w = r.samples.wait_ms;
      std::printf(
          "| %d | %.0f | %.0f | %llu | %llu | %llu | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | "
          "%.1f %% | %.1f %% |\n",
          r.cameras, r.fps,
          static_cast<double>(r.samples.frames + r.samples.lost) / (s.seconds * r.cameras),
          static_cast<unsigned long long>(r.samples.frames),
          static_cast<unsigned long long>(r.samples.complete),
          static_cast<unsigned long long>(r.samples.lost), util::nearest_rank_percentile(d, 0.5),
          util::nearest_rank_percentile(d, 0.99),
          d.empty() ? 0.0 : *std::max_element(d.begin(), d.end()),
          util::nearest_rank_percentile(w, 0.5), util::nearest_rank_percentile(w, 0.99),
          w.empty() ? 0.0 : *std::max_element(w.begin(), w.end()), r.receiver_cpu, r.camera_cpu);
      std::fflush(stdout);
    }
  }
  return 0;
}

}  // namespace
}  // namespace tactile::camera

int main(int argc, char** argv) {
  tactile::util::set_program_name("tactile_camera_latency_bench");
  tactile::camera::Settings s;
  CLI::App app(
      "GigE Vision fill -> receive latency and CPU of tactile::camera (FakeGvCamera -> "
      "AravisCamera) in a private loopback network namespace");
  app.add_option("--seconds", s.seconds, "measured time per row")->check(CLI::Range(0.5, 600.0));
  app.add_option("--fps", s.rates, "frame rates")->delimiter(',')->check(CLI::Range(1.0, 1000.0));
  app.add_option("--cameras", s.camera_counts, "camera counts (1 or 2)")
      ->delimiter(',')
      ->check(CLI::Range(1, 2));
  app.add_option("--format", s.format, "Mono8 or Mono16");
  app.add_option("--packet-size", s.packet_size, "GVSP packet size")->check(CLI::Range(576, 65500));
  return tactile::cli::run(app, argc, argv, [&] { return tactile::camera::run(s); });
}
