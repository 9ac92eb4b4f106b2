// Exposure: how dynsky chooses the brightness of a display image (PNG previews, frames, skies).
//
// One module for every policy, each named for what it keeps fixed. All return stops (EV): the
// display image is tonemap_to_display(linear, ev) (util/image.h), i.e. radiance times 2^ev.
//   log-average  the image's log-average luminance lands at middle grey (0.18): photographic
//                auto exposure (Reinhard et al. 2002). Renders and predicted skies.
//   median       the median non-zero luminance lands at 0.18: robust to a sun of a few pixels,
//                for sky previews (a clear sky is ~5-30 W m^-2 sr^-1, far above display range).
//   irradiance   a grey (albedo 0.4) horizontal surface under irradiance E shows middle grey:
//                one fixed exposure for a whole animation from the sky at t = 0 (no flicker).
#pragma once

#include <string>

#include "util/image.h"
#include "util/math.h"

namespace dynsky {

// Log-average luminance to 0.18. 0 for a black image or one with fewer than 3 channels.
float exposure_log_average(const Image& linear);

// Median of the positive luminances to middle_grey (0.18; procedural previews use 0.2). 0 when no
// pixel is positive.
float exposure_median(const Image& linear, float middle_grey = 0.18f);

// 0.4 * E / pi (the radiance of a grey horizontal surface) to 0.18. 0 for E <= 0.
float exposure_for_irradiance(const Color& irradiance);

// Writes a display preview of a sky's linear radiance (exposure_median, then ACES and sRGB), and
// with say prints the path and the exposure.
void write_display_preview(const std::string& path, const Image& linear, bool say = true);

}  // namespace dynsky
