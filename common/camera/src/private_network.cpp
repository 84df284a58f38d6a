#include "tactile/camera/private_network.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <fmt/core.h>
#include <ifaddrs.h>
#include <linux/netlink.h>
#include <linux/rtnetlink.h>
#include <net/if.h>
#include <netinet/in.h>
#include <sched.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <exception>
#include <stdexcept>
#include <thread>

#include "tactile/util/fd.hpp"

namespace tactile::camera {

namespace {

std::string errno_text(int error) {
  return std::strerror(error);
}

using util::Fd;

in_addr parse_ipv4(std::string_view text) {
  const std::string s(text);
  in_addr address{};
  if (inet_pton(AF_INET, s.c_str(), &address) != 1) {
    throw std::runtime_error(fmt::format("'{}' is not an IPv4 address", text));
  }
  return address;
}

void write_proc_file(const char* path, const std::string& text) {
  const Fd fd(::open(path, O_WRONLY | O_CLOEXEC));
  if (fd.get() < 0) {
    throw std::runtime_error(fmt::format("cannot open {}: {}", path, errno_text(errno)));
  }
  if (::write(fd.get(), text.data(), text.size()) != static_cast<ssize_t>(text.size())) {
    throw std::runtime_error(
        fmt::format("cannot write '{}' to {}: {}", text, path, errno_text(errno)));
  }
}

void bring_loopback_up() {
  const Fd fd(::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0));
  if (fd.get() < 0) throw std::runtime_error("cannot open a socket: " + errno_text(errno));
  ifreq request{};
  std::strncpy(request.ifr_name, "lo", IFNAMSIZ - 1);
  if (::ioctl(fd.get(), SIOCGIFFLAGS, &request) != 0) {
    throw std::runtime_error("cannot read the flags of lo: " + errno_text(errno));
  }
  request.ifr_flags = static_cast<short>(request.ifr_flags | IFF_UP);
  if (::ioctl(fd.get(), SIOCSIFFLAGS, &request) != 0) {
    throw std::runtime_error("cannot bring lo up: " + errno_text(errno));
  }
}

// `ip addr add ADDRESS/8 dev lo` over rtnetlink.
void add_loopback_address(std::string_view text) {
  const in_addr address = parse_ipv4(text);
  const unsigned index = if_nametoindex("lo");
  if (index == 0) throw std::runtime_error("no interface lo: " + errno_text(errno));

  struct Request {
    nlmsghdr header;
    ifaddrmsg message;
    rtattr local_attribute;
    in_addr local;
    rtattr address_attribute;
    in_addr address;
  };
  static_assert(sizeof(Request) == NLMSG_ALIGN(sizeof(Request)));
  Request request{};
  request.header.nlmsg_len = sizeof(Request);
  request.header.nlmsg_type = RTM_NEWADDR;
  request.header.nlmsg_flags = NLM_F_REQUEST | NLM_F_ACK | NLM_F_CREATE | NLM_F_EXCL;
  request.header.nlmsg_seq = 1;
  request.message.ifa_family = AF_INET;
  request.message.ifa_prefixlen = 8;
  request.message.ifa_scope = RT_SCOPE_HOST;
  request.message.ifa_index = index;
  request.local_attribute.rta_len = sizeof(rtattr) + sizeof(in_addr);
  request.local_attribute.rta_type = IFA_LOCAL;
  request.local = address;
  request.address_attribute.rta_len = sizeof(rtattr) + sizeof(in_addr);
  request.address_attribute.rta_type = IFA_ADDRESS;
  request.address = address;

  const Fd fd(::socket(AF_NETLINK, SOCK_RAW | SOCK_CLOEXEC, NETLINK_ROUTE));
  if (fd.get() < 0) throw std::runtime_error("cannot open a netlink socket: " + errno_text(errno));
  sockaddr_nl kernel{};
  kernel.nl_family = AF_NETLINK;
  if (::sendto(fd.get(), &request, sizeof(request), 0, reinterpret_cast<sockaddr*>(&kernel),
               sizeof(kernel)) != static_cast<ssize_t>(sizeof(request))) {
    throw std::runtime_error(fmt::format("cannot add {} to lo: {}", text, errno_text(errno)));
  }
  alignas(nlmsghdr) char reply[512];
  const ssize_t n = ::recv(fd.get(), reply, sizeof(reply), 0);
  if (n < static_cast<ssize_t>(sizeof(nlmsghdr) + sizeof(nlmsgerr))) {
    throw std::runtime_error(fmt::format("cannot add {} to lo: no answer from the kernel", text));
  }
  nlmsghdr header{};
  std::memcpy(&header, reply, sizeof(header));
  if (header.nlmsg_type != NLMSG_ERROR) {
    throw std::runtime_error(fmt::format("cannot add {} to lo: unexpected answer", text));
  }
  nlmsgerr answer{};
  std::memcpy(&answer, reply + NLMSG_ALIGN(sizeof(nlmsghdr)), sizeof(answer));
  if (answer.error != 0 && answer.error != -EEXIST) {
    throw std::runtime_error(
        fmt::format("cannot add {}/8 to lo: {}", text, errno_text(-answer.error)));
  }
}

}  // namespace

