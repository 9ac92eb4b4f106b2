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

#include <optional>
#include <vector>

#include "sky/sky_image.h"

namespace dynsky {

// The sun's pixels cut out of a sky (relative to the sun's pixel) with their excess radiance.
// (fx, fy): where in that pixel the sun was (its exact position minus the pixel's, each in
// [-0.5, 0.5]), so that insert_sun can move the patch by the sun's exact displacement.
struct SunPatch {
    std::vector<int> di, dj;
    std::vector<Color> excess;
    double fx = 0, fy = 0;
    bool empty() const { return di.empty(); }
};

// Finds the sun near sky.sun_direction (pixels within 1 degree + 2 px brighter than 20x the
// surrounding median), fills them with the clear sky's background of that sun times the sky's median
// ratio to it around them (so the fill keeps the aureole's peak) and returns the
// cut-out. No sun direction, or no bright pixels there: an empty patch and the sky unchanged.
SunPatch remove_sun(SkyImage* sky);

// The pixels remove_sun may cut around the sun's pixel in an n x n sky (1 degree + 2 px, and the
// limb's pixel beyond): CV_8UC1, all zero when the sun is below the horizon.
cv::Mat sun_cut_mask(int n, const Vec3d& sun);

// The pixels near the sun whose cloud the moving sky cannot judge by their look: the cut
// (sun_cut_mask) and every pixel within kSunUnseenDeg of the sun, so that at any resolution at
// least the sun's glare (1 degree + 2 px at 1024 px: 1.35 degrees) is taken from the clouds around
// it. Wider (5.5 degrees until 2026-12-06, when the look rule still read a forward-lit cloud near
// the sun as clear) it hid the edge of the cloud that covers the sun, whose fill from around it
// then held the sun covered or clear 10-25 s too long: in the main job's setting (`compare`
// defaults, 1024 px, seeds 1-6) the sky's illuminance was 29 % off on average, now 11 %; bench/sun_seeds at
// 512 px 8.1 % -> 6.7 % (docs/animation.md).
inline constexpr double kSunUnseenDeg = 1.5;
cv::Mat sun_unseen_mask(int n, const Vec3d& sun);

// The pixels of an n x n sky (CV_8UC1, 255) inside its disc and within `degrees` of the sun.
cv::Mat sun_cone_mask(int n, const Vec3d& sun, double degrees);

// The clear sun of an n x n sky: the Hosek-Wilkie disc (turbidity as the clear sky compared with
// in estimate_sun_transmittance) splatted as make_clear_sky and the photo import's sun restoration
// splat it, as a patch centred on the pixel of `sun`. Empty below the horizon.
SunPatch clear_sun_patch(int n, const Vec3d& sun, double turbidity = 3.0);

// How much of that clear sun a patch cut from an n x n sky at `sun` holds: the luminance of its
// irradiance over the clear disc's (0 for an empty patch; about 1 for a clear or restored sun).
double sun_patch_share(const SunPatch& patch, int n, const Vec3d& sun, double turbidity = 3.0);

// Adds weight x the patch back, moved by the sun's exact displacement from where it was cut to
// `direction` (skipped below the horizon): each pixel shared bilinearly among the four it falls
// on, so a sun following the clock moves smoothly rather than a whole pixel at a time (a clear
// sky's horizontal illuminance stepped +2.9 % at 128 px as the sun crossed into the next pixel).
// At the sun's own position (no displacement) the patch goes back on the pixels it was cut from.
void insert_sun(SkyImage* sky, const SunPatch& patch, const Vec3d& direction, double weight = 1.0);

// The solid angle of a pixel of an n x n sky at `direction`'s exact position (bilinear between the
// four pixels around it; the nearest pixel's at the rim): what a patch of radiance put there by
// insert_sun covers, smooth as the sun moves.
double sun_pixel_solid_angle(int n, const Vec3d& direction);

// What a sun patch cut at `from` is multiplied by when insert_sun puts it at `to` on the clock: the
// clear-sky model's sun irradiance there over at `from` (per channel: the sun reddens and dims as
// it sets), times the solid angle of the pixels it leaves over that of those it lands on
// (sun_pixel_solid_angle), so that its irradiance follows the model's. 1 where the model has no
// sun at `from`. The sky timeline and compare's clear sky both use it.
Color sun_patch_relight(int n, const Vec3d& from, const Vec3d& to, double turbidity);

// In an image in the [0, 1] form (CV_32FC3): the pixels where any channel is >= 0.999, dilated by
// one pixel, filled from their unclipped surroundings (normalised convolution); the image clamped to
// [0, 1], 0 outside the disc. Returns that mask (CV_8UC1,
// all zero when nothing clipped, and then the image is unchanged).
cv::Mat fill_saturated_pixels(cv::Mat* unit);

// Where the sun probably is in a sky that does not say (no time and place): the centroid of the
// largest blob of pixels within 2 % of the sky's brightest, when that is at least twice the median
// and the blob is compact (at most 3 % of the disc, filling at least a third of its bounding circle)
// and above 5 degrees of elevation (any elevation when it is 1000 x the median: an HDR sun at
// sunset); else nullopt (an overexposed cloud or horizon is not a sun).
std::optional<Vec3d> sun_from_brightest_pixels(const SkyImage& sky);

// Copies `from`'s pixels where mask (CV_8UC1, the skies' size) is set. With a transmittance T below
// 1: T x from + (1 - T) x the sky's own pixel there (a cloud over the sun dims what is put back).
void restore_pixels(SkyImage* sky, const SkyImage& from, const cv::Mat& mask, double transmittance = 1.0);

// How much of the direct sun a sky lets through (glossary: "sun transmittance"), estimated from
// the sky around the sun, since the sun itself has been cut out (or hidden by a shadow band): the
// pixels within outer_deg of the sun's direction are compared with the clear sky (Hosek-Wilkie) of
// that sun, pixel by pixel. A pixel's cloudiness rises smoothly (a smoothstep in log units) as its
// colour turns whiter than the clear sky's (red/blue ratio over the model's towards cloud_ratio) or
// its luminance departs from the model's towards brightness_ratio either way: a cloud's edge, where
// the sky turns gradually, counts gradually, so a cloud sliding over the sun dims it without a
// jump. The clear share of those pixels, each weighted by 1 / (angle to the sun^2 + core_deg^2)
// (the cloud at the sun counts most), goes through a smoothstep from covered_share (0) to
// clear_share (1).
// Thresholds calibrated on the ARM TSI day against the imager's own cloud masks
// (docs/animation.md, "The sun and passing clouds").
struct SunTransmittanceParams {
    double inner_deg = 0.0, outer_deg = 12.0;  // the disc (or ring) around the sun
    double cloud_ratio = 1.25;                 // (r/b) / (r/b)_clear at this: half cloud
    double brightness_ratio = 2.5;             // luminance / clear luminance at this or its inverse: half cloud
    // Width of the cloudiness ramp in units of the log thresholds above: a pixel is clear below
    // (1 - edge_softness) x the threshold and cloud beyond (1 + edge_softness) x it (0: a hard switch).
    double edge_softness = 0.5;
    double core_deg = 0.5;                            // the weights' core (the sun's own pixel is finite)
    double covered_share = 0.25, clear_share = 0.75;  // the smoothstep's ends
    double turbidity = 3.0;                           // of the clear sky compared with
};

// How cloudy a pixel of radiance v looks where the clear sky would be `clear` (0 clear .. 1 cloud):
// the soft per-pixel rule of estimate_sun_transmittance above.
double cloudiness(const Color& v, const Color& clear, const SunTransmittanceParams& params = {});

// 1 for clear surroundings, 0 for surroundings mostly cloud; 1 when the sun is below the horizon or the ring has
// no pixels (nothing to say).
double estimate_sun_transmittance(const SkyImage& sky, const Vec3d& sun, const SunTransmittanceParams& params = {});

// The same from a map of cloud opacity (square CV_32FC1, 0 clear .. 1 cloud, in the sky's layout)
// instead of a sky's look: the clouds a model moved over the sun, as opaque as they looked where
// they were seen (motion/advect_residual.h CloudRollout::opacity). Near the sun a cloud's forward
// scattering can make it as bright and white as the aureole it hides (the procedural sky's do), so
// its look there says little. The map holds the clouds at the sun itself (no cut, glare or shadow
// band to look past), so only the pixels within 3 degrees count by default: on ten procedural skies
// whose cumulus crosses the sun, 12 degrees missed the illuminance by 16.3 % on average, 6 by 14.6 %,
// 3 by 12.9 % (docs/animation.md).
inline SunTransmittanceParams opacity_transmittance_params() {
    SunTransmittanceParams p;
    p.outer_deg = 3.0;
    return p;
}
double sun_transmittance_of_opacity(const cv::Mat& opacity, const Vec3d& sun,
                                    const SunTransmittanceParams& params = opacity_transmittance_params());

// What a sun's weight from the clouds moved over it (the opacity's transmittance, moved / start) is
// relative to: the start's transmittance at the sun, but never more cover than the start's sun
// showed (`input_sun_share`: sun_patch_share of its cut sun; 1 for a whole sun), and at least 0.05.
// The opacity within 3 degrees of a sun the start shows whole often holds a cloud beside it, and
// relative to that a cloud moved over the sun later dimmed it only once thicker still (on 20
// procedural skies, mean illuminance error 7.2 % so, 6.9 % with this). The timeline
// (SkyTimeline::model_sun_weight) and `sky predict` (AdvectResidualNetwork::rollout) both use it.
double sun_weight_reference(double start_transmittance, double input_sun_share);

// A transmittance at the sun relative to the start's, in [0, 1] (never brighter than it was):
// moved / start, where a start under 0.05 reads as cloud that nothing can thicken: moved + e over
// start + e with e = 0.05 - start (continuous at 0.05; 1 for a start of 0). An overcast sky seen
// with its sun through it read 0 at the start and 0 after a step with no wind, and the sun went out
// (0 / 0.05); the sun is put back there as it was.
double relative_transmittance(double moved, double start);

// The sun put back into a moved sky, relative to the sky it was cut from: relative_transmittance
// of the look around the sun (estimate_sun_transmittance). The sky's own sun direction when `sun`
// is not given; 1 when neither knows one.
double relative_sun_transmittance(const SkyImage& moved, const SkyImage& start,
                                  std::optional<Vec3d> sun = std::nullopt);

// The weight of the start's cut sun in a moved sky from the clouds a model moved over it (the
// opacity's transmittance at the sun, moved and at the start): relative to sun_weight_reference,
// unless the look around the start's sun also said cloud (start_look under 0.05) while that sun
// shone through (input_sun_share >= 0.05): a sun seen through an overcast or hazy sky, whose cover
// neither measure can see thicken, relative to the start's own (relative_transmittance).
// `travel`: how far the clouds at the sun have moved, as a fraction of the sun's diameter
// (sun_travel_fraction): clouds that have not moved cover the sun as they did at the start, so the
// weight goes from the start's own (1 when nothing moved) at 0 to the rule above at 1. With no
// wind a sun in a gap 2 degrees from a cloud went to half its radiance on the first step.
// Only where the start is overcast (start_cloud_share, the share of its disc a cloud covers, at
// least kOvercastCloudShare): under broken cloud a sun partly seen through the cloud around it is at
// a cloud's edge, and the clouds moved over it decide (a procedural sun half out at the start stayed
// half out for a minute where the truth's went in within 10 s).
inline constexpr double kOvercastCloudShare = 0.85;
double opacity_sun_weight(double moved_opacity_t, double start_opacity_t, double start_look, double input_sun_share,
                          double travel = 1.0, double start_cloud_share = 1.0);

// The share of an opacity map's disc (square CV_32FC1, 0 clear .. 1 cloud) at opacity 0.5 or more;
// 1 for an empty map.
double cloud_share(const cv::Mat& opacity);

// The clouds' displacement at the sun (pixels of a sky of `resolution`) as a fraction of the sun's
// diameter (0.53 degrees), in [0, 1].
double sun_travel_fraction(double displacement_px, int resolution);
// The sun's diameter (0.53 degrees) in pixels of a sky of `resolution` near the zenith.
double sun_diameter_px(int resolution);

}  // namespace dynsky
