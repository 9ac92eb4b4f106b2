// A cloud mask as a job, as `dynsky sky mask` runs it: the red/blue rule (sky/cloud_mask.h) on a
// photograph's camera-encoded values, or on a canonical sky encoded as a camera would, inside the
// sky and outside what is not sky, written as a PNG (255 cloud, 100 clear, 0 not sky: WSISEG's
// coding).
//
// Parameters (defaults as `sky mask` gives them):
//   input         a photograph (JPEG/PNG/...) or a canonical sky (.exr) (required)
//   out           the mask, .png (required)
//   params        the rule and its threshold (`sky mask`: rb 0.75, kWsisegBestRedBlueThreshold)
//   preset        "" or a camera preset: its sky circle and not-sky mask (its mask file beside the
//                 photo, else its own obstruction geometry)
//   circle        the sky circle in photo pixels (none: the preset's, else found)
//   mask          a photo-sized not-sky mask, black = not sky ("")
//   whole_image   classify every pixel of a photograph (false)
#pragma once

#include <optional>
#include <string>

#include "sky/cloud_mask.h"
#include "sky/photo_import.h"

namespace dynsky {

struct CloudMaskJob {
    std::string input, out, preset, mask;
    CloudMaskParams params;
    std::optional<SkyCircle> circle;
    bool whole_image = false;
};

// Writes the mask and prints its cloud fraction. Throws dynsky::Error naming the file and the
// problem (a black sky, a photograph that is not RGB, NaN pixels, another camera's size, ...).
void run_cloud_mask(const CloudMaskJob& job);

}  // namespace dynsky
