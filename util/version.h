// What built this program, as `dynsky --version` says it: "dynsky 0.1.0 (commit abc1234)" (the
// commit left out outside git). Every image written carries it as its Software field
// (util/image.h write_image), so the frames of a farm with mixed builds tell which made them.
#pragma once

#include <string>

namespace dynsky {

std::string dynsky_version();

}  // namespace dynsky
