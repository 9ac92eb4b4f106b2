// Line charts of CSV files with matplotlib (Debian's python3-matplotlib through /usr/bin/python3).
#pragma once

#include <string>

namespace dynsky {

// First column = x, every other column a line; a column named "boundary" (0/1) shades those x
// instead of being drawn. Written through a temporary name (util/atomic_file.h); if matplotlib
// fails, throws dynsky::Error naming png (the data stays in the CSV) and writes nothing.
void make_line_chart(const std::string& csv, const std::string& png, const std::string& title,
                     const std::string& xlabel, const std::string& ylabel, bool logy);

}  // namespace dynsky
