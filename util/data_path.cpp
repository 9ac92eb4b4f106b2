#include "util/data_path.h"

#include <cstdlib>
#include <filesystem>

#include "util/error.h"

namespace dynsky {

std::string data_path(const std::string& relative) {
    namespace fs = std::filesystem;
    const char* env = std::getenv("DYNSKY_DATA");
    fs::path root = env && *env ? fs::path(env) : fs::path(DYNSKY_DATA_DIR);
    fs::path p = root / relative;
    if (!fs::exists(p))
        throw Error(p.string() + ": dynsky data file not found (set DYNSKY_DATA to the dynsky source folder)");
    return p.string();
}

}  // namespace dynsky
