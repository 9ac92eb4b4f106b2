#include "util/interrupt.h"

#include <atomic>

namespace dynsky {

namespace {
std::atomic<bool> allowed{false}, requested{false}, stopped{false};
static_assert(std::atomic<bool>::is_always_lock_free, "read and set from a signal handler");
}  // namespace

bool graceful_stop_allowed() noexcept { return allowed.load(); }
bool request_stop() noexcept { return requested.exchange(true); }
bool stop_requested() noexcept { return requested.load(); }
void note_stopped_early() noexcept { stopped.store(true); }
bool stopped_early() noexcept { return stopped.load(); }

AllowGracefulStop::AllowGracefulStop() { allowed.store(true); }
AllowGracefulStop::~AllowGracefulStop() { allowed.store(false); }

}  // namespace dynsky
