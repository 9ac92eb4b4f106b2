// Moving sky pixels along a flow field on the sphere (the paper's Lambda), and the flow itself.
//
// A flow field is an N x N CV_32FC2 image: the displacement, in pixels of the N x N canonical
// fisheye (+x right, +y down), that the content seen at each pixel undergoes from one image to the
// next. Advection does NOT shift pixels along straight image lines: a pixel's displacement names
// a target direction on the sphere, and the content moves along the great arc between the two
// directions (rotation about the axis perpendicular to both), so clouds keep their solid angle and
// follow great circles across the zenith and near the horizon (sky/fisheye.h does the mapping).
#pragma once

#include <opencv2/core.hpp>

#include "sky/sky_image.h"

namespace dynsky {

struct SkyFlowParams {
    int work_resolution = 512;      // Farneback runs at this size; the flow is scaled back to N
    double min_texture = 0.02;      // confidence: local gradient of log luminance below this is a hole
    double fill_sigma = 0.06;       // hole filling reach, as a fraction of the work resolution
};

// Optical flow from `from` to `to` (cv::calcOpticalFlowFarneback on log luminance at
// work_resolution, then resized to N and scaled). Where the image has no texture to track (inside
// large uniform clouds, clear sky, outside the disc) the estimate is replaced by the confident
// flow around it (normalised convolution), so such regions move with their surroundings.
cv::Mat estimate_sky_flow(const SkyImage& from, const SkyImage& to, const SkyFlowParams& params = {});

// Replaces low-confidence flow by the confidence-weighted Gaussian average of its neighbourhood
// (normalised convolution, sigma in pixels). confidence: CV_32FC1 in [0, 1].
cv::Mat fill_flow_holes(const cv::Mat& flow, const cv::Mat& confidence, double sigma_px);

// The sky with its content moved by `fraction` of the flow along great arcs (fraction may be
// negative: backwards). Backward mapping: output pixel q takes the input at q's direction rotated
// by -fraction of the arc from q to q + flow(q), sampled bilinearly. fraction 0 returns the input.
// Time and sun are copied from the input.
SkyImage advect_great_arc(const SkyImage& sky, const cv::Mat& flow, double fraction);

// The flow of a rigid rotation of the sky by `angle` radians about `axis` (world frame):
// flow(p) = pixel(R d_p) - p. For tests and for a uniform wind drift across the sky.
cv::Mat rotation_flow(int resolution, const Vec3d& axis, double angle);

// Direction <-> continuous pixel coordinates (x = column, y = row; pixel (i, j)'s centre is at (i, j),
// OpenCV's convention) of an
// N x N fisheye, for any direction (below the horizon gives r > 1).
Vec3d direction_from_pixel(double x, double y, int resolution);
void pixel_from_direction(const Vec3d& w, int resolution, double* x, double* y);

}  // namespace dynsky
