// The advection-residual cloud model (glossary: "advect-residual"; networks/advect.py trains it,
// docs/networks-advect-residual.md measures it). Motion comes from a GIVEN flow, never from
// memory: one medium step advects the sky along the flow F and a small network only corrects
// (cloud growth and decay, what the flow cannot move, clear sky held still):
//
//   W      = E(I)(x - F(x)) + B - E(B)(x - F(x))   the warp (motion/advection.h warp_in_disc) of the
//                                                   clouds only: B is the clear background
//                                                   (motion/network_form.h clear_background) of the
//                                                   sky's sun, which stays where it is
//   next   = clamp(net([W, I, F / (flow_scale N)]), 0, 1), 0 outside the disc
//
// at the networks' resolution N on the network form (motion/network_form.h). A rollout keeps F
// fixed (constant velocity) and feeds each prediction back. A sky of any resolution is stepped at
// its own resolution: its state is warped there along the flow resampled to it, and the network's
// correction (next - W at N) is added, upsampled; so the sky keeps its fine detail.
//
// Where F comes from (CloudMotion): the previous frame (Farneback on the network form, previous ->
// current, scaled to one step), a wind (motion/flow.h wind_flow), or, with neither, the default
// wind (Wind{}: from the west at 12 m/s, clouds at 1500 m).
//
// Model folder: model.json (format dynsky-cloud-model, version 2, kind advect-residual) and
// model.onnx (1 x 8 x N x N -> 1 x 3 x N x N). Kind "advect" without a folder is the same step
// with no network (next = W): the pure-advection baseline.
//
// Parameters (defaults): folder (required for the network), motion (the default wind).
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <nlohmann/json.hpp>
#include <vector>

#include "motion/cloud_layer_paths.h"
#include "motion/flow.h"
#include "motion/network_form.h"
#include "motion/step_model.h"
#include "sky/sky_image.h"

