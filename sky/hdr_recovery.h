// From a display-referred photograph to plausible absolute radiance, and the [0, 1] encoding the
// cloud-motion networks consume.
//
// recover_hdr (inverse tone mapping, docs/sky-import.md):
//  1. the photo is already linear (sRGB-decoded by sky/photo_import.h), but its scale is unknown;
//  2. the clear-sky model (sky/clear_sky.h, Hosek-Wilkie, W m^-2 sr^-1) is evaluated for the sun's
//     position at the photo's time and place;
//  3. colour (docs/sky-import.md): with a camera's colour known (CameraColour: its grey and typical
//     chroma stretch), every pixel's log(R/G), log(B/G) is taken relative to the camera's grey and
//     divided by the chroma stretch, fitted per photo so that the CLEAR pixels (cloud rule says clear,
//     not clipped, not filled, away from the sun and the horizon) get the model's colour: clouds stay
//     grey and the clear sky gets the model's blue. Without it, per-channel gains (a diagonal white
//     balance) fitted on the clear pixels. Luminance is kept; too few clear pixels: the camera's
//     typical colour, or none;
//     then the ratio model luminance / photo luminance on the clear pixels is taken, and its median
//     is the scale applied to the whole photo; with too few clear pixels (overcast) the scale instead
//     matches the photo's mean luminance to the clear model's: a weak, documented fallback; between
//     1 % and 10 % of the disc clear the two are blended (in log), so the scale never jumps;
//  4. the sun: clipped pixels near the sun (the sun seen, saturated) get max(scaled photo, model
//     sky + disc), which restores the disc's true radiance and the aureole's clipped core. A sun
//     hidden by a shadow band counts as seen if the sky around the band near it is clear or clipped.
//
// UnitMap: y = log(1 + x / scale) / log(1 + max_radiance / scale), per channel, clamped to [0, 1];
// exactly invertible below max_radiance (which by default exceeds any sun pixel the model makes).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "sky/cloud_mask.h"
#include "sky/photo_import.h"
#include "sky/sky_image.h"
#include "sky/sun_position.h"
#include "util/image.h"

