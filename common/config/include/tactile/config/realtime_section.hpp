#pragma once

#include <string>
#include <vector>

#include "tactile/config/yaml.hpp"
#include "tactile/util/realtime.hpp"

namespace tactile::config {

// The `realtime` section of a program's configuration:
//   realtime: {priority: 10, lock_memory: true}
// priority 1 to 98 (SCHED_FIFO; absent: the default scheduler), lock_memory a boolean (default
// false). Throws ConfigError naming file, line, key and value; unknown keys go to `warnings` as
// the caller's own do.
util::RealtimeScheduling parse_realtime_section(const Node& section,
                                                std::vector<std::string>* warnings);

}  // namespace tactile::config
