#include "util/frame_names.h"

#include <cstdio>
#include <filesystem>

namespace dynsky {

std::string numbered_name(const std::string& prefix, int k, const std::string& ext) {
    char digits[32];
    std::snprintf(digits, sizeof digits, "_%04d", k);
    return prefix + digits + ext;
}

std::string numbered_path(const std::string& folder, const std::string& prefix, int k, const std::string& ext) {
    return (std::filesystem::path(folder) / numbered_name(prefix, k, ext)).string();
}

std::string numbered_pattern(const std::string& prefix, const std::string& ext) { return prefix + "_%04d" + ext; }

}  // namespace dynsky
