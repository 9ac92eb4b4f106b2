// Parsing option values: lists and numbers with messages that name the option; and numbers
// written into messages.
#pragma once

#include <string>
#include <vector>

namespace dynsky {

// A whole number in [min, max] (digits only, no sign), or dynsky::Error "WHAT: 'TEXT' is not a whole
// number in MIN..MAX" (never std::stoi's bare "stoi" for an over-long number).
long long parse_whole_number(const std::string& text, const std::string& what, long long min, long long max);

// Any 64-bit seed, 0..18446744073709551615 (digits only), or dynsky::Error "WHAT: 'TEXT' is not
// a whole number in 0..18446744073709551615": every seed a frame of `animate --seed-per-frame`
// uses (seed + k x 0x9E3779B97F4A7C15, wrapping) can be given again.
unsigned long long parse_seed(const std::string& text, const std::string& what);

// "1,2,3,6" -> {1, 2, 3, 6}, sorted, duplicates removed, each >= 1. Throws dynsky::Error naming
// `option` and the bad item.
std::vector<int> parse_int_list(const std::string& text, const std::string& option);

// "1280x720" -> 1280, 720 (each 1..16384). Throws dynsky::Error naming `option`.
void parse_frame_size(const std::string& text, int* w, int* h, const std::string& option = "--res");

// A number for a message, printf's %g with `significant` digits: 1e+35, 0.5, 128.
std::string number_text(double v, int significant = 6);

// A URI's %XX escapes decoded (as tinygltf decodes a glTF's buffer and image URIs before opening
// them); everything else as written.
std::string percent_decoded(const std::string& uri);

}  // namespace dynsky
