// Helpers shared by the test programs: where ../shared is, temporary folders, running dynsky.
#pragma once

#include <string>

namespace dynsky::test {

// Absolute path of a file under ../shared, or "" if the shared folder is absent.
std::string shared_path(const std::string& relative);
// Skip the calling test (GTEST_SKIP) when shared data is absent: use the macro below.
bool shared_available();

// A fresh, empty temporary directory unique to this test (removed by the caller or left in /tmp).
std::string temp_dir(const std::string& tag);

// The whole of a file (bytes as they are; "" if it cannot be read).
std::string read_text(const std::string& path);

// True when DYNSKY_TEST_SMALL is set to anything but "" or "0": the ASan + UBSan run
// (scripts/test_sanitizers.sh, several times slower) asks long tests for a smaller size that
// checks the same property (fewer steps, pixels or frames). docs/testing.md.
bool small_run();
// `full` normally, `small` under DYNSKY_TEST_SMALL.
template <typename T>
T run_size(T full, T small) {
    return small_run() ? small : full;
}

struct CommandResult {
    int exit_code = -1;
    std::string output;  // stdout and stderr together
};
// Runs a shell command line, capturing its output.
CommandResult run_command(const std::string& command_line);

}  // namespace dynsky::test

#define DYNSKY_REQUIRE_SHARED()                                                     \
    do {                                                                            \
        if (!dynsky::test::shared_available()) GTEST_SKIP() << "../shared missing"; \
    } while (0)
