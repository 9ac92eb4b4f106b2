// A sky's radiance scale against the clear-sky model (glossary: "radiance scale").
//
// Parameters (RadianceScaleParams), defaults in brackets:
//   calibration   [HdrCalibrationParams{}]  the photo import's calibration rule, measured again on
//                 the sky (sky/hdr_recovery.h): clear pixels by the red/blue rule on the sky encoded
//                 as a camera would (exposure-free), 15 degrees around the sun and the last 12 above
//                 the horizon left out; the clear pixels' median ratio to the Hosek-Wilkie sky
//                 (turbidity 3), blended in log with the mean's ratio by the clear share (1 %..10 %)
//   band          [1.5]  a scale beyond [1/band, band] is divided out; within it the sky moves as it is
//
// The moving sky is made at absolute radiance (W m^-2 sr^-1): imports calibrate photographs to it
// by the rule above, the clear and procedural skies are made in it, and the step models compare a
// sky with the clear-sky model (its clouds' opacity, the cloud over the sun; the networks' [0, 1]
// form clips at 300). A sky in other units (a relative HDRI, an EXR scaled by hand) was misjudged by
// all of them: a clear sky x 3 lost its sun in one step (its whole sky read as cloud over the sun),
// x 1e-6 came out 1400 times too bright. Such a sky is divided by its scale for the steps and the
// frames are multiplied back, so it moves as the same sky at scale does and keeps its own units.
// Measured again on imported ARM and Mobotix frames (clear, broken, overcast, dusk) the rule gives
// 0.85-1.15: they move as before.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "sky/hdr_recovery.h"
#include "sky/sky_image.h"

namespace dynsky {

struct RadianceScaleParams {
    HdrCalibrationParams calibration;
    double band = 1.5;
};

struct RadianceScale {
    double factor = 1.0;        // the sky's radiance over the clear-sky model's (1: not measured)
    bool measured = false;      // false without a sun above the horizon to compare with
    double clear_fraction = 0;  // of the pixels compared
    double clear_weight = 0;    // of the clear pixels' ratio in the blend (the rest: the mean's)
    bool apply = false;         // factor outside its band: move the sky divided by it
    // "3.02 x the clear-sky model's radiance (its clear pixels)".
    std::string describe() const;
};

// The sky's scale, measured against the Hosek-Wilkie sky of its sun (sky.sun_direction, else the
// sun its brightest pixels show); not measured without one.
RadianceScale measure_radiance_scale(const SkyImage& sky, const RadianceScaleParams& params = {});

// Every pixel times `factor` (the sun and time kept).
void scale_radiance(SkyImage* sky, double factor);

// What `sky predict` and the timeline do with the sky they move and its previous frame (if any):
// measures the sky's scale (against `sun_if_unrecorded` when the sky records no sun: a clock's)
// and, when it is to be applied, divides both by it. Not for a sky in kAbsoluteRadiance units measured
// mostly on its mean (an overcast: dark because it is dark), unless it is brighter than any sky can
// be (over 30 x the clear-sky model's: then not in those units whatever it says). The
// caller gives the results back multiplied by the returned factor.
RadianceScale bring_to_model_scale(SkyImage* sky, std::shared_ptr<const SkyImage>* previous,
                                   const std::optional<Vec3d>& sun_if_unrecorded = std::nullopt);

}  // namespace dynsky