namespace dynsky {

// How far a fit on the clear pixels is trusted: 0 under `none_below` of the disc clear, 1 from
// `full_from`, a smoothstep between (so neighbouring frames of a sky clouding over agree).
double trust_ramp(double clear_fraction, double none_below, double full_from);

struct HdrCalibrationParams {
    UtcTime time;            // when the photo was taken (UTC)
    GeoLocation location;    // where
    double turbidity = 3.0;  // clear-sky model parameters (sky/clear_sky.h)
    double ground_albedo = 0.3;
    // Which pixels are clear sky for the calibration; the paper's 0.46 is too strict for most
    // cameras (docs/sky-import.md), WSISEG's best threshold is the default here.
    CloudMaskParams clear_rule{CloudRule::RedBlueRatio, kWsisegBestRedBlueThreshold};
    double exclude_sun_deg = 15;  // skip the aureole: its clipping and forward scattering
    double max_zenith_deg = 78;   // skip the haze and obstructions near the horizon
    // Clear pixels (fractions of the disc) to trust the clear-pixel calibration at all and fully;
    // between, its scale is blended in log with the fallback's (step 3).
    double min_clear_fraction = 0.01;
    double full_clear_fraction = 0.10;
    bool restore_sun = true;
    double sun_search_deg = 3;     // a clipped blob this close to the computed sun is the sun
    bool use_observed_sun = true;  // place the sun where the photo shows it (if seen)
    // Colour against the model (step 3); false keeps the camera's colours (one scale for all three
    // channels).
    bool white_balance = true;
    // Clear pixels (fractions of the disc) to fit the colour at all and to trust the fit fully;
    // between, the fit is blended with what stands in for it without one.
    double min_white_balance_fraction = 0.03;
    double full_white_balance_fraction = 0.10;
    // The camera's colour rendering (CameraPreset::colour); none: per-channel gains.
    std::optional<CameraColour> camera_colour;
    // The clear share that decides how far the fits on the clear pixels are trusted (the ramps
    // above), instead of the photo's own: a sequence's, smoothed over time (sky/photo_import_job.h),
    // so that a frame whose clear share spiked (the Mobotix's dawn: 0.03 %, 6.7 %, 0.03 % a minute
    // apart, the middle sky 2x brighter) is calibrated as its neighbours are. The fits themselves
    // stay the photo's own (its exposure and white balance may differ from theirs).
    std::optional<double> trusted_clear_fraction;
    // Where the sun lies in this photograph's own frame, instead of where the clock puts it: a
    // sequence's sun track (fit_sun_track), for a camera that is not level or not turned as its
    // north says. The clipped sun is then searched for within 5 degrees of it.
    std::optional<Vec3d> sun_in_photo;
};

// A north found from the sun a photograph shows (north_from_seen_sun, below).
struct NorthFromSun {
    double north_deg = 0;        // [0, 360)
    double seen_zenith_deg = 0;  // the blob's centre, as imported
    double sun_zenith_deg = 0;   // computed
    double moved_deg = 0;        // the blob's angle from the computed sun as imported (before the turn)
};

struct HdrCalibrationReport {
    // "clear-sky pixels", "mean-luminance fallback", or both blended (clear_weight between 0 and 1)
    std::string method;
    double clear_weight = 0;            // the clear-pixel scale's weight in log (1 - the fallback's)
    double scale = 0;                   // radiance (W m^-2 sr^-1) per linear photo unit
    long long clear_pixels = 0;         // pixels used (before subsampling)
    double clear_fraction = 0;          // of the disc
    double trusted_clear_fraction = 0;  // what the trust ramps took (clear_fraction, or one imposed)
    double ratio_spread = 0;            // median absolute deviation / median of the per-pixel ratios
    // Colour correction applied before the scale (luminance kept): log(R/G), log(B/G) minus
    // grey_rg/grey_bg (the camera's grey, or the fitted gains' log), divided by chroma_rg/chroma_bg;
    // and where it came from ("clear-sky pixels", "the camera's typical colour (...)", "none (...)").
    double grey_rg = 0, grey_bg = 0, chroma_rg = 1, chroma_bg = 1;
    std::string white_balance_method = "none";
    bool sun_visible = false;  // clipped sun found, or sun behind the band with clear sky around
    bool sun_restored = false;
    double sun_offset_deg = -1;  // angle between the clipped sun seen and the computed sun (-1: not seen)
    // The clipped sun was joined to other clipped sky (the horizon under it, sunlit cloud): seen, and
    // put at the computed sun (its blob's shape cannot place it more closely).
    bool sun_joined = false;
    // ... or the middle of a wide clipped glare on a clear sky (an over-exposed photo): also put there.
    bool sun_in_wide_glare = false;
    // No sun near the computed one, but a clipped sun at its height elsewhere (north_from_seen_sun):
    // the camera's north is likely wrong; the north that would put the computed sun on it.
    std::optional<NorthFromSun> sun_elsewhere;
    double sun_elevation_deg = 0;  // computed
    // computed_sun: where the sun was looked for (the clock's, or HdrCalibrationParams::sun_in_photo);
    // clock_sun: the clock's always; seen_sun: the centre of the clipped blob taken for the sun, when
    // its shape placed it (not joined to other glare).
    Vec3d computed_sun = Vec3d::UnitY(), used_sun = Vec3d::UnitY(), clock_sun = Vec3d::UnitY();
    std::optional<Vec3d> seen_sun;
    std::string summary() const;  // one line for people
    // Non-empty when the clipped sun lies farther than kSunOffsetWarningDeg from the computed one
    // (a wrong time, place or orientation, or glare taken for the sun), or is seen only elsewhere at
    // its height (sun_elsewhere): says so, what was done, and the north that would fit.
    std::string sun_offset_warning() const;
    static constexpr double kSunOffsetWarningDeg = 3.0;
};

// Where north is in a photograph from the sun it shows, for a level camera whose north is not
// known: the clipped blob that could be the sun (its saturated disc and aureole, within a 20 degree
// cone, at least the sun's disc and 1.5 pixels) nearest the computed sun's zenith angle (within
// max_zenith_error_deg; larger blobs preferred, 1.5 degrees per doubling), and the north
// (PhotoGeometry::north_deg, the photo's convention) that puts it at the computed sun's azimuth. None when the camera is tilted, the sun is under 3 degrees up
// or no such blob is seen (overcast, or only a field of clipped cloud).
std::optional<NorthFromSun> north_from_seen_sun(const ImportedPhoto& photo, const UtcTime& time,
                                                const GeoLocation& where, double max_zenith_error_deg = 5);

// One north from those found on several photographs of a sequence (north_from_seen_sun on each):
// the one with the least summed angular distance to the others (a median on the circle: a photo
// whose glare was taken for the sun does not pull it), how many lie within 10 degrees of it and
// the farthest of those, and whether they agree: more than half of them near it, and at least two
// unless only one photograph was looked at (`tries`). Glare or a bright cloud taken for the sun
// scatters the norths: on an ARM sequence imported as an unknown camera, 1 of 10 put north 140
// degrees off. Throws dynsky::Error for none.
struct ConsensusNorth {
    double north_deg = 0;
    int near = 0;
    double spread_deg = 0;
    bool agreed = false;
};
ConsensusNorth consensus_north(const std::vector<double>& norths_deg, int tries = 1);

// The turn that takes where the clock puts the sun to where a sequence's photographs show it
// (Wahba's problem, by SVD), fitted to the photographs whose clipped sun was seen and refitted
// without those more than max(3 x the median, 2 degrees) off (glare taken for the sun). None with
// fewer than 5 such photographs, a track under 10 degrees long, or a median residual over 2 degrees.
// A camera that is tilted, or turned otherwise than its north says, shows the sun on such a track:
// the Mobotix's morning, 82 photographs, 9-38 degrees from the clock's sun, within 1.1 degrees
// (median) of one turn.
struct SunTrack {
    Eigen::Matrix3d turn = Eigen::Matrix3d::Identity();  // seen = turn * clock
    int used = 0, seen = 0;
    std::vector<bool> taken;  // per seen sun: whether the turn was fitted to it (false: glare)
    double median_residual_deg = 0, median_offset_deg = 0, turn_deg = 0;
};
std::optional<SunTrack> fit_sun_track(const std::vector<Vec3d>& clock, const std::vector<Vec3d>& seen);

// Absolute radiance from an imported LDR photo (throws dynsky::Error if the photo was not
// display-referred: HDR input already has its own scale). Sets sun_direction on the result.
SkyImage recover_hdr(const ImportedPhoto& photo, const HdrCalibrationParams& params,
                     HdrCalibrationReport* report = nullptr);

// The forward map to [0, 1] and back. Defaults: radiance in W m^-2 sr^-1 (the clear-sky model's
// unit), scale 1 (a clear sky is 1-25 there, so the sky spans about 0.05-0.2 of the range),
// max 1e7 (above the model's brightest sun pixel, about 3e6).
struct UnitMapParams {
    double scale = 1.0;
    double max_radiance = 1e7;
};
void validate_unit_map(const UnitMapParams& params);
float radiance_to_unit(float radiance, const UnitMapParams& params);
float unit_to_radiance(float unit, const UnitMapParams& params);

// Whole images: N x N x 3, 0 outside the disc; the parameters travel as metadata
// ("dynsky:unit_scale", "dynsky:unit_max") and unit_to_hdr checks them when present.
Image hdr_to_unit(const SkyImage& sky, const UnitMapParams& params = {});
SkyImage unit_to_hdr(const Image& unit, const UnitMapParams& params = {});

}  // namespace dynsky