namespace dynsky {

// What moves the clouds: a previous frame (taken previous_dt seconds before the sky being moved;
// 0: one step before), else a wind, else the default wind.
struct CloudMotion {
    std::optional<Wind> wind;
    std::shared_ptr<const SkyImage> previous;
    double previous_dt = 0;
};

// The seconds between a previous frame and the sky: `given` when positive, else their clocks'
// difference (dynsky:time) when both files carry one (0 included: a sequence's first frame) and
// they are not both 0, else the difference of the UTC times their imports recorded, else 0 (one
// medium step). Throws naming both files
// when their clocks put the previous frame at or after the sky, or more than an hour before it (not
// a previous frame of the same sky: its motion says nothing about this one's).
double previous_frame_gap(const SkyImage& sky, const SkyImage& previous, double given, const std::string& sky_name,
                          const std::string& previous_name);
// The note given when previous_frame_gap returns 0 (neither file says when it was taken).
std::string unknown_previous_gap_note(const std::string& sky_name, const std::string& previous_name);
// A warning when the previous frame lies more than kLongPreviousGapSeconds before the sky, else "":
// over such a gap clouds change shape, and the motion measured between the two frames comes out
// slow (ARM day, 17:05Z from frames 30 / 60 / 120 / 300 s before: 7.8 / 6.3 / 4.5 / 1.0 px per 30 s
// step at 256 px against about 9 seen), silently freezing the clouds of an animation.
inline constexpr double kLongPreviousGapSeconds = 90;
std::string long_previous_gap_warning(double gap_seconds, const std::string& sky_name,
                                      const std::string& previous_name);

// The flow of one rollout, per step, at one resolution. A measured flow (from a previous frame) is
// trusted for the first steps and relaxes to the uniform wind that best explains it
// (motion/flow.h fit_wind): measured - wind decays as exp(-(k - 1) / relax_steps). A fixed
// non-uniform flow, iterated for hours, shears every cloud into streaks; a uniform wind moves the
// layer as a whole. From a wind: that wind's flow throughout.
//
//
// The clear background (motion/network_form.h clear_background) is held still where it is seen:
// only the clouds move. Under a wind it is held fully. With a measured flow it is held in
// proportion to the clear share of the start sky (1 - cloud cover): Farneback's noise on clear sky
// would otherwise shuffle its gradients (+0.7 dB one step ahead on the clear ARM morning), while an
// overcast sky hides the background, and holding an assumed one there costs accuracy (-0.3 to
// -2.4 dB on the overcast Mobotix and ARM dusk sequences).
struct CloudFlow {
    cv::Mat measured;              // CV_32FC2, pixels per step
    cv::Mat wind;                  // empty: `measured` throughout
    double relax_steps = 6.0;      // default: 6 steps (3 minutes at 30 s)
    bool hold_background = false;  // fully (a wind); else by the clear share of the start sky
    // The clouds ride one layer under the (fitted) wind, recycled when they leave the view
    // (motion/cloud_layer_paths.h), so rollouts of any length keep moving; false: the flow's own
    // paths, with sky from beyond the horizon shown as the start showed it.
    bool recycle = false;
    // With a measured flow: what of `measured` (MeasuredMotion::confirmed) moves the clouds on
    // the first step only, then rides along with them: confirmed - (wind + agreement x (smoothed -
    // wind)). The rest, the smoothed flow's departure from the wind where the flow measured back
    // agrees, is kept for several steps (CloudRollout).
    cv::Mat detail;
    // How much of the network's correction a rollout's first step adds (0..1; later steps add all
    // of theirs): 1 unless a previous frame says otherwise (AdvectResidualNetwork::correction_gain).
    // Scaling every step's lost 0.05-0.09 dB six steps ahead on the validation frames.
    double correction_gain = 1.0;
    // With a measured flow: the uniform wind fitted to it (at the layer's assumed height), which the
    // flow relaxes to; reported to users, who otherwise cannot tell what motion a pair gave.
    std::optional<Wind> fitted_wind = std::nullopt;
    cv::Mat at(int k) const;  // the flow of step k = 1, 2, ...
    CloudFlow resized(int n) const;
    static CloudFlow from_wind(const cv::Mat& flow) { return CloudFlow{flow, cv::Mat(), 0.0, true, true, cv::Mat()}; }
    static CloudFlow constant(const cv::Mat& flow) { return CloudFlow{flow, cv::Mat(), 0.0, false, false, cv::Mat()}; }
    // A measured motion (per step of dt), relaxing to the wind fitted to its smoothed field (inside
    // 80 % of the radius, and outside the sun's aureole, 30 degrees, when it is given); the first
    // step's flow is the confirmed one.
    static CloudFlow from_measured(const MeasuredMotion& motion, double dt,
                                   const std::optional<Vec3d>& sun = std::nullopt);
};

struct AdvectResidualInfo {
    std::string name, folder, kind = "advect-residual";
    int resolution = 64;          // N
    int import_resolution = 256;  // where the training flows were measured
    double dt = 30.0;             // the cadence trained on most (the flow input sets the speed)
    double flow_scale = 0.08;     // flow channels = F / (flow_scale N)
    bool compensated = false;     // W input is warp(I) + B - warp(B) ("base": "compensated")
    NetworkFormParams form;
};

class AdvectResidualNetwork {
  public:
    // Reads FOLDER/model.json and FOLDER/model.onnx and runs the network once on zeros. Throws
    // dynsky::Error naming the file and the problem (missing, wrong format, version or kind, not
    // ONNX, wrong shapes).
    static AdvectResidualNetwork load(const std::string& folder);
    // No network: next = W (kind "advect"), with the form and N given.
    static AdvectResidualNetwork pure_advection(int resolution = 64, double dt = 30.0);

    const AdvectResidualInfo& info() const { return info_; }
    bool has_network() const { return !net_.empty(); }

