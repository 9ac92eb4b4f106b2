// Another program run to completion (ffmpeg for the videos): started directly (no shell), its
// standard input from /dev/null, waited for. While it runs it is the active child: an interrupt of
// dynsky (cli/main.cpp: SIGINT, SIGTERM, SIGHUP) stops it too, so no orphan goes on writing.
// (std::system ignored SIGINT in dynsky while the child ran: a kill -INT of dynsky did nothing, and
// a SIGTERM left ffmpeg running with its temporary.)
#pragma once

#include <string>
#include <vector>

namespace dynsky {

struct ChildResult {
    bool started = false;  // false: it could not be run (spawn_error says why: ENOENT, not installed)
    int spawn_error = 0;
    bool exited = false;  // true: it exited with exit_code; false: a signal ended it
    int exit_code = -1;
};

// Runs argv[0] (looked up on PATH) with argv[1..]; returns when it has ended. With `output`, what
// it writes to stdout and stderr is collected there instead of reaching the terminal.
ChildResult run_program(const std::vector<std::string>& argv, std::string* output = nullptr);

// Why a program run with `output` collected failed, in one line: "not started: REASON" when it could
// not be run, else the last line it wrote that says something (Python's "OSError: [Errno 28] No
// space left on device", not its traceback).
std::string child_failure_reason(const ChildResult& result, std::string output);

// Async-signal-safe: sends SIGTERM to the active child, if any (called by the interrupt handler).
void stop_active_child() noexcept;

}  // namespace dynsky
