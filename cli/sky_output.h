// What the sky-writing commands (`sky clear`, `sky latlong`, `sky import`) share: checks of
// output names and the tone-mapped PNG preview.
#pragma once

#include <string>

#include "util/image.h"

namespace dynsky::cli {

// Throws naming path unless it ends in ext (".exr", ".png"); option names the flag in the message.
void check_extension(const std::string& option, const std::string& path, const std::string& ext);

// Writes a display preview of linear radiance: exposed so the median sky pixel lands at 18% grey
// (a clear sky is ~5-30 W m^-2 sr^-1, far above the display range), then ACES and sRGB. Prints
// the path and the exposure.
void write_preview(const std::string& path, const Image& linear, bool say = true);

}  // namespace dynsky::cli
