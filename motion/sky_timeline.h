// A sky at any time t from one input sky and a medium-timescale model (the paper's xi and Gamma).
//
// Medium steps: S_0 = the input, S_{i+1} = xi(S_0..S_i), one every Delta t, computed in order
// and cached (deterministic: the same steps whichever frames are asked for first). Between two
// steps, Gamma (the short timescale) uses the flow F_i re-estimated on the steps themselves
// (motion/advection.h, Farneback), at s = (t - i Delta t) / Delta t, in one of two forms:
//
// GammaKind::constant (the default): both steps advected along great arcs to the frame's moment and
// cross-faded by time,
//   Upsilon(Lambda(S_i, F_i, +s), Lambda(S_{i+1}, F_i, -(1 - s)), s),
// so clouds move and brightness changes at a constant pace across the whole interval (two
// advections per frame).
//
// GammaKind::paper (the paper's): two key images,
//   s = 0    S_i
//   s = 1/3  Lambda(S_i, F_i, +1/3)       the earlier step advected forward a third of the way
//   s = 2/3  Lambda(S_{i+1}, F_i, -1/3)   the later step advected backward a third of the way
//   s = 1    S_{i+1}
// blended linearly between consecutive keys: one blend per frame, but every change of appearance
// between the steps happens in the middle third (docs/animation.md, docs/gamma-pace.png).
//
// Both are exactly S_i at t = i Delta t and exactly S_{i+1} at (i+1) Delta t; the model runs once
// per Delta t whatever the frame rate.
//
// The sun is taken out of the input before any step (motion/sun_patch.h) and put back into every
// frame at the sun's direction for that time: fixed, or following the clock when the timeline knows
// where and when the input was taken (SunClock). It is put back dimmed by the clouds the model moved
// over it: the frame's sun transmittance, estimated from the sky around the sun, relative to the
// input's (motion/sun_patch.h relative_sun_transmittance). Models that make their own sun
// (ProceduralStepModel) keep it.
//
// Stored timelines (motion/sky_timeline_store.cpp, glossary "stored timeline"): save() writes the
// steps, flows and sun patches of the whole duration to a folder once; load() gives a timeline that
// reads them instead of running the model, so a frame rendered from it anywhere (a render farm's
// task) has exactly the pixels of the same frame of one run that computed the steps itself.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "motion/flow.h"
#include "motion/step_model.h"
#include "motion/sun_patch.h"
#include "sky/sky_image.h"
#include "sky/sun_position.h"

namespace dynsky {

// Where and when the input sky was taken: the sun then follows the clock.
struct SunClock {
    UtcTime start;  // UTC of t = 0
    GeoLocation where;
};

// Which in-between Gamma makes (above).
enum class GammaKind { constant, paper };
// "constant" | "paper"; anything else throws dynsky::Error naming --gamma.
GammaKind parse_gamma(const std::string& name);
const char* gamma_name(GammaKind kind);

struct SkyTimelineTimings {
    double medium_seconds = 0;  // xi, flow estimation and the two key images, summed over this run
    int medium_steps = 0;       // steps computed by this run
    double gamma_seconds = 0;   // the last sky_at's blend and sun insertion
};

class SkyTimeline {
  public:
    SkyTimeline(SkyImage input, std::unique_ptr<MediumStepModel> model, double dt,
                std::optional<SunClock> clock = std::nullopt, SkyFlowParams flow_params = {});

    // The input's radiance scale when it was divided out before the steps (motion/radiance_scale.h):
    // every frame sky_at gives is multiplied back by it, so the frames keep the input's units. 1: none.
    void set_radiance_scale(double factor) { radiance_scale_ = factor; }
    double radiance_scale() const { return radiance_scale_; }

    // Which in-between (default constant); changing it drops the cached in-betweens, not the steps.
    void set_gamma(GammaKind kind);
    GammaKind gamma() const { return gamma_; }

    // Gamma at t (seconds since the input; t >= 0). Computes and caches the steps it needs.
    SkyImage sky_at(double t);
    // The same into *out, reusing its pixel storage: per-frame use without allocating (and
    // page-faulting) 50 MB for every 2048 sky.
    void sky_at(double t, SkyImage* out);
    // The medium step S_i (i >= 0).
    std::shared_ptr<const SkyImage> step(int i);
    // The paper's first key image of interval i, at s = 1/3 (benchmarks time building the keys).
    const SkyImage& key_third(int i);
    const cv::Mat& flow(int i);  // F_i: from S_i to S_{i+1}

    double dt() const { return dt_; }
    const SkyTimelineTimings& timings() const { return timings_; }
    // The weight the sun was put back with in the last sky_at (1: as in the input; 0: covered).
    double last_sun_weight() const { return last_sun_weight_; }
    const MediumStepModel& model() const { return *model_; }
    // The sun direction at t (the input's, or the clock's); nullopt when unknown.
    std::optional<Vec3d> sun_direction_at(double t) const;

