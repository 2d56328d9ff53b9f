// Ctrl-C (SIGINT) and SIGTERM as a request to stop a frame loop: the loop finishes its current
// frame, the command writes what it has, and the process exits normally. A second signal ends
// the process at once (the default action is restored after the first).
#pragma once

namespace upd::app {

/// While an instance lives, SIGINT and SIGTERM set the flag that stopRequested() reads instead
/// of ending the process; its destructor restores the default actions. One at a time.
class StopOnSignal {
 public:
  StopOnSignal();
  ~StopOnSignal();
  StopOnSignal(const StopOnSignal&) = delete;
  StopOnSignal& operator=(const StopOnSignal&) = delete;
};

/// A SIGINT or SIGTERM arrived since the live StopOnSignal was made.
bool stopRequested();

/// The signal that asked to stop (SIGINT or SIGTERM), 0 when none did.
int stopSignal();

/// "SIGINT", "SIGTERM" or "a signal".
const char* stopSignalName(int signo);

}  // namespace upd::app
