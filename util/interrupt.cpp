#include "util/interrupt.h"

#include <atomic>

namespace dynsky {

namespace {
std::atomic<bool> allowed{false}, requested{false};
static_assert(std::atomic<bool>::is_always_lock_free, "read and set from a signal handler");
}  // namespace

bool graceful_stop_allowed() noexcept { return allowed.load(); }
void request_stop() noexcept { requested.store(true); }
bool stop_requested() noexcept { return requested.load(); }

AllowGracefulStop::AllowGracefulStop() { allowed.store(true); }
AllowGracefulStop::~AllowGracefulStop() { allowed.store(false); }

}  // namespace dynsky
