// Moving sky pixels along a flow field (motion/flow.h): on the sphere (the paper's Lambda) and, for
// the networks' small images and the baselines, in the image plane.
//
// Great-arc advection does NOT shift pixels along straight image lines: a pixel's displacement names
// a target direction on the sphere, and the content moves along the great arc between the two
// directions (rotation about the axis perpendicular to both), so clouds keep their solid angle and
// follow great circles across the zenith and near the horizon (sky/fisheye.h does the mapping).
#pragma once

#include <opencv2/core.hpp>

#include "motion/flow.h"
#include "sky/sky_image.h"

namespace dynsky {

// The sky with its content moved by `fraction` of the flow along great arcs (fraction may be
// negative: backwards). Backward mapping: output pixel q takes the input at q's direction rotated
// by -fraction of the arc from q to q + flow(q), sampled bilinearly. fraction 0 returns the input.
// Time and sun are copied from the input.
SkyImage advect_great_arc(const SkyImage& sky, const cv::Mat& flow, double fraction);

// The sky one step of `flow` later (`end`: its content where the flow took it) carried back to
// `fraction` of the step (0 the start, 1 the end itself): output pixel q shows the end at the end of
// the arc of the start's p whose arc passes q at `fraction`. The flow is the start's (where content
// starts), so this meets advect_great_arc(start, flow, fraction) content for content: the two
// halves of an in-between frame (SkyTimeline) coincide. advect_great_arc(end, flow, fraction - 1)
// reads the flow where content ends, and where it varies (1 px per 15 px at 1024 px) the two
// copies met a few pixels apart: doubled cloud edges in every in-between frame.
SkyImage advect_great_arc_from_end(const SkyImage& end, const cv::Mat& flow, double fraction);

// The image with every pixel outside the disc holding the rim's value along its radius (pixel
// centres with r > 1 - 1.5 / N take the value at r = 1 - 1.5 / N, bilinear, border replicate), so
// that bilinear lookups at the horizon never mix in the black corners. Any channel count.
cv::Mat extend_past_rim(const cv::Mat& image);

// The networks' warp (motion/advect_residual.h): W(x) = E(I)(x - F(x)), E = extend_past_rim,
// bilinear with border replicate, then 0 outside the disc. Exact for a flow by destination
// (motion/flow.h wind_flow); the usual first-order stand-in for a flow by source.
cv::Mat warp_in_disc(const cv::Mat& image, const cv::Mat& flow);

// Where the warp of a flow reads, per output pixel (CV_32FC2 pixel coordinates, x - F(x)), with
// the networks' rim rule (sources beyond the rim read the rim-extended image, extend_past_rim). With
// recycle, such a source is first carried to the far side of the disc (reflected across the line through the zenith
// perpendicular to the flow's mean direction): what leaves downwind comes back upwind, so long
// rollouts keep their clouds instead of filling up with the rim's values.
cv::Mat warp_sources(const cv::Mat& flow, bool recycle = false);

// extend_past_rim in full float precision (what the networks' warp samples).
cv::Mat extend_past_rim_exact(const cv::Mat& image);

// Bilinear lookup of a float image (any channel count) at positions (CV_32FC2), border replicate,
// in full float precision (cv::remap rounds positions to 1/32 pixel).
cv::Mat sample_exact(const cv::Mat& image, const cv::Mat& positions);

// The flow applied `steps` times, as one displacement: D with x - D(x) the point `steps` steps
// upstream along the flow's streamline through x (x_k = x_{k-1} - F(x_{k-1}), F read bilinearly
// from the rim-extended flow, so a path that leaves the disc keeps the rim's motion). warp_in_disc
// by D moves an image along the flow's curved paths with one interpolation; a warp by steps x F
// moves it in a straight line with the motion at the destination.
cv::Mat traced_flow(const cv::Mat& flow, int steps);

// Advects an image along a flow field for `steps` steps at constant velocity:
// out(x) = image(x - steps * flow(x)) (bilinear; outside the image reads 0). The backward lookup
// through the flow at the destination is the usual first-order stand-in for forward splatting.
cv::Mat advect_by_flow(const cv::Mat& image, const cv::Mat& flow, double steps);

// The Farneback-extrapolation baseline: the flow of previous -> current, applied `steps` times to
// current.
cv::Mat extrapolate_farneback(const cv::Mat& previous, const cv::Mat& current, int steps,
                              const FarnebackParams& params = {});

}  // namespace dynsky