    // The raw network on its input [W, I, F / (flow_scale N)] (N x N CV_32FC(8)): N x N CV_32FC3.
    cv::Mat run(const cv::Mat& input);
    // The network's input for image I (N x N CV_32FC3) and flow F (N x N CV_32FC2): [W, I, F /
    // (flow_scale N)], with W = warp(I) + compensation when the model was trained on the
    // background-compensated warp (model.json "base": "compensated"; compensation = B - warp(B),
    // empty when the sun, hence B, is unknown).
    cv::Mat network_input(const cv::Mat& image, const cv::Mat& flow, const cv::Mat& compensation = cv::Mat()) const;
    // One step at N: warp (+ compensation), network, clamp, 0 outside the disc.
    cv::Mat step_network(const cv::Mat& image, const cv::Mat& flow, const cv::Mat& compensation = cv::Mat());

    // K recursive steps of an HDR sky of any resolution along a fixed flow given at the sky's
    // resolution (pixels per step); on_step(k, sky_k) for k = 1..K. The sun (pixels the network
    // form clips) is filled before the first step and the input's put back into every output.
    // background: the clear background at the sky's resolution; empty: made from the sky's sun.
    void rollout(const SkyImage& sky, const CloudFlow& flow, int steps,
                 const std::function<void(int, const SkyImage&)>& on_step, cv::Mat background = cv::Mat());

    // The clear background of a sun at n (computed at most at 256 px and upsampled: it is smooth).
    cv::Mat background(const Vec3& sun, int n, double turbidity = 3.0) const;

    // The same on the network form: state (R x R CV_32FC3, any R >= N, no saturated pixels) and
    // flow (R x R CV_32FC2, per step); on_step(k, state_k) for k = 1..K.
    // With a background (the clear sky under the clouds, motion/network_form.h clear_background, at
    // the state's resolution), only the clouds move: each step adds B - warp(B), so the background's
    // own gradients (horizon, aureole) stay where they are.
    void rollout_network_form(const cv::Mat& state, const CloudFlow& flow, int steps,
                              const std::function<void(int, const cv::Mat&)>& on_step,
                              const cv::Mat& background = cv::Mat());

    // The flow per step of length dt at resolution n for a sky and its motion (see CloudMotion).
    // With a previous frame, its correction_gain is measured on the pair (correction_gain).
    CloudFlow motion_flow(const SkyImage& sky, const CloudMotion& motion, double dt, int n);

    // How much of the network's correction this camera's sky takes, measured on the one pair a
    // previous frame gives: the share s in [0, 1] of the correction C = net(P, F) - warp(P, F)
    // that best explains what the warp alone misses of the current frame, argmin |warp + s C -
    // current|^2 over the pixels seen in both. The network was trained on a few days of two
    // cameras; on a camera or a light it has not seen its correction can cost more than it gives
    // (held-out overcast Mobotix morning, one step ahead), and the pair in hand says which.
    // previous, current: the network form (R x R CV_32FC3, R >= N, saturated pixels filled); seen:
    // CV_8UC1 at R; flow: previous -> current at R (the confirmed one). 1 without a network.
    double correction_gain(const cv::Mat& previous, const cv::Mat& current, const cv::Mat& seen, const cv::Mat& flow);

