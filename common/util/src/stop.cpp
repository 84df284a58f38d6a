#include "tactile/util/stop.hpp"

#include <unistd.h>

#include <csignal>
#include <cstdlib>

namespace tactile::util {
namespace {

volatile std::sig_atomic_t g_stop = 0;
volatile std::sig_atomic_t g_signal = 0;

void on_signal(int sig) {
  // The second signal: the program did not finish stopping, so it ends now (make, ninja, docker).
  if (g_signal != 0) _exit(128 + sig);
  g_signal = sig;
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
int stop_signal() {
  return g_signal;
}
int interrupted_exit_status() {
  return g_signal != 0 ? 128 + g_signal : 0;
}

}  // namespace tactile::util
