#include "util/version.h"

#include "dynsky_commit.h"  // generated at every build (cmake/commit_header.cmake)

namespace dynsky {

std::string dynsky_version() {
    const std::string commit = DYNSKY_COMMIT;
    return std::string("dynsky ") + DYNSKY_VERSION + (commit.empty() ? "" : " (commit " + commit + ")");
}

}  // namespace dynsky
