#include "tactile/util/stop.hpp"

#include <unistd.h>

#include <csignal>
#include <cstdlib>

namespace tactile::util {
namespace {

volatile std::sig_atomic_t g_stop = 0;

void on_signal(int) {
  if (g_stop) _exit(130);
  g_stop = 1;
}

}  // namespace

void install_stop_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  // A peer that vanished must not kill us through a write on a closed pipe.
  signal(SIGPIPE, SIG_IGN);
}

bool stop_requested() {
  return g_stop != 0;
}
void request_stop() {
  g_stop = 1;
}

}  // namespace tactile::util
