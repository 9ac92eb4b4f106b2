// A stop asked for by an interrupt (Ctrl-C, SIGTERM, SIGHUP) that long work takes at a clean point
// instead of losing what it has done: `render` finishes its round of samples and writes the image
// of the samples taken, `sky evaluate` the report of the frames scored. Only while a command allows it (AllowGracefulStop); elsewhere, and at the
// second interrupt, the program stops at once (cli/main.cpp).
#pragma once

namespace dynsky {

// True when work in progress can stop at a clean point; set by AllowGracefulStop.
bool graceful_stop_allowed() noexcept;
// What the work does when asked to stop (the interrupt handler says it); "" when not allowed.
const char* graceful_stop_action() noexcept;
// Async-signal-safe (a lock-free atomic): the interrupt handler's request; returns whether one
// was made before (two interrupts at once: only one takes the graceful way).
bool request_stop() noexcept;
bool stop_requested() noexcept;
// Work that stopped early at a request says so (the program then exits with kInterrupted); work
// that finished anyway does not.
void note_stopped_early() noexcept;
bool stopped_early() noexcept;

// Allows a graceful stop while in scope; `action` (a string literal) says what the work does then,
// e.g. "finishing this round of samples, then writing the image of the samples taken".
class AllowGracefulStop {
  public:
    explicit AllowGracefulStop(const char* action);
    ~AllowGracefulStop();
    AllowGracefulStop(const AllowGracefulStop&) = delete;
    AllowGracefulStop& operator=(const AllowGracefulStop&) = delete;
};

}  // namespace dynsky
