// The networks' form of a sky (glossary: "network form"): the HDR sky mapped to [0, 1] by
// sky/hdr_recovery.h's log map (UnitMapParams), 0 outside the disc, at the networks' resolution N,
// with the cloud rule that makes the cloud mask I_cm; and frames of real or procedural sequences in
// that form, with the pixels the camera saw.
#pragma once

#include <opencv2/core.hpp>

#include <optional>
#include <string>
#include <vector>

#include "sky/cloud_mask.h"
#include "sky/hdr_recovery.h"
#include "sky/sky_image.h"

namespace dynsky {

// How skies become what the networks see: sky/hdr_recovery.h's log map HDR -> [0, 1] (its
// parameters are the model's: stored in model.json and the dataset's meta.json) and the cloud rule
// for I_cm (sky/cloud_mask.h, on the sky encoded as a camera would: encode_sky_for_mask).
// Defaults: the log map spans 0..300 W m^-2 sr^-1 (the sky and sunlit clouds of the ARM and
// procedural sequences reach about 100; only the sun and its nearest aureole clip), and red/blue >
// 0.75 (WSISEG's best threshold; on the ARM day it calls 53 % of the sky cloud, the imager's own
// masks 55 %, while the paper's 0.46 calls 79 %).
struct NetworkFormParams {
    UnitMapParams unit_map{1.0, 300.0};
    CloudMaskParams cloud_rule{CloudRule::RedBlueRatio, kWsisegBestRedBlueThreshold};
};

// The [0, 1] form of an HDR sky (CV_32FC3, 0 outside the disc) and back: sky/hdr_recovery.h's
// hdr_to_unit / unit_to_hdr. to_network_form also area-resamples to `resolution` when it is given
// and differs; from_network_form takes time, sun and source from `like`.
cv::Mat to_network_form(const SkyImage& sky, const NetworkFormParams& form, int resolution = 0);
SkyImage from_network_form(const cv::Mat& image, const SkyImage& like, const NetworkFormParams& form);

// A frame as the networks see it, at their resolution N.
struct NetworkFrame {
    cv::Mat image;  // N x N CV_32FC3 in [0, 1], 0 outside the disc
    cv::Mat valid;  // N x N CV_8UC1: 255 where the sky was seen (inside the disc, not hidden)
    cv::Mat cloud;  // N x N CV_8UC1: 255 where the cloud mask (sky/cloud_mask.h) says cloud
    double time_seconds = 0.0;
    std::optional<Vec3> sun_direction;  // the sky's, when known
};

// The clear sky of a sun direction (Hosek-Wilkie, turbidity 3 unless given, no solar disc) in the
// network form at n: the background the clouds of a sky move over (glossary: "clear background").
cv::Mat clear_background(const Vec3d& sun_direction, int n, const NetworkFormParams& form, double turbidity = 3.0);

// The turbidity of the background for a sky: 3, unless the sky is a Hosek-Wilkie clear sky of
// another turbidity (1.5..10, found to a tenth): one whose median departure from that model, in log
// luminance and log red/blue, is under 0.02 and under half its departure from turbidity 3 (a clear sky made by
// `dynsky sky clear --turbidity 2`). A photograph or a cloudy sky keeps 3. Against turbidity 3 a
// turbidity-2 sky at sunrise read as cloud near the sun, which went out for 11-14 minutes.
double clear_sky_turbidity(const SkyImage& sky, const Vec3d& sun_direction);

// From a sky of any resolution. `not_sky` (sky.resolution^2 values, 1 = hidden by the camera's arm,
// band or masts and filled in by the import) may be empty (everything seen). A pixel at N is valid
// only if every input pixel under it was seen.
NetworkFrame network_frame(const SkyImage& sky, const std::vector<unsigned char>& not_sky, int resolution,
                           const NetworkFormParams& form);

// The same frame at another resolution: image area-averaged (0 outside the new disc), a pixel valid
// only if all pixels under it were, cloud where most of the pixels under it were.
NetworkFrame resample_frame(const NetworkFrame& frame, int resolution);

// The cloud mask of an image in the [0, 1] form (mapped back to HDR, encoded as a camera would,
// the rule applied), CV_8UC1 255 = cloud, 0 outside the disc.
cv::Mat network_cloud_mask(const cv::Mat& image, const NetworkFormParams& form);

// A photograph from one of the camera presets (sky/photo_import.h: "arm-tsi", "mobotix"), imported
// at import_resolution exactly as `dynsky sky import --preset P --res R` does (the preset's mask,
// HDR calibrated from the file name's time and the preset's place), then as above. The import's
// not-sky pixels (arm, shadow band, masts) are what the frame marks as not valid.
// With no preset the file is a sky already imported (EXR, photo_sequence.h), resampled to
// import_resolution (never up: a smaller sky is refused naming the file); the pixels its import
// filled are left out when their mask lies beside it as STEM.filled.png (`dynsky sky import
// --filled-mask`), of the sky's size.
NetworkFrame network_frame_from_photo(const std::string& path, const std::string& preset, int import_resolution,
                                      int resolution, const NetworkFormParams& form);

}  // namespace dynsky
