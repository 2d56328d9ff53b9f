#include "stop_signal.h"

#include <atomic>
#include <csignal>

namespace upd::app {

namespace {

std::atomic<int> g_signal{0};
static_assert(std::atomic<int>::is_always_lock_free, "read and written in a signal handler");

void onStopSignal(int signo) {
  g_signal = signo;
  std::signal(signo, SIG_DFL);  // a second Ctrl-C ends the process
}

}  // namespace

StopOnSignal::StopOnSignal() {
  g_signal = 0;
  std::signal(SIGINT, onStopSignal);
  std::signal(SIGTERM, onStopSignal);
}

StopOnSignal::~StopOnSignal() {
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
}

bool stopRequested() { return g_signal != 0; }

int stopSignal() { return g_signal; }

const char* stopSignalName(int signo) {
  switch (signo) {
    case SIGINT: return "SIGINT";
    case SIGTERM: return "SIGTERM";
    default: return "a signal";
  }
}

}  // namespace upd::app