  private:
    AdvectResidualInfo info_;
    cv::dnn::Net net_;
};

// A sky of unknown scale (no sun direction: no time and place it could have been calibrated with,
// e.g. an uncalibrated photograph in [0, 1] or an HDRI of its own scale) is brought to the
// networks' range by a factor that puts its median luminance at kUnknownScaleMedian (W m^-2 sr^-1,
// about a daylight sky's), and back after: in the networks' log map (0..300) a [0, 1] photograph
// was nearly black and its clear sky 50x dimmer than any background. 1 for a sky with its sun. A
// sky whose brightest pixels show a sun (sun_from_brightest_pixels) is measured against the clear-sky
// model of that sun instead (motion/radiance_scale.h; 1 within its band): a clear sunset HDRI
// without metadata, put at median 20, was 8 x its model and read as cloud everywhere, its glow
// dragged across the sky.
constexpr double kUnknownScaleMedian = 20.0;
double model_scale(const SkyImage& sky);
SkyImage scaled_sky(const SkyImage& sky, double factor);

// SkyImage::filled as a mask (CV_8UC1, 255 = filled) at the sky's resolution; empty when none.
cv::Mat filled_mask(const SkyImage& sky);

// The glow of a start around its sun beyond the model's background (both N x N CV_32FC3 in the
// network form, `unit` its map), per 1-degree ring out to 35 degrees, in radiance, measured on the
// pixels `filled` (CV_8UC1, may be empty) does not mark: added to the background around the sun of
// every step, so that the glow neither reads as cloud nor moves. Shaped as a glow: falling away
// from the sun, and rising towards it no faster than the angle^-4 from the rings outside (cloud
// all around a sun is not its glow). Empty: none. Exposed for tests.
std::vector<cv::Vec3f> halo_excess(const cv::Mat& start, const cv::Mat& background, const Vec3d& sun,
                                   const UnitMapParams& unit, const cv::Mat& filled);

// One rollout in progress on the network form, semi-Lagrangian: the clouds are always read from the
// start image along their accumulated paths, not re-warped from the last step's image, so hours of
// steps do not blur them away. With a wind (CloudFlow::recycle) the paths are the layer's
// (motion/cloud_layer_paths.h: the wind's displacement, plus the measured flow's departure from it
// while it relaxes, recycled when the clouds leave the view); else the composed source positions
// of every step's warp. The network's corrections (its output minus the warp it was given) ride
// along as a field of their own. The network itself sees the last step's image at N, as it was
// trained.
//
// The network was trained on daylight skies (median radiance 0.3-40 W m^-2 sr^-1) and adds its
// corrections in the log map's units, where a dim sky lies near 0: its small bias there multiplied
// a clear twilight sky's radiance by 4.5, a night sky's by 40,000 and a dusk overcast (0.013) by 5
// within ten steps, where pure advection keeps them. Its corrections are therefore weighed by
// network_trust_of_brightness of the start's median radiance (its channels' mean in the log map,
// mapped back): all of them from 1 W m^-2 sr^-1 up,
// none at 0.1 and below (pure advection), log-linear between. None either for a start that is
// the model's clear sky: one that departs from its background (network form) by more than
// kClearStartTolerance on less than kClearStartShare of the disc, counted more than
// kClearStartSunDeg from the sun, has no cloud to change.
double network_trust_of_brightness(double median_radiance);
constexpr double kClearStartTolerance = 0.01, kClearStartShare = 0.002, kClearStartSunDeg = 5.0;
// The share of the disc where `start` departs from `background` (both network form, N x N CV_32FC3)
// by more than kClearStartTolerance in any channel.
double start_departs_from(const cv::Mat& start, const cv::Mat& background, const cv::Mat& disc);

class CloudRollout {
  public:
    // unseen (CV_8UC1, may be empty): pixels of the start whose cloud cannot be judged (the sun cut
    // out and the sky around it, motion/sun_patch.h sun_unseen_mask); they count as clear in
    // opacity(). sun: the background's (see set_background).
    // sun_seen_whole: the start shows its sun whole (sun_patch_share >= 0.5), so it is not overcast
    // whatever its colours (set_background). filled: see set_filled.
    CloudRollout(AdvectResidualNetwork* network, const cv::Mat& start, const CloudFlow& flow,
                 const cv::Mat& background = cv::Mat(), const cv::Mat& unseen = cv::Mat(),
                 const std::optional<Vec3d>& sun = std::nullopt, bool sun_seen_whole = false,
                 const cv::Mat& filled = cv::Mat());
    void set_sun_seen_whole(bool whole) { sun_seen_whole_ = whole; }  // for the next set_background
    const cv::Mat& advance();                                         // the next step's state
    int steps() const { return steps_; }
    const cv::Mat& state() const { return state_; }
    // The clear background (at the state's resolution) for the following steps; used only when the
    // flow holds the background. With its sun, clouds hide the aureole they cover (moved onto it
    // they do not shine with it; moved off it they do not take it along).
    void set_background(const cv::Mat& background, const std::optional<Vec3d>& sun = std::nullopt);
    // The unseen pixels' opacity is at least this, and that of the pixels within a degree and a
    // half of them at least 0.9 of it, from the next set_background (the input's sun was dimmed by
    // a cloud there, however clear the sky around it looks).
    void set_unseen_opacity(double a) { unseen_opacity_ = a; }
    // Pixels an import filled (CV_8UC1 at the state's resolution, may be empty: SkyImage::filled):
    // like the unseen ones they take the opacity of the clouds around them, from the next
    // set_background. A TSI's shadow band runs through the sun, and its smooth fill, as bright
    // and white as the glare it crosses, read as cloud over the sun: a sun the next photographs
    // show went out on the first step.
    void set_filled(const cv::Mat& filled) { filled_ = filled; }
    // How opaque the clouds each pixel shows are (CV_32FC1, 0 clear .. 1 cloud): measured on the
    // start against the background (motion/sun_patch.h cloudiness) and carried with the clouds (the
    // network's corrections not included). The start's before the first step; empty without a
    // background.
    const cv::Mat& opacity() const { return carried_opacity_; }
    const cv::Mat& start_opacity() const { return opacity_; }
    // How far the clouds at the background's sun have moved since the start (pixels of the state):
    // the length of the summed flow at the sun (motion/sun_patch.h opacity_sun_weight's travel).
    double sun_travel_px() const { return cv::norm(sun_travel_); }
    // The share of the network's corrections the steps add (network_trust_of_brightness).
    double network_trust() const { return network_trust_; }

