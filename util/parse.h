// Parsing option values: lists and numbers with messages that name the option.
#pragma once

#include <string>
#include <vector>

namespace dynsky {

// "1,2,3,6" -> {1, 2, 3, 6}, sorted, duplicates removed, each >= 1. Throws dynsky::Error naming
// `option` and the bad item.
std::vector<int> parse_int_list(const std::string& text, const std::string& option);

// "1280x720" -> 1280, 720 (each 1..16384). Throws dynsky::Error naming --res.
void parse_frame_size(const std::string& text, int* w, int* h);

}  // namespace dynsky