void run_in_network_namespace(const std::string& netns, const std::function<void()>& fn) {
  const std::string path = netns.find('/') == std::string::npos ? "/run/netns/" + netns : netns;
  const Fd ns(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
  if (ns.get() < 0) {
    const int error = errno;
    throw std::runtime_error(
        fmt::format("cannot open the network namespace {}: {} (make it with `ip netns add {}`)",
                    path, errno_text(error), netns));
  }
  std::exception_ptr failed;
  std::thread([&] {
    try {
      if (::setns(ns.get(), CLONE_NEWNET) != 0) {
        const int error = errno;
        throw std::runtime_error(fmt::format("cannot join the network namespace {}: {}{}", path,
                                             errno_text(error),
                                             error == EPERM ? " (it needs root)" : ""));
      }
      fn();
    } catch (...) {
      failed = std::current_exception();
    }
  }).join();
  if (failed) std::rethrow_exception(failed);
}

void enter_private_network(const std::vector<std::string>& loopback_addresses) {
  for (const auto& address : loopback_addresses)
    parse_ipv4(address);

  const uid_t uid = ::geteuid();
  const gid_t gid = ::getegid();
  std::string root_error;
  bool entered = false;
  if (uid == 0) {
    if (::unshare(CLONE_NEWNET) == 0) {
      entered = true;
    } else {
      root_error = fmt::format("unshare(CLONE_NEWNET): {}; ", errno_text(errno));
    }
  }
  if (!entered) {
    if (::unshare(CLONE_NEWUSER | CLONE_NEWNET) != 0) {
      const int error = errno;
      throw std::runtime_error(fmt::format(
          "cannot make a private network namespace: {}unshare(CLONE_NEWUSER | CLONE_NEWNET): {} "
          "(it needs a single-threaded process and user namespaces enabled: "
          "/proc/sys/user/max_user_namespaces > 0; in a container, allow unshare in its "
          "seccomp profile or run with CAP_SYS_ADMIN)",
          root_error, errno_text(error)));
    }
    // Map ourselves to root inside, as `unshare -r` does, to configure the namespace.
    write_proc_file("/proc/self/setgroups", "deny");
    write_proc_file("/proc/self/uid_map", fmt::format("0 {} 1", uid));
    write_proc_file("/proc/self/gid_map", fmt::format("0 {} 1", gid));
  }
  bring_loopback_up();
  for (const auto& address : loopback_addresses)
    add_loopback_address(address);
}

bool ipv4_address_assigned(std::string_view text) {
  in_addr wanted{};
  const std::string s(text);
  if (inet_pton(AF_INET, s.c_str(), &wanted) != 1) return false;
  ifaddrs* list = nullptr;
  if (::getifaddrs(&list) != 0) return false;
  bool found = false;
  for (const ifaddrs* it = list; it != nullptr && !found; it = it->ifa_next) {
    if (it->ifa_addr == nullptr || it->ifa_addr->sa_family != AF_INET) continue;
    sockaddr_in address{};
    std::memcpy(&address, it->ifa_addr, sizeof(address));
    found = address.sin_addr.s_addr == wanted.s_addr;
  }
  ::freeifaddrs(list);
  return found;
}

std::string source_address_for(std::string_view remote) {
  sockaddr_in target{};
  target.sin_family = AF_INET;
  target.sin_port = htons(3956);  // GVCP
  target.sin_addr = parse_ipv4(remote);
  const Fd fd(::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0));
  if (fd.get() < 0) throw std::runtime_error("cannot open a socket: " + errno_text(errno));
  if (::connect(fd.get(), reinterpret_cast<const sockaddr*>(&target), sizeof(target)) != 0) {
    throw std::runtime_error(fmt::format("no route to camera {}: {}", remote, errno_text(errno)));
  }
  sockaddr_in local{};
  socklen_t length = sizeof(local);
  if (::getsockname(fd.get(), reinterpret_cast<sockaddr*>(&local), &length) != 0) {
    throw std::runtime_error(
        fmt::format("no local address toward {}: {}", remote, errno_text(errno)));
  }
  char text[INET_ADDRSTRLEN] = {};
  ::inet_ntop(AF_INET, &local.sin_addr, text, sizeof(text));
  return text;
}

}  // namespace tactile::camera