  private:
    AdvectResidualNetwork* network_;
    CloudFlow flow_, flow_small_;
    cv::Mat start_, start_ext_, state_, positions_, corrections_;
    cv::Mat background_, background_ext_, background_n_, disc_big_, disc_n_;
    std::unique_ptr<CloudLayerPaths> paths_;  // with a wind
    bool seam_chosen_ = false;
    bool clear_start_judged_ = false;    // whether the start was compared with its clear sky (set_background)
    cv::Mat departure_;                  // smoothed measured - wind flow (pixels per step), relaxing
    cv::Mat detail_;                     // the flow's confirmed detail: one step's displacement
    double departure_sum_ = 0;           // sum of its relaxation weights so far
    cv::Mat cloud_field_;                // cloud_brightness_field (cloud_signal_field without opacities)
    cv::Mat background_field_;           // scales the model's clear sky to the start's
    cv::Mat clouds_ext_;                 // start_ext_ - background_ext_: what the paths carry
    cv::Mat clouds_;                     // start_ - background_: what a pixel shows of its own start
    cv::Mat opacity_ext_;                // the start's a x background_, a, share_ (CV_32FC(5))
    cv::Mat cloud_own_ext_;              // a x the cloud's own radiance, a (CV_32FC4): what the tile carries
    cv::Mat opacity_, carried_opacity_;  // a at the start, and where the clouds have taken it
    cv::Mat unseen_, filled_;
    bool sun_seen_whole_ = false;
    double unseen_opacity_ = 0;
    cv::Mat share_;                       // circumsolar share (where a cloud hides the background)
    std::vector<cv::Vec3f> halo_excess_;  // the start's glow beyond the background, per ring (halo_excess)
    bool halo_measured_ = false;
    std::optional<Vec3d> sun_;  // the background's
    double background_weight_ = 1.0;
    double network_trust_ = 1.0;
    int steps_ = 0;
    cv::Vec2d sun_travel_ = cv::Vec2d(0, 0);
};

// The motion measured from a previous frame: Farneback flow previous -> current (and back) on the
// network form at min(256, N_sky) px (as the training flows were measured), smoothed and confirmed
// (motion/flow.h measured_motion), returned at resolution n in pixels at n (per the gap between the
// frames). A previous frame of another resolution is resampled to the sky's first.
MeasuredMotion network_form_flow(const SkyImage& previous, const SkyImage& current, const NetworkFormParams& form,
                                 int n);
// The two frames that motion is measured on: the network form at min(256, N_sky) px, saturated
// pixels filled, and the pixels seen in both (in the disc, clipped in neither, filled by an import
// in neither).
struct NetworkFormPair {
    cv::Mat previous, current, seen;
};
NetworkFormPair network_form_pair(const SkyImage& previous, const SkyImage& current, const NetworkFormParams& form);

// The step model: "network:FOLDER" for a folder of kind advect-residual, or "advect".
class AdvectResidualStepModel : public MediumStepModel {
  public:
    AdvectResidualStepModel(AdvectResidualNetwork network, CloudMotion motion);
    SkyImage step(const std::vector<std::shared_ptr<const SkyImage>>& history, double dt) override;
    std::string name() const override;
    double native_dt() const override { return network_.info().dt; }
    bool dt_is_fixed() const override { return false; }
    // The timeline's sun for the next step: the clear background is that sun's.
    void set_sun_direction(const Vec3d& d) override { sun_ = d.cast<float>(); }
    // CloudRollout::opacity and start_opacity, at most at 256 px (the sun's weight needs no more).
    cv::Mat last_cloud_opacity() const override { return last_opacity_; }
    cv::Mat input_cloud_opacity() const override { return input_opacity_; }
    void set_input_sun_cover(double c) override { sun_cover_ = c; }
    void set_input_sun_share(double s) override { told_sun_share_ = s; }
    cv::Mat last_step_flow() const override { return last_flow_; }

