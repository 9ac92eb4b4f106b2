#include "sky/sky_timeline.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <opencv2/photo.hpp>

#include "sky/cloud_model.h"
#include "sky/fisheye.h"
#include "util/error.h"

namespace dynsky {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

class NetworkStepModel : public MediumStepModel {
  public:
    explicit NetworkStepModel(const std::string& folder) : model_(CloudModel::load(folder)) {}
    SkyImage step(const std::vector<std::shared_ptr<const SkyImage>>& history, double dt) override {
        SkyImage next = model_.step(*history.back());
        next.time_seconds = history.back()->time_seconds + dt;
        return next;
    }
    std::string name() const override { return "network:" + model_.info().folder; }
    double native_dt_seconds() const override { return model_.info().dt_seconds; }

  private:
    CloudModel model_;
};

}  // namespace

std::unique_ptr<MediumStepModel> make_network_step_model(const std::string& folder) {
    return std::make_unique<NetworkStepModel>(folder);
}

FlowExtrapolationStepModel::FlowExtrapolationStepModel(double wind_from_deg, double degrees_per_second,
                                                       SkyFlowParams flow_params)
    : wind_from_deg_(wind_from_deg), degrees_per_second_(degrees_per_second), flow_params_(flow_params) {}

SkyImage FlowExtrapolationStepModel::step(const std::vector<std::shared_ptr<const SkyImage>>& history, double dt) {
    const SkyImage& last = *history.back();
    cv::Mat flow;
    if (history.size() >= 2) {
        flow = estimate_sky_flow(*history[history.size() - 2], last, flow_params_);
    } else {
        // Clouds overhead drift towards where the wind blows to: rotate the zenith towards it.
        Vec3d to = fisheye::direction_from_angles(kPiD / 2, (wind_from_deg_ + 180.0) * kPiD / 180.0);
        Vec3d axis = Vec3d::UnitY().cross(to);
        flow = rotation_flow(last.resolution, axis, degrees_per_second_ * dt * kPiD / 180.0);
    }
    SkyImage next = advect_great_arc(last, flow, 1.0);
    next.time_seconds = last.time_seconds + dt;
    next.source = "flow-extrapolation of " + last.source;
    return next;
}

SkyImage ProceduralStepModel::step(const std::vector<std::shared_ptr<const SkyImage>>& history, double dt) {
    const SkyImage& last = *history.back();
    SkyImage next = sky_.render(last.time_seconds + dt, last.resolution);
    next.time_seconds = last.time_seconds + dt;
    return next;
}

UtcTime add_seconds(const UtcTime& t, double seconds) {
    std::tm tm{};
    tm.tm_year = t.year - 1900, tm.tm_mon = t.month - 1, tm.tm_mday = t.day;
    tm.tm_hour = t.hour, tm.tm_min = t.minute, tm.tm_sec = 0;
    double total = t.second + seconds;
    double whole = std::floor(total);
    time_t base = timegm(&tm) + time_t(whole);
    std::tm out{};
    gmtime_r(&base, &out);
    UtcTime r;
    r.year = out.tm_year + 1900, r.month = out.tm_mon + 1, r.day = out.tm_mday;
    r.hour = out.tm_hour, r.minute = out.tm_min, r.second = out.tm_sec + (total - whole);
    return r;
}

SunPatch remove_sun(SkyImage* sky) {
    SunPatch patch;
    if (!sky->sun_direction || sky->sun_direction->y() <= 0) return patch;
    const int n = sky->resolution;
    double x, y;
    pixel_from_direction(sky->sun_direction->cast<double>(), n, &x, &y);
    const int ci = int(std::lround(x)), cj = int(std::lround(y));
    const int radius = int(std::ceil(n / 180.0)) + 2, margin = 3 * radius;
    const int i0 = std::max(0, ci - margin), i1 = std::min(n - 1, ci + margin);
    const int j0 = std::max(0, cj - margin), j1 = std::min(n - 1, cj + margin);
    if (i1 <= i0 || j1 <= j0) return patch;
    std::vector<float> around;
    for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i)
            if (sky->in_disc(i, j)) around.push_back(luminance(sky->pixel(i, j)));
    if (around.empty()) return patch;
    const float threshold = 20.0f * std::max(median(std::move(around)), 1e-6f);

    const int w = i1 - i0 + 1, h = j1 - j0 + 1;
    cv::Mat mask = cv::Mat::zeros(h, w, CV_8UC1);
    for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i)
            if ((i - ci) * (i - ci) + (j - cj) * (j - cj) <= radius * radius && sky->in_disc(i, j) &&
                luminance(sky->pixel(i, j)) > threshold)
                mask.at<uint8_t>(j - j0, i - i0) = 255;
    if (cv::countNonZero(mask) == 0) return patch;
    cv::dilate(mask, mask, cv::Mat());  // the disc's soft limb too
    cv::Mat filled[3];
    for (int c = 0; c < 3; ++c) {
        cv::Mat channel(h, w, CV_32FC1);
        for (int j = 0; j < h; ++j)
            for (int i = 0; i < w; ++i)
                channel.at<float>(j, i) = std::log(sky->rgb[(size_t(j + j0) * n + i + i0) * 3 + c] + 1e-6f);
        cv::inpaint(channel, mask, filled[c], 3, cv::INPAINT_TELEA);
    }
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            if (!mask.at<uint8_t>(j, i) || !sky->in_disc(i + i0, j + j0)) continue;
            Color before = sky->pixel(i + i0, j + j0), after;
            for (int c = 0; c < 3; ++c)
                after[c] = std::min(before[c], std::max(std::exp(filled[c].at<float>(j, i)) - 1e-6f, 0.0f));
            sky->set_pixel(i + i0, j + j0, after);
            patch.di.push_back(i + i0 - ci), patch.dj.push_back(j + j0 - cj);
            patch.excess.push_back(before - after);
        }
    return patch;
}

