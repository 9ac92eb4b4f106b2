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

// A flow field measured at another resolution, area-averaged (or resized) to N and rescaled to
// N's pixels.
cv::Mat flow_at_resolution(const cv::Mat& flow, int n);

}  // namespace dynsky
