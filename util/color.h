// Transfer functions and display mapping.
#pragma once

#include "util/math.h"

namespace dynsky {

// IEC 61966-2-1 sRGB transfer function, per channel value in [0, 1].
inline float srgb_to_linear(float v) { return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f); }
inline float linear_to_srgb(float v) {
    v = clamp(v, 0.0f, 1.0f);
    return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

// Display mapping for previews: exposure, then ACES-fitted filmic curve (Narkowicz 2015), then sRGB.
inline float tonemap_aces(float x) {
    const float a = 2.51f, b = 0.03f, c = 2.43f, d = 0.59f, e = 0.14f;
    x = std::max(0.0f, x);
    return clamp((x * (a * x + b)) / (x * (c * x + d) + e), 0.0f, 1.0f);
}

}  // namespace dynsky
