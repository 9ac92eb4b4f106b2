// Where dynsky's shipped data lives (Hosek-Wilkie tables, scenes, networks).
#pragma once

#include <string>

namespace dynsky {

// $DYNSKY_DATA if set, else the source tree recorded at build time. Throws naming the
// relative path if the file is missing.
std::string data_path(const std::string& relative);

}  // namespace dynsky
