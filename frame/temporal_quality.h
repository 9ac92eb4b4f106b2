// Temporal quality of an animation folder (`dynsky temporal`): the frame-to-frame luminance change,
// for pairs across a medium-step boundary and within intervals (popping), and Monte Carlo flicker
// (compare animations rendered with and without a seed per frame). Writes temporal.csv and
// temporal.png into the folder and prints the means.
#pragma once

#include <string>

namespace dynsky {

void analyse_temporal_quality(const std::string& folder);

}  // namespace dynsky
