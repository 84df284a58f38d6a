#include "tactile/util/realtime.hpp"

#include <fmt/format.h>
#include <sched.h>
#include <sys/mman.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace tactile::util {

namespace {

constexpr const char* kHowToGrant =
    "run it as root, give it CAP_SYS_NICE and CAP_IPC_LOCK (setcap cap_sys_nice,cap_ipc_lock+ep, "
    "or cap_add: [SYS_NICE, IPC_LOCK] in docker compose), or raise its rtprio and memlock "
    "limits (/etc/security/limits.conf); or remove the realtime section";

// AddressSanitizer and ThreadSanitizer map terabytes of shadow memory: mlockall would try to
// fault all of it in.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr bool kShadowMemory = true;
#else
constexpr bool kShadowMemory = false;
#endif

}  // namespace

void apply_realtime_scheduling(const RealtimeScheduling& r, const std::string& where) {
  if (r.priority != 0) {
    if (r.priority < kMinRealtimePriority || r.priority > kMaxRealtimePriority)
      throw std::invalid_argument(fmt::format("{}: priority must be {} to {}, is {}", where,
                                              kMinRealtimePriority, kMaxRealtimePriority,
                                              r.priority));
    sched_param p{};
    p.sched_priority = r.priority;
    if (::sched_setscheduler(0, SCHED_FIFO, &p) != 0) {
      const int e = errno;
      throw std::runtime_error(fmt::format("{}: SCHED_FIFO priority {} refused ({}): {}", where,
                                           r.priority, std::strerror(e), kHowToGrant));
    }
  }
  if (r.lock_memory && kShadowMemory)
    throw std::runtime_error(
        fmt::format("{}: lock_memory cannot be used by a build with AddressSanitizer or "
                    "ThreadSanitizer (mlockall would lock their terabytes of shadow memory); "
                    "remove it, or use a build without them",
                    where));
  if (r.lock_memory && ::mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    const int e = errno;
    throw std::runtime_error(
        fmt::format("{}: lock_memory refused ({}): {}", where, std::strerror(e), kHowToGrant));
  }
}

std::string describe(const RealtimeScheduling& r) {
  std::string s = r.priority != 0 ? fmt::format("SCHED_FIFO priority {}", r.priority)
                                  : std::string("the default scheduler");
  if (r.lock_memory) s += ", memory locked";
  return s;
}

}  // namespace tactile::util
