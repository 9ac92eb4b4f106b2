// Running helper programs (ffmpeg, /usr/bin/python3 with matplotlib) through /bin/sh.
#pragma once

#include <string>

namespace dynsky {

// s as one word for /bin/sh (single quotes; a quote inside becomes '\'').
std::string shell_quote(const std::string& s);

}  // namespace dynsky
