#pragma once
/// @file SIGINT, SIGTERM and SIGHUP as a request to stop: installed first
/// thing in a program that must end cleanly (record what it measured, stop
/// motors), so that a signal arriving while it still reads its files is not
/// fatal but seen by the loop as soon as it starts.
#include <atomic>

namespace haptel {

/// Installs the handlers (idempotent) and returns the flag they set. The
/// flag is lock-free and may be read from any thread, the servo loop included.
/// SIGUSR1, SIGUSR2 and SIGPIPE are ignored: a program documents what SIGUSR1
/// does where it does something (the link fault's cut, which installs its
/// own handler after this), and no other signal of theirs ends a run
/// unrecorded; a peer gone from a socket is an error the writer sees.
/// SIGXFSZ is ignored too: a file grown past the size limit (ulimit -f)
/// fails its write with EFBIG, which the writer reports like a full disk,
/// instead of the signal killing the program and the run with it.
const std::atomic<bool>& InstallStopSignals();

/// The signal that set the flag (0 while none has).
int StopSignal();

}  // namespace haptel
