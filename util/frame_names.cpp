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

std::optional<int> numbered_index(const std::string& name, const std::string& prefix) {
    const std::filesystem::path p(name);
    const std::string stem = p.stem().string(), start = prefix + "_";
    if (stem.rfind(start, 0) != 0) return std::nullopt;
    const std::string digits = stem.substr(start.size());
    if (digits.size() < 4 || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos)
        return std::nullopt;
    return std::stoi(digits);
}

std::string numbered_pattern(const std::string& prefix, const std::string& ext) { return prefix + "_%04d" + ext; }

}  // namespace dynsky