  private:
    AdvectResidualNetwork network_;
    CloudMotion motion_;
    CloudFlow flow_;  // at the sky's resolution, per step; measured at the first step
    double flow_dt_ = 0;
    std::unique_ptr<CloudRollout> rollout_;
    const SkyImage* rollout_input_ = nullptr;
    SkyImage front_;                     // the input upsampled to the network's resolution (when smaller)
    SkyImage scaled_input_;              // the input at model_scale (when it is not 1)
    double scale_ = 1.0;                 // model_scale of the input
    std::optional<Vec3> estimated_sun_;  // from the input's brightest pixels, when it has no sun
    cv::Mat sun_mask_;
    std::optional<double> input_sun_share_;  // how much of the clear sun the input shows (sun_weight_reference)
    std::optional<double> input_sun_look_;   // the look around the input's sun (estimate_sun_transmittance)
    cv::Mat background_;                     // of background_sun_ (recomputed when the sun has moved by 0.2 degrees)
    Vec3 background_sun_ = Vec3::Zero();
    std::optional<Vec3> sun_;  // from the timeline, else the sky's own
    cv::Mat last_opacity_, input_opacity_;
    double sun_cover_ = 0;
    std::optional<double> turbidity_;       // of the input's clear background (clear_sky_turbidity), found once
    std::optional<double> told_sun_share_;  // set_input_sun_share: the input's sun before the timeline cut it
    cv::Mat last_flow_;                     // the flow of the last step, at the given sky's resolution
};

// The kind of a model folder's model.json ("advect-residual", or "flownet-cloudnet" for the
// paper's v1 folders without a kind). Throws naming the file when it is missing or unreadable.
std::string cloud_model_kind(const std::string& folder);
// FOLDER/model.json, parsed once and checked to be a dynsky-cloud-model with a whole version; throws
// naming the file otherwise.
nlohmann::json read_model_description(const std::string& folder);

}  // namespace dynsky
