#include "haptel/core/stop_signals.hpp"

#include <csignal>

namespace haptel {
namespace {

std::atomic<bool> g_stop{false};
volatile std::sig_atomic_t g_signal = 0;
static_assert(std::atomic<bool>::is_always_lock_free, "the stop flag is set in a signal handler");

void OnStopSignal(int signal) {
  g_signal = signal;
  g_stop.store(true);
}

}  // namespace

const std::atomic<bool>& InstallStopSignals() {
  struct sigaction action {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;  // reads and writes in progress go on; the loops poll the flag
  for (const int signal : {SIGINT, SIGTERM, SIGHUP}) sigaction(signal, &action, nullptr);
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  sigemptyset(&ignore.sa_mask);
  for (const int signal : {SIGUSR1, SIGUSR2, SIGPIPE, SIGXFSZ}) sigaction(signal, &ignore, nullptr);
  return g_stop;
}

int StopSignal() { return g_signal; }

}  // namespace haptel
