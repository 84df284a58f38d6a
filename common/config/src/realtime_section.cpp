#include "tactile/config/realtime_section.hpp"

#include <string>

namespace tactile::config {

util::RealtimeScheduling parse_realtime_section(const Node& section) {
  if (!section.is_map())
    section.fail("must be a mapping such as {priority: 10, lock_memory: true}, is " +
                 section.text());
  section.refuse_unknown_keys({"priority", "lock_memory"});
  util::RealtimeScheduling r;
  if (const auto priority = section.find("priority")) {
    const std::int64_t p = priority->as_int();
    if (p < util::kMinRealtimePriority || p > util::kMaxRealtimePriority)
      priority->fail("must be a SCHED_FIFO priority from " +
                     std::to_string(util::kMinRealtimePriority) + " to " +
                     std::to_string(util::kMaxRealtimePriority) + ", is " + priority->text());
    r.priority = static_cast<int>(p);
  }
  r.lock_memory = section.get("lock_memory", false);
  return r;
}

}  // namespace tactile::config
