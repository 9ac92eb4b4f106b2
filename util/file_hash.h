// What a file is, for settings that must change when an input does: "NAME (BYTES bytes, fnv1a
// HASH)". A changed or replaced file counts, a moved one does not. Resumable jobs (animate's frames,
// a sequence import's skies) compare these to keep only work made from the same inputs.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace dynsky {

// FNV-1a 64 of n bytes, continuing from h.
inline constexpr uint64_t kFnvOffset = 0xcbf29ce484222325ull;
uint64_t fnv1a(const void* data, size_t n, uint64_t h = kFnvOffset);
// 16 lower-case hex digits.
std::string hex64(uint64_t h);
// hex64 of the FNV-1a 64 of a text (a canonical settings text, recorded as the key of resumable work).
std::string hash_text(const std::string& text);
// "NAME (BYTES bytes, fnv1a HASH)" of the file's whole contents (NAME: its file name only).
std::string describe_file(const std::string& path);

}  // namespace dynsky
