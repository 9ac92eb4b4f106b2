// Where the cloud seen at each pixel was at the start of a rollout, for clouds carried by a uniform
// wind on one layer, RECYCLED so that a rollout of any length keeps moving (glossary: "recycled
// layer"). Used by motion/advect_residual.h CloudRollout when the motion has a wind.
//
// Parameters (defaults):
//   tile_zenith_deg  = 55   the recycled tile: the part of the layer seen within this zenith angle
//   max_stretch      = 4    a pixel keeps reading the real start image while the start's pixels it
//                           reads are at most this many times more foreshortened than its own
//                           (sec^2 of the zenith angle); beyond, it fades into the recycled tile
//   entry_band       = 0.25 the fade into the tile, as a fraction of that trigger's ground radius
//   cycle_band       = 0.2  the cross-fade between one pass of the tile and the next, as a fraction
//                           of the pass
//
// Why: the layer is a plane at height h; a wind translates it by w per step (units of h). The sky
// seen at a pixel is the layer point P(x) = tan(theta) (u, v) / r; after k steps its cloud was at
// P(x) - k w. Read from the start image, that is exact while the point is in view, but within
// minutes it is near the upwind horizon, where the start is foreshortened 10-1000x: the sky fills
// with streaks and, past 88 degrees, has nothing left to show. Here the layer is taken as periodic
// along the wind: each streamline (a line of constant cross-wind coordinate c) repeats its strip
// -R <= s < R along the wind (R the tile's radius; one period for all streamlines, so the passes do
// not shear the clouds), every other pass mirrored across the wind (c -> -c) so that the
// repetition is twice as long and less regular; passes are cross-faded. The first pass is the real
// start image, so short rollouts (minutes) are unchanged.
#pragma once

#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace dynsky {

struct CloudLayerPathsParams {
    double tile_zenith_deg = 55.0;
    double max_stretch = 4.0;
    double entry_band = 0.25;
    double cycle_band = 0.2;
};

// The layer point seen at continuous pixel position (x, y) of an n x n fisheye (units of the layer
// height; image axes; zenith angles beyond 88 degrees are taken at 88), and back.
cv::Vec2d layer_point(double x, double y, int n);
cv::Vec2d pixel_of_layer_point(const cv::Vec2d& p, int n);

// The layer displacement per step of a flow by destination (motion/flow.h wind_flow: the cloud at
// x came from x - F(x)): the median over the pixels within 45 degrees of the zenith of
// P(x) - P(x - F(x)). Exact for a wind's flow.
cv::Vec2d layer_step_of_flow(const cv::Mat& flow);

class CloudLayerPaths {
  public:
    // n: the image's resolution; step: the layer displacement per step (units of its height).
    CloudLayerPaths(int n, const cv::Vec2d& step, const CloudLayerPathsParams& params = {});

    // Up to four reads per pixel for step k (k may be fractional): positions (CV_32FC2 pixel
    // coordinates in the start image) and weights (CV_32FC1) that sum to 1: the real start image
    // along the layer's path (0), two passes of the recycled tile (1, 2), and the pixel itself (3:
    // where the path reads the outermost 3 % of the radius, or the pixel is past 88 degrees).
    struct Reads {
        std::array<cv::Mat, 4> positions, weights;
    };
    Reads at(double k) const;

    // False when the wind is too weak to ever leave the view (no recycling needed).
    bool moving() const { return moving_; }

  private:
    int n_;
    cv::Vec2d step_, along_, across_;
    CloudLayerPathsParams params_;
    double tile_radius_ = 0;
    bool moving_ = false;
    cv::Mat trigger_radius_;       // CV_64FC1: the ground radius at which each pixel starts to recycle
    std::vector<uint8_t> beyond_;  // pixels past 88 degrees from the zenith
    cv::Mat points_;               // CV_64FC2: the layer point seen at each pixel (layer_point)
};

}  // namespace dynsky
