#pragma once

#include <string>
#include <vector>

#include "tactile/config/yaml.hpp"
#include "tactile/util/realtime.hpp"

namespace tactile::config {

// The `realtime` section of a program's configuration:
//   realtime: {priority: 10, lock_memory: true}
// priority 1 to 98 (SCHED_FIFO; absent: the default scheduler), lock_memory a boolean (default
// false). Throws ConfigError naming file, line, key and value, and for an unknown key.
util::RealtimeScheduling parse_realtime_section(const Node& section);

}  // namespace tactile::config
