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
