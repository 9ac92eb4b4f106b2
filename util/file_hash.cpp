#include "util/file_hash.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <vector>

namespace dynsky {

uint64_t fnv1a(const void* data, size_t n, uint64_t h) {
    constexpr uint64_t kFnvPrime = 0x100000001b3ull;
    const auto* bytes = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < n; ++i) h = (h ^ uint64_t(bytes[i])) * kFnvPrime;
    return h;
}

std::string hex64(uint64_t h) {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
    return buf;
}

std::string hash_text(const std::string& text) { return hex64(fnv1a(text.data(), text.size())); }

std::string describe_file(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    std::vector<char> buf(1 << 16);
    uint64_t h = kFnvOffset, size = 0;
    while (f) {
        f.read(buf.data(), std::streamsize(buf.size()));
        const size_t n = size_t(f.gcount());
        h = fnv1a(buf.data(), n, h), size += n;
    }
    return std::filesystem::path(path).filename().string() + " (" + std::to_string(size) + " bytes, fnv1a " + hex64(h) +
           ")";
}

}  // namespace dynsky
