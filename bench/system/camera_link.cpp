#include "camera_link.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <map>

#include "tactile/camera/private_network.hpp"
#include "tactile/util/stop.hpp"

namespace tactile::bench {

Dist probe_link(const CameraLink& link, const std::vector<std::size_t>& sizes, int bursts) {
  const std::size_t packets = sizes.size();
  if (!link.shaped() || packets == 0) return {};
  const auto fail = [](const std::string& what) {
    return std::runtime_error(fmt::format("link probe: {}: {}", what, std::strerror(errno)));
  };
  const int rx = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (rx < 0) throw fail("socket");
  sockaddr_in at{};
  at.sin_family = AF_INET;
  ::inet_pton(AF_INET, link.node_address().c_str(), &at.sin_addr);
  const int big = 16 << 20;
  ::setsockopt(rx, SOL_SOCKET, SO_RCVBUF, &big, sizeof big);
  const timeval tv{0, 200'000};
  ::setsockopt(rx, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  socklen_t len = sizeof at;
  if (::bind(rx, reinterpret_cast<sockaddr*>(&at), sizeof at) != 0 ||
      ::getsockname(rx, reinterpret_cast<sockaddr*>(&at), &len) != 0) {
    ::close(rx);
    throw fail("bind " + link.node_address());
  }
  int tx = -1;
  camera::run_in_network_namespace(link.netns(),
                                   [&] { tx = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0); });
  if (tx < 0) {
    ::close(rx);
    throw fail("socket in the cameras' namespace");
  }
  ::setsockopt(tx, SOL_SOCKET, SO_SNDBUF, &big, sizeof big);
  struct Header {
    std::uint32_t burst;
    std::int64_t sent_ns;
  };
  std::vector<std::vector<char>> payload;
  for (const std::size_t size : sizes)
    payload.emplace_back(std::max(size, sizeof(Header)));
  std::vector<iovec> iov(packets);
  std::vector<mmsghdr> msgs(packets);
  std::jthread sender([&] {
    for (int b = 0; b < bursts && !util::stop_requested(); ++b) {
      const Header h{static_cast<std::uint32_t>(b), util::realtime_ns()};
      for (std::size_t i = 0; i < packets; ++i) {
        std::memcpy(payload[i].data(), &h, sizeof h);
        iov[i] = {payload[i].data(), payload[i].size()};
        msgs[i] = {};
        msgs[i].msg_hdr.msg_iov = &iov[i];
        msgs[i].msg_hdr.msg_iovlen = 1;
        msgs[i].msg_hdr.msg_name = &at;
        msgs[i].msg_hdr.msg_namelen = sizeof at;
      }
      for (std::size_t sent = 0; sent < packets;) {
        const int k = ::sendmmsg(tx, msgs.data() + sent, static_cast<unsigned>(packets - sent), 0);
        if (k <= 0) return;
        sent += static_cast<std::size_t>(k);
      }
      std::this_thread::sleep_for(milliseconds(20));
    }
  });
  std::vector<double> whole;
  std::uint32_t current = ~0U;
  std::size_t count = 0;
  std::int64_t sent_ns = 0, last_ns = 0;
  const auto close_burst = [&] {
    if (current != ~0U && count == packets)
      whole.push_back(static_cast<double>(last_ns - sent_ns) * 1e-6);
  };
  std::vector<char> buf(*std::max_element(sizes.begin(), sizes.end()) + sizeof(Header));
  for (;;) {
    const ssize_t k = ::recv(rx, buf.data(), buf.size(), 0);
    if (k < static_cast<ssize_t>(sizeof(Header))) break;  // 200 ms of silence: the last burst is in
    const std::int64_t now = util::realtime_ns();
    Header h{};
    std::memcpy(&h, buf.data(), sizeof h);
    if (h.burst != current) {
      close_burst();
      current = h.burst;
      count = 0;
      sent_ns = h.sent_ns;
    }
    ++count;
    last_ns = now;
  }
  close_burst();
  sender.join();
  ::close(tx);
  ::close(rx);
  return dist(whole);
}

}  // namespace tactile::bench
