#pragma once

#include <atomic>

namespace lumistage {

// Stopping in order on SIGINT, SIGTERM and SIGHUP (Ctrl-C, a service manager's stop, a closed
// terminal). The first of them asks the program to stop: it finishes what it writes (a take, a
// recording of the view, a video), stops the processes it started and removes its temporary
// files, as when it ends by itself. A second one, for a program that does not stop, ends it at
// once, as the signal would have without a handler. A signal that the program was started
// ignoring (SIGHUP under nohup) stays ignored.

// Installs the handlers (the first call; later calls only return the flag) and returns the flag
// that the first signal sets. The program may set it itself to stop the same way.
std::atomic<bool>& stopOnSignals();

// The signal that asked to stop; 0 while none has.
int stopSignal();

// The signal's name, for messages: "SIGINT (Ctrl-C)", "SIGTERM", "SIGHUP".
const char* stopSignalName(int signal);

// A descriptor that becomes readable when a signal asks to stop, for an event loop (Qt's
// QSocketNotifier); -1 before stopOnSignals(). Not inherited by programs started with exec.
int stopSignalDescriptor();

}  // namespace lumistage
