#pragma once

namespace tactile::util {

// Installs SIGINT and SIGTERM handlers that set a flag; loops poll stop_requested() and
// finish cleanly. A second signal while stopping ends the process at once (exit 130).
void install_stop_handlers();
bool stop_requested();
void request_stop();

}  // namespace tactile::util