void insert_sun(SkyImage* sky, const SunPatch& patch, const Vec3d& direction, double weight) {
    if (patch.empty() || direction.y() <= 0 || weight == 0.0) return;
    const int n = sky->resolution;
    double x, y;
    pixel_from_direction(direction, n, &x, &y);
    const int ci = int(std::lround(x)), cj = int(std::lround(y));
    for (size_t k = 0; k < patch.di.size(); ++k) {
        int i = ci + patch.di[k], j = cj + patch.dj[k];
        if (i < 0 || j < 0 || i >= n || j >= n || !sky->in_disc(i, j)) continue;
        sky->set_pixel(i, j, sky->pixel(i, j) + float(weight) * patch.excess[k]);
    }
}

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

SkyTimeline::SkyTimeline(SkyImage input, std::unique_ptr<MediumStepModel> model, double dt_seconds,
                         std::optional<SunClock> clock, SkyFlowParams flow_params)
    : model_(std::move(model)), dt_(dt_seconds), clock_(clock), flow_params_(flow_params) {
    if (!(dt_ > 0)) throw Error("sky timeline: Delta t must be positive");
    validate_sky(input, input.source.empty() ? "input sky" : input.source);
    input_sun_ = input.sun_direction ? std::optional<Vec3d>(input.sun_direction->cast<double>()) : std::nullopt;
    input_time_ = input.time_seconds;
    // The sun is cut out where the image has it; it is put back where the clock says.
    suns_.push_back(remove_sun(&input));
    if (clock_) {
        validate_location(clock_->where);
        input.sun_direction = compute_sun_position(clock_->start, clock_->where).direction().cast<float>();
    }
    steps_.push_back(std::make_shared<const SkyImage>(std::move(input)));
}

std::optional<Vec3d> SkyTimeline::sun_direction_at(double t) const {
    if (clock_) return compute_sun_position(add_seconds(clock_->start, t), clock_->where).direction();
    return input_sun_;
}

std::shared_ptr<const SkyImage> SkyTimeline::step(int i) {
    if (i < 0) throw Error("sky timeline: negative step index");
    while (int(steps_.size()) <= i) {
        auto t0 = std::chrono::steady_clock::now();
        double t_next = double(steps_.size()) * dt_;
        auto sun = sun_direction_at(t_next);
        if (sun) model_->set_sun_direction(*sun);
        SkyImage next = model_->step(steps_, dt_);
        if (next.resolution != steps_[0]->resolution)
            throw Error("sky timeline: model '" + model_->name() + "' changed the sky's resolution");
        clear_outside_disc(&next);
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
    iv.flow = estimate_sky_flow(*a, *b, flow_params_);
    iv.third = advect_great_arc(*a, iv.flow, 1.0 / 3.0);
    iv.two_thirds = advect_great_arc(*b, iv.flow, -1.0 / 3.0);
    timings_.medium_seconds += seconds_since(t0);
    // Frames run forwards: intervals two behind are not needed again.
    intervals_.erase(intervals_.begin(), intervals_.lower_bound(i - 1));
    return intervals_.emplace(i, std::move(iv)).first->second;
}

const SkyImage& SkyTimeline::key_third(int i) { return interval(i).third; }
const SkyImage& SkyTimeline::key_two_thirds(int i) { return interval(i).two_thirds; }
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
    s = snap(snap(s, 1.0 / 3.0), 2.0 / 3.0);
    if (s < 1e-9) s = 0;

    if (s == 0) {
        auto a = step(i);
        auto t0 = std::chrono::steady_clock::now();
        blend_skies(*a, *a, 0.0, out);
        timings_.gamma_seconds = seconds_since(t0);
    } else {
        Interval& iv = interval(i);
        auto a = step(i), b = step(i + 1);
        auto t0 = std::chrono::steady_clock::now();
        if (s < 1.0 / 3.0) blend_skies(*a, iv.third, 3.0 * s, out);
        else if (s < 2.0 / 3.0) blend_skies(iv.third, iv.two_thirds, s == 1.0 / 3.0 ? 0.0 : 3.0 * s - 1.0, out);
        else blend_skies(iv.two_thirds, *b, s == 2.0 / 3.0 ? 0.0 : 3.0 * s - 2.0, out);
        timings_.gamma_seconds = seconds_since(t0);
    }
    auto t0 = std::chrono::steady_clock::now();
    out->time_seconds = input_time_ + t;
    auto sun = sun_direction_at(t);
    if (sun) {
        out->sun_direction = sun->cast<float>();
        insert_sun(out, suns_[size_t(i)], *sun, 1.0 - s);
        if (s > 0) insert_sun(out, suns_[size_t(i) + 1], *sun, s);
    }
    timings_.gamma_seconds += seconds_since(t0);
}

}  // namespace dynsky
