#include "tests/test_support.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>

namespace dynsky::test {

namespace fs = std::filesystem;

bool small_run() {
    const char* v = std::getenv("DYNSKY_TEST_SMALL");
    return v && *v && std::string(v) != "0";
}

bool shared_available() { return fs::exists(fs::path(DYNSKY_SHARED_DIR) / "CONVENTIONS.md"); }

std::string shared_path(const std::string& relative) {
    if (!shared_available()) return "";
    return fs::weakly_canonical(fs::path(DYNSKY_SHARED_DIR) / relative).string();
}

std::string temp_dir(const std::string& tag) {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = info ? std::string(info->test_suite_name()) + "." + info->name() : tag;
    fs::path dir = fs::temp_directory_path() / ("dynsky-test-" + tag + "-" + name + "-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir.string();
}

CommandResult run_command(const std::string& command_line) {
    CommandResult result;
    std::string full = command_line + " 2>&1";
    FILE* pipe = ::popen(full.c_str(), "r");
    if (!pipe) return result;
    std::array<char, 4096> buffer;
    size_t n;
    while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0) result.output.append(buffer.data(), n);
    int status = ::pclose(pipe);
    result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    // In the sanitizer build a report exits 1 (ASan, UBSan) or 23 (LeakSanitizer), which a test
    // expecting a refusal would take for one: any report in a command's output fails the test.
    for (const char* report : {"ERROR: AddressSanitizer", "ERROR: LeakSanitizer", "runtime error: "})
        if (result.output.find(report) != std::string::npos)
            ADD_FAILURE() << "sanitizer report (" << report << ") from: " << command_line << "\n" << result.output;
    return result;
}

std::string read_text(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

}  // namespace dynsky::test
