// A sky at any time t from one input sky and a medium-timescale model (the paper's xi and Gamma).
//
// Medium steps: S_0 = the input, S_{i+1} = xi(S_0..S_i), one every Delta t, computed in order
// and cached (deterministic: the same steps whichever frames are asked for first). Between two
// steps, Gamma (the short timescale) builds two key images from the flow F_i re-estimated on the
// steps themselves (sky/advection.h, Farneback):
//   s = 0    S_i
//   s = 1/3  Lambda(S_i, F_i, +1/3)       the earlier step advected forward a third of the way
//   s = 2/3  Lambda(S_{i+1}, F_i, -1/3)   the later step advected backward a third of the way
//   s = 1    S_{i+1}
// and blends linearly (Upsilon) between consecutive keys, s = (t - i Delta t) / Delta t. Gamma is
// exactly S_i at t = i Delta t and exactly S_{i+1} at (i+1) Delta t; frames at any rate cost one
// blend each, the model runs once per Delta t.
//
// The sun is taken out of the input before any step (its few bright pixels, inpainted over with
// cv::inpaint) and put back into every frame at the sun's direction for that time: fixed, or
// following the clock when the timeline knows where and when the input was taken (SunClock).
// Models that make their own sun (ProceduralStepModel) keep it.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "sky/advection.h"
#include "sky/procedural_clouds.h"
#include "sky/sky_image.h"
#include "sky/sun_position.h"

namespace dynsky {

// xi: the next medium step from the steps so far (history.back() is the latest; at least one).
// The result's time must be history.back().time_seconds + dt.
class MediumStepModel {
  public:
    virtual ~MediumStepModel() = default;
    virtual SkyImage step(const std::vector<std::shared_ptr<const SkyImage>>& history, double dt) = 0;
    virtual std::string name() const = 0;
    // True when the model's skies already hold the right sun (the timeline then leaves it alone).
    virtual bool makes_own_sun() const { return false; }
    // Where the sun is for the next step (models that make their own sun follow it).
    virtual void set_sun_direction(const Vec3d&) {}
    // The Delta t the model was made for (a trained network's), 0 when any is fine.
    virtual double native_dt_seconds() const { return 0.0; }
};

// Flow extrapolation: Farneback flow of the last two steps, applied once more (great-arc
// advection). From a single input sky there is no motion to measure yet: the first step drifts
// the sky by `initial_wind`, a rotation about a horizontal axis (a uniform wind aloft).
class FlowExtrapolationStepModel : public MediumStepModel {
  public:
    // wind_from_deg: where the wind blows from (clockwise from north); angular speed of the
    // cloud field in degrees per second as seen overhead.
    FlowExtrapolationStepModel(double wind_from_deg = 270.0, double degrees_per_second = 0.25,
                               SkyFlowParams flow_params = {});
    SkyImage step(const std::vector<std::shared_ptr<const SkyImage>>& history, double dt) override;
    std::string name() const override { return "flow-extrapolation"; }

  private:
    double wind_from_deg_, degrees_per_second_;
    SkyFlowParams flow_params_;
};

// The procedural sky's own next frame (ground truth motion; sky/procedural_clouds.h).
class ProceduralStepModel : public MediumStepModel {
  public:
    explicit ProceduralStepModel(const ProceduralSkyParams& params) : sky_(params) {}
    SkyImage step(const std::vector<std::shared_ptr<const SkyImage>>& history, double dt) override;
    std::string name() const override { return "procedural"; }
    bool makes_own_sun() const override { return true; }
    void set_sun_direction(const Vec3d& d) override { sky_.set_sun_direction(d); }
    ProceduralSky& sky() { return sky_; }

  private:
    ProceduralSky sky_;
};

// The trained networks (sky/cloud_model.h, CloudModel::step) from a model folder.
std::unique_ptr<MediumStepModel> make_network_step_model(const std::string& folder);

// Where and when the input sky was taken: the sun then follows the clock.
struct SunClock {
    UtcTime start;  // UTC of t = 0
    GeoLocation where;
};
UtcTime add_seconds(const UtcTime& t, double seconds);

// The sun's pixels cut out of a sky (relative to the sun's pixel) with their excess radiance.
struct SunPatch {
    std::vector<int> di, dj;
    std::vector<Color> excess;
    bool empty() const { return di.empty(); }
};
// Finds the sun near sky.sun_direction (pixels within 1 degree + 2 px brighter than 20x the
// surrounding median), inpaints them (cv::inpaint, per channel on log radiance) and returns the
// cut-out. No sun direction, or no bright pixels there: an empty patch and the sky unchanged.
SunPatch remove_sun(SkyImage* sky);
// Adds weight x the patch back centred on the pixel of `direction` (skipped below the horizon).
void insert_sun(SkyImage* sky, const SunPatch& patch, const Vec3d& direction, double weight = 1.0);

struct SkyTimelineTimings {
    double medium_seconds = 0;  // xi, flow estimation and the two key images, summed over this run
    int medium_steps = 0;       // steps computed by this run
    double gamma_seconds = 0;   // the last sky_at's blend and sun insertion
};

class SkyTimeline {
  public:
    SkyTimeline(SkyImage input, std::unique_ptr<MediumStepModel> model, double dt_seconds,
                std::optional<SunClock> clock = std::nullopt, SkyFlowParams flow_params = {});

    // Gamma at t (seconds since the input; t >= 0). Computes and caches the steps it needs.
    SkyImage sky_at(double t);
    // The same into *out, reusing its pixel storage: per-frame use without allocating (and
    // page-faulting) 50 MB for every 2048 sky.
    void sky_at(double t, SkyImage* out);
    // The medium step S_i (i >= 0).
    std::shared_ptr<const SkyImage> step(int i);
    // The key images of interval i: at s = 1/3 and 2/3.
    const SkyImage& key_third(int i);
    const SkyImage& key_two_thirds(int i);
    const cv::Mat& flow(int i);  // F_i: from S_i to S_{i+1}

    double dt() const { return dt_; }
    const SkyTimelineTimings& timings() const { return timings_; }
    const MediumStepModel& model() const { return *model_; }
    // The sun direction at t (the input's, or the clock's); nullopt when unknown.
    std::optional<Vec3d> sun_direction_at(double t) const;

  private:
    struct Interval {
        cv::Mat flow;
        SkyImage third, two_thirds;
    };
    Interval& interval(int i);

    std::unique_ptr<MediumStepModel> model_;
    double dt_;
    std::optional<SunClock> clock_;
    SkyFlowParams flow_params_;
    std::vector<std::shared_ptr<const SkyImage>> steps_;
    std::map<int, Interval> intervals_;
    std::vector<SunPatch> suns_;  // per step: the sun cut out of it (all the input's for models without a sun)
    std::optional<Vec3d> input_sun_;
    double input_time_ = 0;
    SkyTimelineTimings timings_;
};

// Upsilon: (1 - w) a + w b, pixel by pixel (same resolution); metadata from a.
SkyImage blend_skies(const SkyImage& a, const SkyImage& b, double w);
void blend_skies(const SkyImage& a, const SkyImage& b, double w, SkyImage* out);

}  // namespace dynsky
