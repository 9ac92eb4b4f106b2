#include "util/child_process.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstring>
#include <cctype>
#include <cerrno>
#include <string>

extern char** environ;

namespace dynsky {

namespace {
std::atomic<pid_t> g_child{0};
}  // namespace

void stop_active_child() noexcept {
    const pid_t child = g_child.load();
    if (child > 0) ::kill(child, SIGTERM);
}

std::string child_failure_reason(const ChildResult& result, std::string output) {
    if (!result.started) return "not started: " + std::string(std::strerror(result.spawn_error));
    while (!output.empty() && std::isspace(static_cast<unsigned char>(output.back()))) output.pop_back();
    const size_t newline = output.rfind('\n');
    return newline == std::string::npos ? output : output.substr(newline + 1);
}

ChildResult run_program(const std::vector<std::string>& argv, std::string* output) {
    ChildResult result;
    if (argv.empty()) {
        result.spawn_error = EINVAL;
        return result;
    }
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    int pipe_fds[2] = {-1, -1};
    if (output) {
        if (::pipe2(pipe_fds, O_CLOEXEC) != 0) {
            result.spawn_error = errno;
            posix_spawn_file_actions_destroy(&actions);
            return result;
        }
        posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], 1);
        posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], 2);
    }
    pid_t pid = 0;
    const int err = ::posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (output) ::close(pipe_fds[1]);
    if (err != 0) {
        if (output) ::close(pipe_fds[0]);
        result.spawn_error = err;
        return result;
    }
    result.started = true;
    g_child = pid;
    if (output) {
        char buffer[4096];
        for (;;) {
            const ssize_t got = ::read(pipe_fds[0], buffer, sizeof buffer);
            if (got > 0) output->append(buffer, size_t(got));
            else if (got == 0 || errno != EINTR) break;
        }
        ::close(pipe_fds[0]);
    }
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {}
    g_child = 0;
    if (WIFEXITED(status)) result.exited = true, result.exit_code = WEXITSTATUS(status);
    return result;
}

}  // namespace dynsky
