#pragma once

namespace tactile::util {

// Installs SIGINT and SIGTERM handlers: the first signal sets a flag that loops poll
// (stop_requested()) to finish cleanly; a second one, while the program is still stopping, ends it
// at once with 128 + its number (130 for SIGINT, 143 for SIGTERM), the convention of make, ninja
// and docker (docs/reliability.md#signals). Async-signal-safe: the handler only stores a number or
// calls _exit.
void install_stop_handlers();
bool stop_requested();
// Asks for a stop as a signal would, without a signal: interrupted_exit_status() stays 0.
void request_stop();
// The signal that asked for the stop (SIGINT or SIGTERM), or 0 when none came.
int stop_signal();
// The exit status of work a signal cut short before it was done: 128 + stop_signal(), or 0 when no
// signal came.
int interrupted_exit_status();

}  // namespace tactile::util
