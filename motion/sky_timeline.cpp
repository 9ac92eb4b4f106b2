#include "motion/sky_timeline.h"

#include "motion/radiance_scale.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <opencv2/photo.hpp>

#include "motion/advection.h"
#include "motion/radiance_scale.h"
#include "motion/network_form.h"
#include "sky/clear_sky.h"
#include "sky/fisheye.h"
#include "util/progress.h"
#include "util/error.h"

namespace dynsky {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

GammaKind parse_gamma(const std::string& name) {
    if (name == "constant") return GammaKind::constant;
    if (name == "paper") return GammaKind::paper;
    throw Error("--gamma '" + name +
                "': expected 'constant' (even pace, the default) or 'paper' (the paper's keys at 1/3 and 2/3)");
}

const char* gamma_name(GammaKind kind) { return kind == GammaKind::paper ? "paper" : "constant"; }

void blend_skies(const SkyImage& a, const SkyImage& b, double w, SkyImage* out) {
    if (a.resolution != b.resolution) throw Error("blend_skies: resolutions differ");
    out->resolution = a.resolution, out->time_seconds = a.time_seconds, out->sun_direction = a.sun_direction;
    out->source = a.source;
    out->rgb.resize(a.rgb.size());
    if (w == 0.0 || w == 1.0) {
        std::copy((w == 0.0 ? a : b).rgb.begin(), (w == 0.0 ? a : b).rgb.end(), out->rgb.begin());
        return;
    }
    const float wa = float(1.0 - w), wb = float(w);
    const size_t count = a.rgb.size(), chunk = 1 << 16;
    float* o = out->rgb.data();
    tbb::parallel_for(size_t(0), (count + chunk - 1) / chunk, [&](size_t c) {
        for (size_t k = c * chunk, e = std::min(count, k + chunk); k < e; ++k) o[k] = wa * a.rgb[k] + wb * b.rgb[k];
    });
}

SkyImage blend_skies(const SkyImage& a, const SkyImage& b, double w) {
    SkyImage out;
    blend_skies(a, b, w, &out);
    return out;
}

SkyTimeline::SkyTimeline(SkyImage input, std::unique_ptr<MediumStepModel> model, double dt,
                         std::optional<SunClock> clock, SkyFlowParams flow_params)
    : model_(std::move(model)), dt_(dt), clock_(clock), flow_params_(flow_params) {
    if (!(dt_ > 0)) throw Error("sky timeline: Delta t must be positive");
    validate_sky(input, input.source.empty() ? "input sky" : input.source);
    // A sky that does not record its sun (a downloaded HDRI): where its brightest pixels are. Left
    // in, the clouds' motion carried it off as a second sun beside the one put back.
    if (!input.sun_direction)
        if (const auto found = sun_from_brightest_pixels(input)) input.sun_direction = found->cast<float>();
    input_sun_ = to_double(input.sun_direction);
    input_time_ = input.time_seconds;
    input_units_ = input.units;
    // The sun is cut out where the image has it; it is put back where the clock says.
    suns_.push_back(remove_sun(&input));
    if (input_sun_) input_look_transmittance_ = estimate_sun_transmittance(input, *input_sun_);
    if (clock_) {
        validate_location(clock_->where);
        input.sun_direction = compute_sun_position(clock_->start, clock_->where).direction().cast<float>();
    }
    steps_.push_back(std::make_shared<const SkyImage>(std::move(input)));
    if (input_sun_) model_->set_input_sun_share(input_sun_share());
    if (input_sun_ && input_sun_share() < 0.5) model_->set_input_sun_cover(1.0 - input_sun_share());
}

double SkyTimeline::input_sun_share() {
    if (!input_sun_share_)
        input_sun_share_ = input_sun_ ? sun_patch_share(suns_[0], steps_[0]->resolution, *input_sun_) : 0.0;
    return *input_sun_share_;
}

double SkyTimeline::sun_travel_px(int i, double s, const Vec3d& sun, int n) {
    if (travel_n_ != n) travel_sums_.clear(), travel_n_ = n;
    if (travel_sums_.empty()) travel_sums_.push_back(cv::Vec2d(0, 0));
    const double far = sun_diameter_px(n);  // moved past the sun: nothing more to read
    auto flow_at = [&](int k) {
        const cv::Mat f = stored_last_step_ >= 0 ? stored_flow(k) : interval(k).flow;
        const cv::Vec2f v = flow_at_direction(f, sun_direction_at(k * dt_).value_or(sun));
        return cv::Vec2d(v[0], v[1]) * (double(n) / f.rows);
    };
    const int whole = i + (s > 0 ? 1 : 0);
    while (int(travel_sums_.size()) <= whole) {
        const cv::Vec2d last = travel_sums_.back();
        const int k = int(travel_sums_.size()) - 1;
        travel_sums_.push_back(cv::norm(last) >= far ? last : last + flow_at(k));
    }
    cv::Vec2d moved = travel_sums_[size_t(i)];
    if (s > 0 && cv::norm(moved) < far) moved += s * (travel_sums_[size_t(i) + 1] - travel_sums_[size_t(i)]);
    return cv::norm(moved);
}

std::optional<double> SkyTimeline::model_sun_weight(int i, double s, const Vec3d& sun, bool relative) {
    auto opacity = [&](int k) { return size_t(k) < model_opacity_.size() ? model_opacity_[size_t(k)] : cv::Mat(); };
    const cv::Mat o0 = opacity(0), a = opacity(i), b = s > 0 ? opacity(i + 1) : a;
    if (o0.empty() || a.empty() || b.empty()) return std::nullopt;
    double t = sun_transmittance_of_opacity(a, sun);
    if (s > 0) {
        // Between two steps the clouds move as Gamma moves them: what covers the sun at s was at
        // sun - s F in step i and will be at sun + (1 - s) F in step i + 1 (F: the interval's flow
        // at the sun). Where the two disagree (a cloud's edge at the sun; the flow is estimated),
        // the smaller: a sun is behind a cloud or not, and cross-faded like the skies it shone at
        // half strength through a frame the truth had it covered. On ten procedural skies whose
        // cumulus crosses the sun the mean illuminance error was 12.9 % so, 13.8 % cross-faded.
        const cv::Mat& flow = interval(i).flow;
        const int n = flow.rows;
        double x, y;
        fisheye::pixel_from_direction(sun, n, &x, &y);
        const cv::Vec2f f = flow_at_direction(flow, sun);
        const Vec3d from = fisheye::direction_from_pixel(x - s * f[0], y - s * f[1], n);
        const Vec3d to = fisheye::direction_from_pixel(x + (1 - s) * f[0], y + (1 - s) * f[1], n);
        t = std::min(sun_transmittance_of_opacity(a, from), sun_transmittance_of_opacity(b, to));
    }
    // Relative to the input's cover at the sun, never more than its sun showed (opacity_sun_weight).
    if (!relative) return std::clamp(t, 0.0, 1.0);
    // How far the clouds at the sun have moved by then (the same for a computed and a stored
    // timeline: a farm's frames equal one run's).
    const double travel = sun_travel_fraction(sun_travel_px(i, s, sun, o0.rows), o0.rows);
    return opacity_sun_weight(t, sun_transmittance_of_opacity(o0, sun), input_look_transmittance_, input_sun_share(),
                              travel, cloud_share(o0));
}

const SunPatch& SkyTimeline::covered_input_sun(int n) {
    if (!covered_checked_) {
        covered_checked_ = true;
        // A sun dimmed in the input (a cloud over it; an imported photo's sun not seen, so not
        // restored) cannot be brightened by a weight relative to it when the cloud moves off.
        // Only when the sky around the sun says so too: a cloud lit by forward scattering can look
        // as clear as the aureole it hides, and then the look cannot tell when it moves off either.
        if (input_sun_ && !model_->makes_own_sun() && input_sun_share() < 0.5) {
            double around = input_look_transmittance_;
            if (!model_opacity_.empty() && !model_opacity_[0].empty())
                around = std::min(around, sun_transmittance_of_opacity(model_opacity_[0], *input_sun_));
            if (around < 0.5) clear_sun_ = clear_sun_patch(n, *input_sun_);
            covered_input_transmittance_ = around;
        }
    }
    return clear_sun_;
}

Color SkyTimeline::relight_to_clock(double t, SkyImage* out) {
    if (!clock_ || model_->makes_own_sun() || !(t > 0)) return Color::Ones();
    const Vec3d start = *sun_direction_at(0.0), now = *sun_direction_at(t);
    const int n = out->resolution;
    // The clear sky's background (no disc) and its sun's irradiance for a sun; no warning per frame
    // for a sun below the horizon (said once below).
    ClearSkyParams p;
    auto background_at = [&](const Vec3d& sun, int size) {
        p.sun_direction = sun, p.sun_disc = false;
        return make_clear_sky(p, size, false).rgb;
    };
    // The ratio of two clear backgrounds is smooth: computed at most at 256 px and upsampled (at
    // 1024 px the two Hosek-Wilkie skies per frame were a sixth of the sky's time).
    const int w = std::min(n, 256);
    if (relight_n_ != w) {
        p.turbidity = relight_turbidity_ = clear_sky_turbidity(*step(0), start);
        relight_start_ = background_at(start, w);
        relight_n_ = w;
    }
    p.turbidity = relight_turbidity_;
    const std::vector<float> later = background_at(now, w);
    cv::Mat ratio(w, w, CV_32FC3, cv::Scalar::all(0)), inside(w, w, CV_32F, cv::Scalar(0));
    float* r = ratio.ptr<float>();
    for (size_t k = 0; k < later.size(); ++k)
        if (relight_start_[k] > 0)
            r[k] = std::clamp(later[k] / relight_start_[k], 1e-8f, 1e8f), inside.ptr<float>()[k / 3] = 1;
    // Upsampled from the disc's pixels alone (normalised by their share of each footprint): the
    // horizon at sunset is 3 x darker than an hour before, and footprints reaching past the rim
    // brightened it 2.4 x. Within a few degrees of the horizon the model changes faster than 256 px
    // follow (at sunset the last half degree 40 % off): there the ratio is the models' own.
    cv::Mat share = inside;
    if (w != n) {
        cv::resize(ratio, ratio, cv::Size(n, n), 0, 0, cv::INTER_LINEAR);
        cv::resize(inside, share, cv::Size(n, n), 0, 0, cv::INTER_LINEAR);
    }
    p.sun_disc = false;
    p.sun_direction = start;
    const ClearSkyModel model_start(p, false);
    p.sun_direction = now;
    const ClearSkyModel model_now(p, false);
    const double band = w == n ? 2.0 : 1.0 - 8.0 / w;  // none when computed at the sky's own size
    tbb::parallel_for(0, n, [&](int j) {
        const cv::Vec3f* row = ratio.ptr<cv::Vec3f>(j);
        const float* s = share.ptr<float>(j);
        float* px = &out->rgb[size_t(j) * n * 3];
        for (int i = 0; i < n; ++i) {
            cv::Vec3f f = row[i] * (1.0f / std::max(s[i], 1e-6f));
            const Vec2 uv = fisheye::pixel_center_uv(i, j, n);
            const double r2 = double(uv.squaredNorm());
            if (r2 <= 1.0 && r2 >= band * band) {
                const Vec3d d = fisheye::direction_from_uv(double(uv.x()), double(uv.y()));
                const Color a = model_start.sky_radiance(d), b = model_now.sky_radiance(d);
                for (int c = 0; c < 3; ++c) f[c] = a[c] > 0 ? std::clamp(b[c] / a[c], 1e-8f, 1e8f) : 1.0f;
            }
            for (int c = 0; c < 3; ++c) px[3 * i + c] *= f[c];
        }
    });
    if (!relight_warned_ && now.y() < 0) {
        relight_warned_ = true;
        // Below from the start: the start's own warning said so (this named the first step's time).
        if (!reports_silenced() && start.y() >= 0)
            std::fprintf(stderr,
                         "dynsky: warning: the sun is below the horizon %.0f s into the sky timeline: the clear sky "
                         "there is the sunset's, dimmed for twilight (no stars or moon)\n",
                         t);
    }
    // The patch holds radiance: put at a pixel of another solid angle it carries that much more or
    // less light (a sun climbing 11 degrees gained 5 % in an hour): its irradiance kept, and the
    // model's sun's change applied.
    return sun_patch_relight(n, start, now, relight_turbidity_);
}

std::optional<Vec3d> SkyTimeline::sun_direction_at(double t) const {
    if (clock_) return compute_sun_position(add_seconds(clock_->start, t), clock_->where).direction();
    return input_sun_;
}

void SkyTimeline::check_span(double seconds, double dt) {
    const double steps = seconds / dt;
    if (!(steps <= kMaxSteps)) {
        char text[240];
        std::snprintf(text, sizeof text,
                      "--duration %g s at a medium step of %g s (--dt) is %.4g steps, more than the %.0f one sky "
                      "timeline may span: a longer --dt or a shorter --duration",
                      seconds, dt, steps, kMaxSteps);
        throw Error(text);
    }
}

int SkyTimeline::last_step_for(double t) const {
    const double x = t / dt_;
    if (!(x < 1e9)) return std::numeric_limits<int>::max();  // beyond any timeline (check_span)
    const int i = int(std::floor(x + 1e-9));
    return x - i < 1e-9 ? i : i + 1;  // sky_at's own rounding: at a step it needs that step alone
}

std::shared_ptr<const SkyImage> SkyTimeline::step(int i) {
    if (i < 0) throw Error("sky timeline: negative step index");
    if (stored_last_step_ >= 0) return stored_step(i);
    while (int(steps_.size()) <= i) {
        auto t0 = std::chrono::steady_clock::now();
        double t_next = double(steps_.size()) * dt_;
        auto sun = sun_direction_at(t_next);
        // A model moving the input's sky keeps the input's sun (its clear background): the clock's
        // change is put on every frame by relight_to_clock. Given the clock's sun, the model read
        // the input's glow, left where it was, as cloud beside the moved background and carried
        // white crescents off the sun's side after ten minutes of a clear sky.
        if (sun) model_->set_sun_direction(model_->makes_own_sun() ? *sun : *sun_direction_at(0.0));
        SkyImage next = model_->step(steps_, dt_);
        if (next.resolution != steps_[0]->resolution)
            throw Error("sky timeline: model '" + model_->name() + "' changed the sky's resolution");
        clear_outside_disc(&next);
        model_opacity_.resize(steps_.size() + 1);
        model_opacity_.back() = model_->last_cloud_opacity();
        model_flow_.resize(steps_.size() + 1);
        model_flow_.back() = model_->last_step_flow();
        if (!model_flow_.back().empty() && model_flow_.back().rows != next.resolution)
            model_flow_.back() = flow_at_resolution(model_flow_.back(), next.resolution);
        if (steps_.size() == 1) model_opacity_[0] = model_->input_cloud_opacity();
        if (model_->makes_own_sun()) {
            if (sun) next.sun_direction = sun->cast<float>();
            suns_.push_back(remove_sun(&next));
        } else {
            suns_.push_back(suns_[0]);
        }
        next.time_seconds = input_time_ + t_next;
        steps_.push_back(std::make_shared<const SkyImage>(std::move(next)));
        timings_.medium_seconds += seconds_since(t0);
        ++timings_.medium_steps;
    }
    return steps_[size_t(i)];
}

SkyTimeline::Interval& SkyTimeline::interval(int i) {
    auto it = intervals_.find(i);
    if (it != intervals_.end()) return it->second;
    auto a = step(i), b = step(i + 1);
    auto t0 = std::chrono::steady_clock::now();
    Interval iv;
    // The motion the model gave step i + 1 when it knows it, else measured between the steps.
    if (stored_last_step_ >= 0) iv.flow = stored_flow(i);
    else if (size_t(i + 1) < model_flow_.size() && !model_flow_[size_t(i + 1)].empty())
        iv.flow = model_flow_[size_t(i + 1)];
    else iv.flow = estimate_sky_flow(*a, *b, flow_params_);
    timings_.medium_seconds += seconds_since(t0);
    // Frames run forwards: intervals two behind are not needed again.
    intervals_.erase(intervals_.begin(), intervals_.lower_bound(i - 1));
    return intervals_.emplace(i, std::move(iv)).first->second;
}

SkyTimeline::Interval& SkyTimeline::interval_with_keys(int i) {
    Interval& iv = interval(i);
    if (iv.has_keys) return iv;
    auto a = step(i), b = step(i + 1);
    auto t0 = std::chrono::steady_clock::now();
    iv.third = advect_great_arc(*a, iv.flow, 1.0 / 3.0);
    iv.two_thirds = advect_great_arc_from_end(*b, iv.flow, 2.0 / 3.0);
    iv.has_keys = true;
    timings_.medium_seconds += seconds_since(t0);
    return iv;
}

void SkyTimeline::set_gamma(GammaKind kind) { gamma_ = kind; }

const SkyImage& SkyTimeline::key_third(int i) { return interval_with_keys(i).third; }
const cv::Mat& SkyTimeline::flow(int i) { return interval(i).flow; }

SkyImage SkyTimeline::sky_at(double t) {
    SkyImage out;
    sky_at(t, &out);
    return out;
}

void SkyTimeline::sky_at(double t, SkyImage* out) {
    if (!(t >= 0)) throw Error("sky timeline: time must be >= 0 (got " + std::to_string(t) + ")");
    double x = t / dt_;
    int i = int(std::floor(x + 1e-9));
    double s = std::max(0.0, x - i);
    auto snap = [](double v, double key) { return std::abs(v - key) < 1e-9 ? key : v; };
    if (gamma_ == GammaKind::paper) s = snap(snap(s, 1.0 / 3.0), 2.0 / 3.0);
    if (s < 1e-9) s = 0;

    if (s == 0) {
        auto a = step(i);
        auto t0 = std::chrono::steady_clock::now();
        blend_skies(*a, *a, 0.0, out);
        timings_.gamma_seconds = seconds_since(t0);
    } else if (gamma_ == GammaKind::constant) {
        Interval& iv = interval(i);
        auto a = step(i), b = step(i + 1);
        auto t0 = std::chrono::steady_clock::now();
        // Both steps carried to this moment along the flow, then cross-faded by time.
        blend_skies(advect_great_arc(*a, iv.flow, s), advect_great_arc_from_end(*b, iv.flow, s), s, out);
        timings_.gamma_seconds = seconds_since(t0);
    } else {
        Interval& iv = interval_with_keys(i);
        auto a = step(i), b = step(i + 1);
        auto t0 = std::chrono::steady_clock::now();
        if (s < 1.0 / 3.0) blend_skies(*a, iv.third, 3.0 * s, out);
        else if (s < 2.0 / 3.0) blend_skies(iv.third, iv.two_thirds, s == 1.0 / 3.0 ? 0.0 : 3.0 * s - 1.0, out);
        else blend_skies(iv.two_thirds, *b, s == 2.0 / 3.0 ? 0.0 : 3.0 * s - 2.0, out);
        timings_.gamma_seconds = seconds_since(t0);
    }
    auto t0 = std::chrono::steady_clock::now();
    out->time_seconds = input_time_ + t;
    out->units = input_units_;  // the steps' images are back in the input's units (below)
    auto sun = sun_direction_at(t);
    last_sun_weight_ = 1.0;
    const Color sun_factor = relight_to_clock(t, out);
    auto relit = [&](const SunPatch& patch) {
        SunPatch p = patch;
        for (Color& e : p.excess) e *= sun_factor;
        return p;
    };
    if (sun) {
        out->sun_direction = sun->cast<float>();
        // A model that moves the input's clouds over the sun dims it (models with their own sun
        // already did). At the input itself the weight is 1: S_0 comes back exactly.
        const bool at_input = i == 0 && s == 0;
        if (!at_input && !covered_input_sun(out->resolution).empty()) {
            // The input's sun was covered: the clear sun by the frame's own transmittance alone.
            // The model's opacity holds the input's cover at the sun (set_input_sun_cover), so at
            // the input this is its dim sun again. The input's dim sun added by 1 - that (as if its
            // cloud stayed) kept shining through a thicker cloud moved over a half-covered sun: on
            // a procedural seed 50 % over the truth for the whole run (docs/animation.md).
            double t_frame = estimate_sun_transmittance(*out, *sun);
            if (auto w = model_sun_weight(i, s, *sun, false)) t_frame = std::min(t_frame, *w);
            // As the cover at the sun changes from the input's: where it stays, the input's dim
            // sun stays (an overcast sky's sun seen through its cloud was put out on the first
            // step, the grey around it read as cloud); where it clears, up to the clear sun.
            // Where the input's cover at the sun reads as its share (the usual case) this is
            // t_frame itself.
            double weight = input_sun_share() + t_frame - covered_input_transmittance_;
            // Under broken cloud (not overcast: kOvercastCloudShare) a sun partly seen through the
            // cloud around it is at that cloud's edge, and once the clouds have moved a sun's
            // diameter the cover moved over it decides, not the input's gap: procedural seed 8's
            // half-covered sun stayed half out for a minute where the truth's went in within 10 s.
            const cv::Mat o0 = model_opacity_.empty() ? cv::Mat() : model_opacity_[0];
            if (!o0.empty() && cloud_share(o0) < kOvercastCloudShare) {
                const double travel = sun_travel_fraction(sun_travel_px(i, s, *sun, o0.rows), o0.rows);
                weight = (1.0 - travel) * weight + travel * t_frame;
            }
            last_sun_weight_ = std::clamp(weight, 0.0, 1.0);
            insert_sun(out, relit(clear_sun_), *sun, last_sun_weight_);
        } else {
            if (!model_->makes_own_sun() && !at_input && !suns_[0].empty()) {
                last_sun_weight_ = relative_transmittance(estimate_sun_transmittance(*out, *sun),
                                                          input_look_transmittance_);
                // The model's, from the clouds it moved over the sun, when it knows them: a cloud is
                // over the sun when either says so.
                if (auto w = model_sun_weight(i, s, *sun)) last_sun_weight_ = std::min(last_sun_weight_, *w);
            }
            insert_sun(out, relit(suns_[size_t(i)]), *sun, (1.0 - s) * last_sun_weight_);
            if (s > 0) insert_sun(out, relit(suns_[size_t(i) + 1]), *sun, s * last_sun_weight_);
        }
    }
    if (radiance_scale_ != 1.0) scale_radiance(out, radiance_scale_);  // back to the input's units
    timings_.gamma_seconds += seconds_since(t0);
}

}  // namespace dynsky
