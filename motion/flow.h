// Cloud motion as a flow field, and how it is measured (optical flow) or made (rotations).
//
// A flow field is an N x N CV_32FC2 image: the displacement, in pixels of the N x N canonical
// fisheye (+x right, +y down; sky/fisheye.h's pixel coordinates), that the content seen at each
// pixel undergoes from one image to the next (over one medium step, Delta t).
//
// Every optical flow in dynsky is OpenCV's Farneback (cv::calcOpticalFlowFarneback) with the
// parameters of one struct, FarnebackParams. Two uses:
//   farneback_flow     on images in the networks' [0, 1] form (metrics, training targets, the
//                      baseline): defaults below, on the 0-255 scale the parameters were tuned for.
//   estimate_sky_flow  on HDR skies (Gamma's in-between keys, flow extrapolation): log luminance
//                      at a working size, 5 levels, window 15 at 512 px (scaled with the size),
//                      holes (no texture to track) filled from the confident flow around them.
#pragma once

#include <opencv2/core.hpp>

#include "sky/default_sky.h"
#include "sky/sky_image.h"

namespace dynsky {

struct FarnebackParams {
    double pyr_scale = 0.5;
    int levels = 3;
    int winsize = 15;
    int iterations = 3;
    int poly_n = 5;
    double poly_sigma = 1.2;
};

// cv::calcOpticalFlowFarneback(from, to) with these parameters (8-bit or float one-channel images).
cv::Mat farneback(const cv::Mat& from, const cv::Mat& to, const FarnebackParams& params);

// Dense optical flow from `from` to `to` (Farneback on the luminance, scaled to 0-255), CV_32FC2 in
// pixels: the content at x in `from` is near x + flow(x) in `to`.
cv::Mat farneback_flow(const cv::Mat& from, const cv::Mat& to, const FarnebackParams& params = {});

struct SkyFlowParams {
    int work_resolution = 512;  // Farneback runs at this size; the flow is scaled back to N
    double min_texture = 0.02;  // confidence: local gradient of log luminance below this is a hole
    double fill_sigma = 0.06;   // hole filling reach, as a fraction of the work resolution
    // winsize is for a 512 px working size and scales with it (at least 5).
    FarnebackParams farneback{0.5, 5, 15, 3, 5, 1.2};
};

// Optical flow from `from` to `to` (Farneback on log luminance at work_resolution, then resized
// to N and scaled). Where the image has no texture to track (inside large uniform clouds, clear
// sky, outside the disc) the estimate is replaced by the confident flow around it (normalised
// convolution), so such regions move with their surroundings.
cv::Mat estimate_sky_flow(const SkyImage& from, const SkyImage& to, const SkyFlowParams& params = {});

// Replaces low-confidence flow by the confidence-weighted Gaussian average of its neighbourhood
// (normalised convolution, sigma in pixels). confidence: CV_32FC1 in [0, 1].
cv::Mat fill_flow_holes(const cv::Mat& flow, const cv::Mat& confidence, double sigma_px);

// The flow of a rigid rotation of the sky by `angle` radians about `axis` (world frame):
// flow(p) = pixel(R d_p) - p. For tests and for a uniform wind drift across the sky.
cv::Mat rotation_flow(int resolution, const Vec3d& axis, double angle);

// A uniform wind on one cloud layer (glossary: "wind"): the clouds are a flat layer at
// cloud_height_m above the camera, moving horizontally at speed_mps towards from_deg + 180 degrees
// (from_deg: where the wind blows FROM, clockwise from north, as weather reports give it). Only
// the ratio speed / height matters for the image: 10 m/s at 1500 m moves an overhead cloud
// 0.38 degrees per second. Defaults: from the west at 12 m/s, a cumulus base at 1500 m (the
// procedural sky's cumulus layer).
struct Wind {
    double from_deg = default_sky::kWindFromDeg;
    double speed_mps = default_sky::kWindSpeedMps;
    double cloud_height_m = default_sky::kCloudHeightM;
};

// The flow of that layer over dt seconds at resolution n, by destination: F(x) = x - s(x), where
// s(x) is the pixel whose cloud moves to x (so a backward warp I(x - F(x)) is exact). Beyond 88
// degrees from the zenith the layer is taken at 88 degrees (the motion there is ~0 anyway).
cv::Mat wind_flow(int n, const Wind& wind, double dt);

// The uniform wind that best explains a measured flow (least squares over the pixels where
// weight > 0, CV_32FC1 or CV_8UC1; the flow's resolution), with the given cloud height. For
// fitting a "true wind" to real motion.
Wind fit_wind(const cv::Mat& flow, const cv::Mat& weight, double dt, double cloud_height_m = 1500.0);

// The motion estimate of a previous frame as the cloud models use it: the flow Gaussian-smoothed
// with sigma = N / 32 (2 px at 64). Farneback's field is noisy where there is little to track (clear
// sky, flat overcast); smoothing keeps the clouds' common motion and drops the noise, which
// otherwise shuffles a static background (measured: +0.37 dB one step ahead on held-out ARM frames,
// never worse on the four real sequences; docs/networks.md).
// With `trusted` (CV_8UC1, the flow's size, 255 where the flow measures the sky: inside the disc,
// not clipped, not filled in by an import) the smoothing averages over those pixels only
// (normalised convolution) and fills the rest from them: the black outside the disc and a static
// sun or filled camera arm measure no motion, and would pull the clouds' flow near them to zero.
cv::Mat smooth_motion(const cv::Mat& flow, const cv::Mat& trusted = cv::Mat());

// The motion of the last pair as the cloud models use it, in two parts:
//   smoothed   smooth_motion of Farneback's forward flow: the clouds' common motion, without the
//              noise where there is little to track (clear sky, flat overcast); what the models
//              iterate
//   confirmed  the same, except where the forward flow and the backward flow (current -> previous,
//              read where the forward flow lands) agree within 0.5 px of a 256 px sky (a weight
//              exp(-e^2 / tau^2) of the mismatch e): there the measurement as it is, sharp edges
//              between layers and the true speed at cloud edges included; the first step's motion
// The two directions' agreement tells sharp broken cumulus (where the raw flow is right) from
// flat skies (where smoothing is). Validation frames, model+prev one step ahead against iterated
// Farneback: arm-tsi +1.12 -> +1.44 dB, the dusk and Mobotix within +-0.02 (docs/networks-advect-residual.md).
struct MeasuredMotion {
    cv::Mat smoothed, confirmed;  // N x N CV_32FC2, pixels per step
    cv::Mat agreement;  // CV_32FC1 in [0, 1]: that weight averaged over the trusted pixels around (sigma N / 32)
    MeasuredMotion at_resolution(int n) const;  // all, as flow_at_resolution
};
// `forward` and `backward` N x N CV_32FC2; `trusted` as for smooth_motion (untrusted pixels take
// the smoothed field).
MeasuredMotion consistent_motion(const cv::Mat& forward, const cv::Mat& backward, const cv::Mat& trusted = cv::Mat());

// consistent_motion of farneback_flow(previous, current) and farneback_flow(current, previous).
MeasuredMotion measured_motion(const cv::Mat& previous, const cv::Mat& current, const cv::Mat& trusted = cv::Mat());

// A flow field measured at another resolution, area-averaged to a smaller N (bilinear to a larger
// one) and rescaled to N's pixels.
cv::Mat flow_at_resolution(const cv::Mat& flow, int n);

// A flow by destination (F(y) = y - s(y): the content arriving at y came from y - F(y), as
// wind_flow gives it) as the same motion by source (S(p): the content at p goes to p + S(p), as
// the step models' last_step_flow and advect_great_arc take it): for each p the y with
// y - F(y) = p, by fixed-point iteration (sample_flow; above 256 px on
// 256^2 and resized, the field being smooth). The two differ
// by F's change over one displacement: for animate's wind at 1024 px by up to 5 px, and read one
// way where the other was meant, in-between frames showed every cloud edge twice.
cv::Mat flow_by_source(const cv::Mat& by_destination);

// A square flow field's displacement (CV_32FC2) at continuous pixel coordinates (x, y): bilinear,
// the reads clamped to the image.
cv::Vec2f sample_flow(const cv::Mat& flow, double x, double y);

// A flow field's displacement (CV_32FC2, pixels of its own resolution) at the pixel nearest to a
// direction of the sky: the motion of the clouds at the sun.
cv::Vec2f flow_at_direction(const cv::Mat& flow, const Vec3d& direction);

}  // namespace dynsky
