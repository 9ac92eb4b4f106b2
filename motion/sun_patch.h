// The sun, taken out of a sky before its clouds are moved and put back afterwards (glossary: "sun
// patch"). Moving clouds must not move, smear or drop the sun: its few bright pixels are not
// clouds, and the networks' [0, 1] form cannot hold them.
//
// Two forms, one for each place the cut happens:
//   SunPatch (remove_sun / insert_sun)  the timeline's: the pixels near the sun's direction that are
//        far brighter than their surroundings, as an excess over the inpainted sky, re-inserted at
//        the sun's direction of every frame (so it can follow the clock).
//   fill_saturated_pixels / restore_pixels  the networks': every pixel the [0, 1] map clips (sun,
//        brightest aureole) filled before the first step, the input's radiance restored after.
#pragma once

#include <opencv2/core.hpp>

#include <vector>

#include "sky/sky_image.h"

namespace dynsky {

// The sun's pixels cut out of a sky (relative to the sun's pixel) with their excess radiance.
struct SunPatch {
    std::vector<int> di, dj;
    std::vector<Color> excess;
    bool empty() const { return di.empty(); }
};

// Finds the sun near sky.sun_direction (pixels within 1 degree + 2 px brighter than 20x the
// surrounding median), inpaints them (cv::inpaint, per channel on log radiance) and returns the
// cut-out. No sun direction, or no bright pixels there: an empty patch and the sky unchanged.
SunPatch remove_sun(SkyImage* sky);

// Adds weight x the patch back centred on the pixel of `direction` (skipped below the horizon).
void insert_sun(SkyImage* sky, const SunPatch& patch, const Vec3d& direction, double weight = 1.0);

// In an image in the [0, 1] form (CV_32FC3): the pixels where any channel is >= 0.999, dilated by
// one pixel, filled from their unclipped surroundings (normalised convolution); the image clamped to
// [0, 1], 0 outside the disc. Returns that mask (CV_8UC1,
// all zero when nothing clipped, and then the image is unchanged).
cv::Mat fill_saturated_pixels(cv::Mat* unit);

// Copies `from`'s pixels where mask (CV_8UC1, the skies' size) is set.
void restore_pixels(SkyImage* sky, const SkyImage& from, const cv::Mat& mask);

}  // namespace dynsky
