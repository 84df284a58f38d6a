#pragma once

#include <string>

namespace tactile::util {

// Real-time scheduling for a program's frame path, the `realtime` section of sensor_node's and
// hand_node's configuration files (docs/deployment.md, "Real-time scheduling").
struct RealtimeScheduling {
  int priority = 0;          // SCHED_FIFO priority, 1 to 98; 0: the default scheduler
  bool lock_memory = false;  // mlockall: no page of the program is ever paged out
};

inline constexpr int kMinRealtimePriority = 1;
// 99 is left to the kernel's own threads (watchdogs, migration).
inline constexpr int kMaxRealtimePriority = 98;

// Applies it to the calling thread and, through inheritance, to every thread and process it
// starts afterwards: call it before ZeroMQ's context, Aravis's stream threads or any other thread
// exists. `where` names the setting in the error (e.g. "hand.yaml: realtime"). Throws
// std::runtime_error with the cause and the ways to grant the privilege when the kernel refuses,
// and for lock_memory in a build with AddressSanitizer or ThreadSanitizer.
void apply_realtime_scheduling(const RealtimeScheduling& r, const std::string& where);

// "SCHED_FIFO priority 10, memory locked", or "the default scheduler": for a start-up log line.
std::string describe(const RealtimeScheduling& r);

}  // namespace tactile::util
