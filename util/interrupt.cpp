#include "util/interrupt.h"

#include <atomic>

namespace dynsky {

namespace {
std::atomic<bool> allowed{false}, requested{false}, stopped{false};
std::atomic<const char*> action{""};
static_assert(std::atomic<bool>::is_always_lock_free, "read and set from a signal handler");
static_assert(std::atomic<const char*>::is_always_lock_free, "read from a signal handler");
}  // namespace

bool graceful_stop_allowed() noexcept { return allowed.load(); }
const char* graceful_stop_action() noexcept { return action.load(); }
bool request_stop() noexcept { return requested.exchange(true); }
bool stop_requested() noexcept { return requested.load(); }
void note_stopped_early() noexcept { stopped.store(true); }
bool stopped_early() noexcept { return stopped.load(); }

AllowGracefulStop::AllowGracefulStop(const char* what) {
    action.store(what);
    allowed.store(true);
}
AllowGracefulStop::~AllowGracefulStop() {
    allowed.store(false);
    action.store("");
}

}  // namespace dynsky