    // Writes steps 0..last_step and flows 0..last_step-1 into `folder`, each step as soon as it is
    // computed: step_NNNN.exr (float), flow_NNNN.npy and timeline.json, rewritten after step 1,
    // every 10 s, after the last step and when an error stops the run, with everything else (sun patches, clock, model, `settings`: what the caller
    // checks on load), so that a run stopped midway leaves a timeline of the steps it finished.
    // Every file atomic. quiet: no progress bar.
    void save(const std::string& folder, int last_step, const std::string& settings, bool quiet = true);
    // A timeline reading a saved folder (steps loaded when first needed). *settings gets the saved
    // settings. Throws dynsky::Error naming the folder when it is not a complete stored timeline.
    static SkyTimeline load(const std::string& folder, std::string* settings = nullptr);
    // The last step a loaded timeline holds (-1: computes its steps); asking beyond it throws.
    int stored_last_step() const { return stored_last_step_; }
    // Reads every stored step and flow once (a loaded timeline): throws dynsky::Error naming the
    // first file missing or damaged, so that a rerun keeping the folder keeps only a whole one.
    void verify_stored();
    // The last step sky_at needs for times up to t (t > 0: the step after the interval holding t).
    int last_step_for(double t) const;
    // The most medium steps one timeline may span (as many as an animation may have frames).
    static constexpr double kMaxSteps = 100000;
    // Throws dynsky::Error naming --duration and --dt when `seconds` spans more than kMaxSteps
    // steps: a --dt of 1e-9 s (or a --duration of 1e9 s) would otherwise compute steps for days.
    void check_span(double seconds) const { check_span(seconds, dt_); }
    static void check_span(double seconds, double dt);

  private:
    SkyTimeline() = default;
    std::shared_ptr<const SkyImage> stored_step(int i);
    cv::Mat stored_flow(int i) const;
    struct Interval {
        cv::Mat flow;
        SkyImage third, two_thirds;  // the paper's keys: made when first needed
        bool has_keys = false;
    };
    Interval& interval(int i);
    Interval& interval_with_keys(int i);

    std::unique_ptr<MediumStepModel> model_;
    double dt_ = 0;
    double radiance_scale_ = 1.0;
    GammaKind gamma_ = GammaKind::constant;
    std::optional<SunClock> clock_;
    SkyFlowParams flow_params_;
    std::vector<std::shared_ptr<const SkyImage>> steps_;
    std::map<int, Interval> intervals_;
    std::vector<SunPatch> suns_;  // per step: the sun cut out of it (all the input's for models without a sun)
    std::optional<Vec3d> input_sun_;
    double input_look_transmittance_ = 1.0;  // around the input's sun, after the cut
    double last_sun_weight_ = 1.0;
    // Per step (0: the input), the opacity of the clouds the model moved (MediumStepModel::
    // last_cloud_opacity; empty: none), and the sun's weight at s in interval i from them.
    std::vector<cv::Mat> model_opacity_;
    // Per step (0: none), the motion the model gave it (MediumStepModel::last_step_flow; empty:
    // unknown, measured between the steps).
    std::vector<cv::Mat> model_flow_;
    // relative: over the input's opacity at the sun (in [0, 1]); else the transmittance itself.
    std::optional<double> model_sun_weight(int i, double s, const Vec3d& sun, bool relative = true);
    // How far the clouds at the sun have moved by step i + s, in pixels of an n px sky: the
    // intervals' flows (the same whether computed or stored) summed at the sun of each interval's
    // start, remembered per step; once past the sun's diameter no further flow is read.
    double sun_travel_px(int i, double s, const Vec3d& sun, int n);
    std::vector<cv::Vec2d> travel_sums_;  // [k]: the summed flow at the sun over intervals 0..k-1 (pixels at travel_n_)
    int travel_n_ = 0;
    // The input's sun when a cloud dimmed it (it holds under half the clear sun's irradiance, or
    // nothing was cut): the clear sun put back by the frame's own transmittance instead, made
    // when first needed (empty otherwise). Set by covered_input_sun().
    bool covered_checked_ = false;
    SunPatch clear_sun_;
    double covered_input_transmittance_ = 0.0;  // at the covered input's sun, as frames measure theirs
    const SunPatch& covered_input_sun(int n);
    // The input's cut sun over the clear sun's irradiance (sun_patch_share at the input's
    // resolution; 0 without a sun), worked out when first needed.
    std::optional<double> input_sun_share_;
    double input_sun_share();
    double input_time_ = 0;
    std::string input_units_;  // dynsky:units of the input, given to every frame
    // With a clock, the clear sky under the clouds follows the sun: a frame at t is the moved sky
    // times the Hosek-Wilkie background (no sun, the input's turbidity) at the clock's sun at t
    // over the one at t = 0, pixel by pixel and channel by channel, and its sun is put back times
    // the model's solar irradiance at t over at 0 (the models move the t = 0 sky: an animation
    // through sunset kept the afternoon's sky, 4 x too bright, and its sun). Not for models that
    // make their own sky (procedural). Returns the sun's factor; the start's background is kept
    // per resolution.
    Color relight_to_clock(double t, SkyImage* out);
    int relight_n_ = 0;
    std::vector<float> relight_start_;
    double relight_turbidity_ = 3;
    bool relight_warned_ = false;
    SkyTimelineTimings timings_;
    std::string stored_folder_;  // a loaded timeline's folder (steps and flows read from there)
    int stored_last_step_ = -1;
    std::string stored_steps_json_;  // its steps' entries in timeline.json (file, time, sun, source)
    // timeline.json as it was read (inode, size, modification time): checked after each step or
    // flow read later, since a keys run replacing the timeline meanwhile (it removes timeline.json
    // first) gave frames of two timelines under the first one's settings.
    std::string stored_identity_;
    void check_stored_unchanged() const;
};

// Upsilon: (1 - w) a + w b, pixel by pixel (same resolution); metadata from a.
SkyImage blend_skies(const SkyImage& a, const SkyImage& b, double w);
void blend_skies(const SkyImage& a, const SkyImage& b, double w, SkyImage* out);

}  // namespace dynsky
