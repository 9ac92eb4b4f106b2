#include "util/allocation.h"

#include <mutex>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace dynsky {

void keep_large_allocations() {
    static std::once_flag once;
    std::call_once(once, [] {
#if defined(__GLIBC__)
        mallopt(M_MMAP_THRESHOLD, 256 << 20);
        mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
    });
}

}  // namespace dynsky
