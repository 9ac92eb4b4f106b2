#include "util/frame_names.h"

#include <cstdio>
#include <filesystem>

namespace dynsky {

namespace {

// Digits of the set's largest number, at least four.
int name_width(int count) {
    int width = 4;
    for (long largest = long(count) - 1, limit = 10000; largest >= limit; limit *= 10) ++width;
    return width;
}

}  // namespace

std::string numbered_name(const std::string& prefix, int k, const std::string& ext, int count) {
    char digits[32];
    std::snprintf(digits, sizeof digits, "_%0*d", name_width(count), k);
    return prefix + digits + ext;
}

std::string numbered_path(const std::string& folder, const std::string& prefix, int k, const std::string& ext,
                          int count) {
    return (std::filesystem::path(folder) / numbered_name(prefix, k, ext, count)).string();
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

std::string numbered_pattern(const std::string& prefix, const std::string& ext, int count) {
    return prefix + "_%0" + std::to_string(name_width(count)) + "d" + ext;
}

bool natural_less(const std::string& a, const std::string& b) {
    auto digit = [](char c) { return c >= '0' && c <= '9'; };
    size_t i = 0, j = 0;
    while (i < a.size() && j < b.size()) {
        if (digit(a[i]) && digit(b[j])) {
            size_t ei = i, ej = j;
            while (ei < a.size() && digit(a[ei])) ++ei;
            while (ej < b.size() && digit(b[ej])) ++ej;
            size_t zi = i, zj = j;  // past the leading zeros
            while (zi + 1 < ei && a[zi] == '0') ++zi;
            while (zj + 1 < ej && b[zj] == '0') ++zj;
            if (ei - zi != ej - zj) return ei - zi < ej - zj;  // fewer significant digits: smaller
            if (const int c = a.compare(zi, ei - zi, b, zj, ej - zj); c != 0) return c < 0;
            if (ei - i != ej - j) return ei - i > ej - j;  // the same number: more zeros first
            i = ei, j = ej;
        } else {
            if (a[i] != b[j]) return static_cast<unsigned char>(a[i]) < static_cast<unsigned char>(b[j]);
            ++i, ++j;
        }
    }
    return a.size() - i < b.size() - j;
}

}  // namespace dynsky
