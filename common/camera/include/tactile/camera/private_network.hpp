#pragma once

// Private loopback networks for the simulated rig, tests and benchmarks: two fake GigE Vision
// cameras need two addresses (GVCP port 3956 is per address), and adding addresses to the
// host's lo needs root and outlives the program. A private network namespace needs neither.
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace tactile::camera {

// Moves the calling process into a new network namespace whose lo is up and carries
// 127.0.0.1 plus `loopback_addresses` (for example 127.0.0.2 and 127.0.0.3, each /8). As root
// this is a new network namespace; otherwise (or where root may not create one) a new user
// namespace too, as `unshare -rn` does. Child processes started afterwards share it. Nothing
// is left behind: the namespace ends with the last process in it.
//
// Must be called while the process has a single thread (before any Aravis or GLib use).
// Throws std::runtime_error saying what failed.
void enter_private_network(const std::vector<std::string>& loopback_addresses);

// Runs `fn` on a thread of its own that has joined the network namespace `netns` (a name `ip
// netns add` made, under /run/netns, or a path such as /proc/PID/ns/net) and waits for it. The
// sockets `fn` opens, and the threads it starts, stay in that namespace; the caller's thread
// does not move. How the rig puts its cameras behind a link of their own (rig --camera-netns).
// Rethrows what `fn` throws; throws std::runtime_error naming the namespace when it cannot be
// opened or joined (joining needs CAP_SYS_ADMIN).
void run_in_network_namespace(const std::string& netns, const std::function<void()>& fn);

// True when some interface of the current network namespace has this IPv4 address.
bool ipv4_address_assigned(std::string_view address);

// The local IPv4 address the kernel would use to reach `remote` (UDP, no packet sent).
// Throws std::runtime_error when there is no route.
std::string source_address_for(std::string_view remote);

}  // namespace tactile::camera
