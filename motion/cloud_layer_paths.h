// Where the cloud seen at each pixel was at the start of a rollout, for clouds carried by a uniform
// wind on one layer, RECYCLED so that a rollout of any length keeps moving (glossary: "recycled
// layer"). Used by motion/advect_residual.h CloudRollout when the motion has a wind.
//
// Parameters (defaults):
//   tile_zenith_deg  = 60   the recycled tile: the layer repeats along the wind with a period of
//                           twice the ground radius seen within this zenith angle (where the start
//                           is foreshortened max_stretch times the zenith's)
//   seam_range       = 0.2  the seam where one pass of the tile meets the next lies within this
//                           fraction of that radius of the tile's upwind edge
//   seam_slope       = 1    the seam's largest slope against the wind (layer units per unit)
//   seam_band        = 0.2  past the seam, the pass before takes its leave over this fraction of a
//                           pass (a linear fade: no seam is clear on every sky)
//   max_stretch      = 4    a pixel upwind of the seam at the start keeps reading the real start
//                           image while the start's pixels it reads are at most this many times
//                           more foreshortened than its own (sec^2 of the zenith angle)
//   entry_band       = 0.25 beyond that, its fade into the tile, as a fraction of that
//                           trigger's ground radius
//   seam_edge_band   = 0.5  pixels upwind of the seam at the start within this fraction of the
//                           tile's radius of the seam line switch as those downwind of it do,
//                           blending the two rules (else they met at a hard, jagged arc fixed in
//                           the image, seen 3-9 minutes into `sky predict --prev` rollouts)
//
// Why: the layer is a plane at height h; a wind translates it by w per step (units of h). The sky
// seen at a pixel is the layer point P(x) = tan(theta) (u, v) / r; after k steps its cloud was at
// P(x) - k w. Read from the start image, that is exact while the point is in view, but within
// minutes it is near the upwind horizon, where the start is foreshortened 10-1000x: the sky fills
// with streaks and, past 88 degrees, has nothing left to show. Here the layer is taken as periodic
// along the wind: each streamline (constant cross-wind coordinate c) repeats its strip
// a(c) <= s < a(c) + 2R along the wind (one period for all streamlines, so the passes do not shear
// the clouds), every other pass mirrored across the wind (c -> -c) so that the repetition is twice
// as long and less regular. The seam a(c) (symmetric in c, for the mirror) is cut where the start
// is clearest at both its ends (choose_seam: least opacity, by dynamic programming across the
// wind), so where the sky allows passes meet without cutting a cloud (past it, the pass before
// fades out over seam_band). A pixel reads the real start until its path crosses the seam, then
// the tile, so the first pass is the real start image and short rollouts (minutes) are unchanged.
// Entered at a fixed ring (every pixel at 4x its own foreshortening) the tile showed a circular
// seam (docs/networks-advect-residual.md); only pixels upwind of the seam at the start still are,
// blended near the seam line into the rule of those downwind of it (seam_edge_band).
#pragma once

#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace dynsky {

struct CloudLayerPathsParams {
    double tile_zenith_deg = 60.0;
    double seam_range = 0.2;
    double seam_slope = 1.0;
    double seam_band = 0.2;
    double max_stretch = 4.0;
    double entry_band = 0.25;
    double seam_edge_band = 0.5;
};

// Zenith angles beyond it see the layer too far off to follow (tan grows without bound): 88 deg.
inline constexpr double kMaxLayerZenith = 88.0 * 3.14159265358979323846 / 180.0;

// The layer point seen at continuous pixel position (x, y) of an n x n fisheye (units of the layer
// height; image axes; zenith angles beyond kMaxLayerZenith are taken at it), and back.
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

    // Cuts the seam through the clearest sky of the start: opacity (CV_32FC1, n x n, 0 clear .. 1
    // cloud). Without it the seam is straight, across the wind at the tile's upwind edge.
    void choose_seam(const cv::Mat& opacity);

    // The seam: the along-wind coordinate a(c) where pass j meets pass j + 1 (units of the layer
    // height; c beyond the range searched takes the last value).
    double seam(double c) const;

    enum Read { kRealRead = 0, kTileRead = 1, kLeavingRead = 2, kOwnRead = 3, kReadCount = 4 };

    // Up to four reads per pixel for step k (k may be fractional): positions (CV_32FC2 pixel
    // coordinates in the start image) and weights (CV_32FC1) that sum to 1: the real start image
    // along the layer's path (kRealRead), the recycled tile's pass (kTileRead), the pass before it
    // taking its leave just past the seam (kLeavingRead), and the pixel itself
    // (kOwnRead: where the path reads the outermost 3 % of the radius, or the pixel is past 88
    // degrees).
    struct Reads {
        std::array<cv::Mat, kReadCount> positions, weights;
    };
    Reads at(double k) const;

    // False when the wind is too weak to ever leave the view (no recycling needed).
    bool moving() const { return moving_; }
    double period() const { return 2.0 * tile_radius_; }  // along the wind, units of the layer height
    cv::Vec2d along() const { return along_; }            // the wind's direction on the layer

  private:
    int n_;
    cv::Vec2d step_, along_, across_;
    CloudLayerPathsParams params_;
    double tile_radius_ = 0;
    bool moving_ = false;
    double seam_step_ = 0;         // spacing of seam_ across the wind
    std::vector<double> seam_;     // a(c) at c = i seam_step_, i >= 0 (symmetric in c)
    cv::Mat trigger_radius_;       // CV_64FC1: the ground radius at which each pixel starts to recycle
    std::vector<uint8_t> beyond_;  // pixels past 88 degrees from the zenith
    cv::Mat points_;               // CV_64FC2: the layer point seen at each pixel (layer_point)
};

}  // namespace dynsky
