// The streaming floor that per-frame distribution rebuilds are measured against: one parallel pass
// over the sky's bytes that reads RGB and writes one float (luminance) per pixel, the least any
// rebuild must do. Compiled with the same flags as EnvLight's rebuild (renderer/CMakeLists.txt), so
// the ratio compares code, not compiler settings. Used by bench/ and `dynsky bench sampling`.
#pragma once

#include <vector>

#include "sky/sky_image.h"

namespace dynsky {

// Runs the pass once and returns its wall time in seconds (out is resized to N x N).
double time_streaming_floor(const SkyImage& sky, std::vector<float>* out);

}  // namespace dynsky
