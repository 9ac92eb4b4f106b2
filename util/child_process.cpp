#include "util/child_process.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>

extern char** environ;

namespace dynsky {

namespace {
std::atomic<pid_t> g_child{0};
}  // namespace

void stop_active_child() noexcept {
    const pid_t child = g_child.load();
    if (child > 0) ::kill(child, SIGTERM);
}

ChildResult run_program(const std::vector<std::string>& argv) {
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
    pid_t pid = 0;
    const int err = ::posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (err != 0) {
        result.spawn_error = err;
        return result;
    }
    result.started = true;
    g_child = pid;
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {}
    g_child = 0;
    if (WIFEXITED(status)) result.exited = true, result.exit_code = WEXITSTATUS(status);
    return result;
}

}  // namespace dynsky
