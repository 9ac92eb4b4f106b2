#include "motion/advect_residual.h"

#include "motion/radiance_scale.h"

#include <tbb/parallel_for.h>

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "motion/advection.h"
#include "motion/onnx_net.h"
#include "motion/sun_patch.h"
#include "sky/fisheye.h"
#include "util/allocation.h"
#include "util/error.h"
#include "util/parse.h"
#include "util/math.h"

namespace dynsky {

namespace fs = std::filesystem;

nlohmann::json read_model_description(const std::string& folder) {
    const std::string path = (fs::path(folder) / "model.json").string();
    if (!fs::is_directory(folder)) throw_file_error(folder, "model folder not found");
    if (!fs::exists(path)) throw_file_error(path, "model description not found (is this a model folder?)");
    if (!fs::is_regular_file(path)) throw_file_error(path, "not a regular file (a directory, a FIFO or a device?)");
    nlohmann::json j;
    try {
        std::ifstream f(path);
        j = nlohmann::json::parse(f);
    } catch (const nlohmann::json::exception& e) {
        throw_file_error(path, std::string("not a valid model description: ") + e.what());
    }
    if (!j.is_object()) throw_file_error(path, "not a model description (expected a JSON object)");
    if (!j.contains("format") || j["format"] != "dynsky-cloud-model")
        throw_file_error(path, "\"format\" is " + (j.contains("format") ? j["format"].dump() : std::string("missing")) +
                                   ", expected \"dynsky-cloud-model\" (is this a dynsky model folder?)");
    if (!j.contains("version") || !j["version"].is_number_integer())
        throw_file_error(path, "\"version\" is " +
                                   (j.contains("version") ? j["version"].dump() : std::string("missing")) +
                                   ": a model description needs a whole version number");
    return j;
}

std::string cloud_model_kind(const std::string& folder) {
    return read_model_description(folder).value("kind", std::string("flownet-cloudnet"));
}

AdvectResidualNetwork AdvectResidualNetwork::pure_advection(int resolution, double dt) {
    AdvectResidualNetwork m;
    m.info_.name = "advect";
    m.info_.kind = "advect";
    m.info_.resolution = resolution;
    m.info_.dt = dt;
    return m;
}

AdvectResidualNetwork AdvectResidualNetwork::load(const std::string& folder) {
    const nlohmann::json j = read_model_description(folder);
    const std::string kind = j.value("kind", std::string("flownet-cloudnet"));
    const std::string json_path = (fs::path(folder) / "model.json").string();
    if (kind != "advect-residual") throw_file_error(json_path, "kind '" + kind + "' is not an advect-residual model");
    AdvectResidualNetwork m;
    AdvectResidualInfo& info = m.info_;
    info.folder = folder;
    try {
        const int version = j.value("version", 0);
        if (version != 2)
            throw_file_error(json_path, "version " + std::to_string(version) + " (this dynsky reads version 2)");
        info.name = j.value("name", fs::path(folder).filename().string());
        info.resolution = j.at("resolution").get<int>();
        info.import_resolution = j.value("import_resolution", 4 * info.resolution);
        info.dt = j.at("dt_s").get<double>();
        info.flow_scale = j.value("flow_scale", 0.08);
        const std::string base = j.value("base", std::string("warp"));
        if (base != "warp" && base != "compensated")
            throw_file_error(json_path, "base '" + base + "' is neither 'warp' nor 'compensated'");
        info.compensated = base == "compensated";
        // The network is always the folder's model.onnx: a file named otherwise is not what would run.
        if (j.contains("onnx_file") && j["onnx_file"] != "model.onnx")
            throw_file_error(json_path,
                             "onnx_file " + j["onnx_file"].dump() + ": the network must be the folder's model.onnx");
        info.form.unit_map.scale = j.value("unit_scale", info.form.unit_map.scale);
        info.form.unit_map.max_radiance = j.value("unit_max", info.form.unit_map.max_radiance);
        info.form.cloud_rule.rule = parse_cloud_rule(j.value("cloud_rule", std::string("rb")));
        info.form.cloud_rule.threshold = j.value("cloud_threshold", info.form.cloud_rule.threshold);
    } catch (const nlohmann::json::exception& e) {
        throw_file_error(json_path, std::string("not a valid model description: ") + e.what());
    }
    if (info.resolution < 8 || info.resolution > 4096)
        throw_file_error(json_path, "resolution " + std::to_string(info.resolution) + " is not in 8..4096");
    if (!(info.dt >= 0.01 && info.dt <= 86400))
        throw_file_error(json_path, "dt_s " + number_text(info.dt) + " is not a step of 0.01 s .. 1 day");
    if (!(info.flow_scale > 0)) throw_file_error(json_path, "flow_scale must be positive");
    if (info.import_resolution < info.resolution || info.import_resolution > 16384 ||
        info.import_resolution % info.resolution != 0)
        throw_file_error(json_path, "import_resolution " + std::to_string(info.import_resolution) +
                                        " is not a multiple of the resolution " + std::to_string(info.resolution));
    try {
        validate_unit_map(info.form.unit_map);
    } catch (const Error& e) {
        throw_file_error(json_path, e.what());
    }
    const std::string onnx = (fs::path(folder) / "model.onnx").string();
    m.net_ = read_onnx(onnx);
    // One run on zeros: a network that does not take 8 and give 3 N x N planes fails here.
    const int n = info.resolution;
    QuietOpenCv quiet;
    cv::Mat out = probe_net(m.net_, to_blob({cv::Mat(n, n, CV_32FC(8), cv::Scalar::all(0))}), onnx, n);
    if (out.rows != n || out.cols != n || out.channels() != 3)
        throw_file_error(onnx, "returns " + shape_text(out) + ", expected " + std::to_string(n) + " x " +
                                   std::to_string(n) + " x 3 (model.json's resolution)");
    return m;
}

cv::Mat AdvectResidualNetwork::network_input(const cv::Mat& image, const cv::Mat& flow,
                                             const cv::Mat& compensation) const {
    const int n = info_.resolution;
    if (image.rows != n || image.cols != n || image.type() != CV_32FC3)
        throw Error("advect-residual: the image must be " + std::to_string(n) + " x " + std::to_string(n) +
                    " x 3 float, got " + shape_text(image));
    if (flow.rows != n || flow.cols != n || flow.type() != CV_32FC2)
        throw Error("advect-residual: the flow must be " + std::to_string(n) + " x " + std::to_string(n) +
                    " x 2 float");
    cv::Mat scaled = flow * (1.0 / (info_.flow_scale * n)), input;
    cv::Mat warped = warp_in_disc(image, flow);
    if (info_.compensated && !compensation.empty()) warped += compensation;
    cv::merge(std::vector<cv::Mat>{warped, image, scaled}, input);
    return input;
}

cv::Mat AdvectResidualNetwork::run(const cv::Mat& input) {
    if (net_.empty()) throw Error("advect-residual: no network (pure advection)");
    return from_blob(run_net(net_, to_blob({input}), "advect-residual network"), "advect-residual network");
}

cv::Mat AdvectResidualNetwork::step_network(const cv::Mat& image, const cv::Mat& flow, const cv::Mat& compensation) {
    cv::Mat next;
    if (net_.empty()) {
        next = warp_in_disc(image, flow);
        if (!compensation.empty()) next += compensation;
    } else {
        next = run(network_input(image, flow, compensation));
        // A model trained on the plain warp gets the compensation added to its output.
        if (!info_.compensated && !compensation.empty()) next += compensation;
    }
    cv::min(cv::max(next, 0.0), 1.0, next);
    next.setTo(cv::Scalar::all(0), ~sky_disc_mask(image.rows));
    return next;
}

namespace {

using Hidden = cv::Vec<float, 5>;  // a x background, a, circumsolar share

// The clear background at n, computed at most at 256 px and upsampled (it is smooth).
cv::Mat background_at(const Vec3& sun, int n, const NetworkFormParams& form, double turbidity) {
    const int w = std::min(n, 256);
    cv::Mat b = clear_background(sun.cast<double>(), w, form, turbidity);
    if (w == n) return b;
    cv::Mat up;
    cv::resize(extend_past_rim(b), up, cv::Size(n, n), 0, 0, cv::INTER_LINEAR);
    up.setTo(cv::Scalar::all(0), ~sky_disc_mask(n));
    return up;
}

// How much of the sun's aureole each pixel is (defined below).
cv::Mat circumsolar_share(int n, const std::optional<Vec3d>& sun, double inner_deg = 15.0, double outer_deg = 30.0);

}  // namespace

cv::Mat CloudFlow::at(int k) const {
    if (wind.empty() || relax_steps <= 0) return measured;
    const double a = std::exp(-(k - 1) / relax_steps);
    return wind + (measured - wind) * a;
}

CloudFlow CloudFlow::from_measured(const MeasuredMotion& motion, double dt, const std::optional<Vec3d>& sun) {
    const int n = motion.smoothed.rows;
    CloudFlow f;
    f.measured = motion.confirmed.empty() ? motion.smoothed : motion.confirmed;
    // The wind that explains it, fitted inside 80 % of the radius (the rim is foreshortened).
    cv::Mat inner = cv::Mat::zeros(n, n, CV_8UC1);
    cv::circle(inner, cv::Point(n / 2, n / 2), int(0.4 * n), cv::Scalar(255), cv::FILLED);
    // Nor in the sun's aureole (circumsolar_share, out to 30 degrees): it and the glare move with
    // the sun, not the wind, and Farneback tracks them (on the clear ARM morning the wind fitted
    // with them came out from 30-60 degrees off the clouds' own). Chosen on the validation frames:
    // arm-tsi +0.09 to +0.32 dB over Farneback at 1-6 steps, the others +0.00 to +0.01
    // (docs/networks-advect-residual.md).
    if (sun) inner.setTo(0, circumsolar_share(n, sun) > 0);
    f.fitted_wind = fit_wind(motion.smoothed, inner, dt);
    f.wind = wind_flow(n, *f.fitted_wind, dt);
    if (!motion.confirmed.empty()) {
        // The departure from the wind that the clouds keep for several steps: the smoothed flow's,
        // where the flow measured back agrees with it. Where it does not (flat cloud, Farneback's
        // noise) the clouds take the wind from the second step on: held there, that noise turned
        // big clouds into swirls (docs/networks-advect-residual.md). The rest of the confirmed
        // flow is the first step's detail.
        cv::Mat kept = motion.smoothed;
        if (!motion.agreement.empty()) {
            cv::Mat a2;
            cv::merge(std::vector<cv::Mat>{motion.agreement, motion.agreement}, a2);
            // A new buffer: an expression assigned to the header of motion.smoothed is written
            // into the caller's smoothed flow (OpenCV evaluates into a same-sized Mat in place).
            kept = cv::Mat(f.wind + (motion.smoothed - f.wind).mul(a2));
        }
        f.detail = motion.confirmed - kept;
    }
    f.relax_steps = 6.0;
    f.recycle = true;
    return f;
}

CloudFlow CloudFlow::resized(int n) const {
    CloudFlow f = *this;
    f.measured = flow_at_resolution(measured, n);
    if (!wind.empty()) f.wind = flow_at_resolution(wind, n);
    if (!detail.empty()) f.detail = flow_at_resolution(detail, n);
    return f;
}

namespace {
constexpr double kCorrectionSteps = 1.0;
constexpr double kDepartureHoldSteps = 8.0;
// How far around the input sun's cut a cloud that dimmed it is spread (set_unseen_opacity): 1 px at
// 128 px, at kSunCoverRing of the cut's opacity. On the 20 procedural seeds of docs/animation.md, on
// the cut alone three suns came out up to 70 s early. Spread further they come out later: seed 1's
// sun (tests/motion/sun_transmittance_test.cpp) 5 s after the truth's at 0.85 of the truth with the
// full opacity on the ring (0.87 at 0.9, 0.96 at 0.5), 10 s after at 2 px; less on the ring let
// seeds 14 and 21 out early again (at 0.5-0.85, mean errors 2-5 points over those of the model not
// told the cover at all). 0.9 is where both hold, with little to spare on either side.
constexpr double kSunCoverSpreadDeg = 1.4;
constexpr double kSunCoverRing = 0.9;
const double kCorrectionFade = std::exp(-1.0 / kCorrectionSteps);

// The start's cloud signal (start - background, mean of the channels) averaged over the sky around
// each pixel (a normalised Gaussian, sigma a tenth of the image, worked out at most at 128 px),
// floored at a tenth of its largest value (a divisor). Recycled clouds are scaled by its ratio
// between where they are shown and where they were read: the recycled tile lies high in the sky,
// where clouds are denser and, on the sun's side, brighter; carried unscaled across the whole sky
// it brightened 3-hour rollouts to 1.20-1.21x their start (ARM photograph, procedural sky; within
// 0.87-1.02x with it, networks/stability_advect.py).
cv::Mat cloud_signal_field(const cv::Mat& clouds) {
    const int big = clouds.rows, w = std::min(big, 128);
    cv::Mat lum, small, weight, num, den, field;
    cv::transform(clouds, lum, cv::Matx13f(1.f / 3, 1.f / 3, 1.f / 3));
    cv::resize(lum, small, cv::Size(w, w), 0, 0, cv::INTER_AREA);
    const cv::Mat disc = sky_disc_mask(w);
    disc.convertTo(weight, CV_32F, 1.0 / 255);
    const double sigma = 0.1 * w;
    cv::GaussianBlur(small.mul(weight), num, cv::Size(0, 0), sigma, sigma, cv::BORDER_REPLICATE);
    cv::GaussianBlur(weight, den, cv::Size(0, 0), sigma, sigma, cv::BORDER_REPLICATE);
    cv::Mat g = num / cv::max(den, 1e-3);
    double top = 0;
    cv::minMaxLoc(g, nullptr, &top, nullptr, nullptr, disc);
    g = cv::max(g, 0.1 * std::max(top, 0.0) + 1e-6);
    cv::resize(g, field, cv::Size(big, big), 0, 0, cv::INTER_LINEAR);
    return field;
}

// The radiance of the start's clouds themselves (start - (1 - a) x background, over a; mean of the
// channels) averaged over the sky around each pixel, weighted by a^2 (the opaque ones say most; a
// normalised Gaussian, sigma a tenth of the image, worked out at most at 128 px), tending to the
// average over the whole sky where no cloud is near. Recycled clouds are scaled by its ratio
// between where they are shown and where they were read: clouds on the sun's side are brighter.
cv::Mat cloud_brightness_field(const cv::Mat& start, const cv::Mat& background, const cv::Mat& alpha) {
    const int big = start.rows, w = std::min(big, 128);
    cv::Mat own, lum, a2, small, small_a2, num, den, field;
    cv::Mat alpha3;
    cv::merge(std::vector<cv::Mat>{alpha, alpha, alpha}, alpha3);
    own = start - background + background.mul(alpha3);  // a x the cloud's own radiance
    cv::transform(own, lum, cv::Matx13f(1.f / 3, 1.f / 3, 1.f / 3));
    a2 = alpha.mul(alpha);
    const cv::Mat disc = sky_disc_mask(big);
    lum.setTo(0, ~disc), a2.setTo(0, ~disc);
    lum = lum.mul(alpha);  // a^2 x the radiance
    cv::resize(lum, small, cv::Size(w, w), 0, 0, cv::INTER_AREA);
    cv::resize(a2, small_a2, cv::Size(w, w), 0, 0, cv::INTER_AREA);
    const double total_a2 = cv::sum(small_a2)[0];
    const double mean = total_a2 > 1e-6 ? cv::sum(small)[0] / total_a2 : 1.0;
    const double sigma = 0.1 * w, prior = 0.02;  // the whole sky's average weighs as a^2 = 0.02
    cv::GaussianBlur(small, num, cv::Size(0, 0), sigma, sigma, cv::BORDER_REPLICATE);
    cv::GaussianBlur(small_a2, den, cv::Size(0, 0), sigma, sigma, cv::BORDER_REPLICATE);
    cv::Mat g = (num + prior * mean) / (den + prior);
    g = cv::max(g, 0.05 * std::max(mean, 1e-6));
    cv::resize(g, field, cv::Size(big, big), 0, 0, cv::INTER_LINEAR);
    return field;
}

// The smooth per-channel field that scales the model's clear sky to the start's own on the start's
// clear pixels (not cloud by the networks' rule, not clipped, inside 94 % of the radius): a
// normalised Gaussian average (sigma a tenth of the image) of start / model there, falling back to
// the mean ratio where no clear pixel is near; all ones when under 2 % of the sky is clear. Worked
// out at most at 128 px (it is smooth). Without it, what the model gets wrong about a real
// camera's clear sky (its gradient, its colour) was taken for cloud and moved by the wind
// (-0.50 dB against persistence 6 steps ahead on the clear ARM morning's validation frames,
// +0.06 dB with it).
cv::Mat clear_sky_field(const cv::Mat& start, const cv::Mat& model, const NetworkFormParams& form) {
    const int big = start.rows, w = std::min(big, 128);
    cv::Mat s = start, m = model;
    if (w != big) {
        cv::resize(start, s, cv::Size(w, w), 0, 0, cv::INTER_AREA);
        cv::resize(model, m, cv::Size(w, w), 0, 0, cv::INTER_AREA);
    }
    const cv::Mat disc = sky_disc_mask(w);
    cv::Mat clear = disc & ~network_cloud_mask(s, form), inner = cv::Mat::zeros(w, w, CV_8UC1);
    cv::circle(inner, cv::Point(w / 2, w / 2), int(0.47 * w), cv::Scalar(255), cv::FILLED);
    std::vector<cv::Mat> ch;
    cv::split(s, ch);
    clear &= inner & (ch[0] < 0.98f) & (ch[1] < 0.98f) & (ch[2] < 0.98f);
    if (cv::countNonZero(clear) < 0.02 * cv::countNonZero(disc)) return cv::Mat(big, big, CV_32FC3, cv::Scalar::all(1));
    cv::Mat ratio, weight, num, den;
    cv::divide(s, cv::max(m, 1e-3), ratio);
    cv::min(cv::max(ratio, 0.25), 4.0, ratio);
    clear.convertTo(weight, CV_32F, 1.0 / 255);
    cv::merge(std::vector<cv::Mat>{weight, weight, weight}, weight);
    const double sigma = 0.1 * w, eps = 0.05;
    cv::GaussianBlur(ratio.mul(weight), num, cv::Size(0, 0), sigma, sigma, cv::BORDER_REPLICATE);
    cv::GaussianBlur(weight, den, cv::Size(0, 0), sigma, sigma, cv::BORDER_REPLICATE);
    cv::Mat field = (num + cv::mean(ratio, clear) * eps) / (den + cv::Scalar::all(eps));
    if (w != big) cv::resize(field, field, cv::Size(big, big), 0, 0, cv::INTER_LINEAR);
    return field;
}

// Fills *map (CV_32FC1) where `unknown` is set from the known pixels of `disc` around them: a
// Gaussian-weighted mean (normalised convolution), widening until every unknown pixel has some.
void fill_from_around(cv::Mat* map, const cv::Mat& unknown, const cv::Mat& disc) {
    if (cv::countNonZero(unknown) == 0) return;
    cv::Mat weight, remaining = unknown.clone();
    cv::Mat known = disc & ~unknown;
    known.convertTo(weight, CV_32F, 1.0 / 255);
    for (double sigma = 1.0; sigma <= map->rows && cv::countNonZero(remaining) > 0; sigma *= 2) {
        cv::Mat num, den;
        cv::GaussianBlur(map->mul(weight), num, cv::Size(0, 0), sigma, sigma, cv::BORDER_REFLECT);
        cv::GaussianBlur(weight, den, cv::Size(0, 0), sigma, sigma, cv::BORDER_REFLECT);
        for (int y = 0; y < map->rows; ++y)
            for (int x = 0; x < map->cols; ++x) {
                if (!remaining.at<uint8_t>(y, x) || den.at<float>(y, x) < 1e-3f) continue;
                map->at<float>(y, x) = num.at<float>(y, x) / den.at<float>(y, x);
                remaining.at<uint8_t>(y, x) = 0;
            }
    }
}

// The clear pixels (opacity under a half) of holes enclosed by cloud, smaller than 2 % of the sky
// and reaching within the circumsolar share (share > 0.5): the sun's aureole seen "through" a cloud
// lit from behind (CV_8UC1, 255), widened by 2 % of the image.
cv::Mat enclosed_clear_near_sun(const cv::Mat& alpha, const cv::Mat& share, const cv::Mat& disc) {
    cv::Mat clear = (alpha < 0.5f) & disc, labels, stats, centroids;
    const int count = cv::connectedComponentsWithStats(clear, labels, stats, centroids, 8, CV_32S);
    const int n = alpha.rows, limit = int(0.02 * cv::countNonZero(disc));
    const double c = (n - 1) / 2.0, r = 0.47 * n;
    std::vector<uint8_t> keep(count, 0), hit(count, 0);
    for (int l = 1; l < count; ++l) {
        const int x0 = stats.at<int>(l, cv::CC_STAT_LEFT), y0 = stats.at<int>(l, cv::CC_STAT_TOP);
        const int x1 = x0 + stats.at<int>(l, cv::CC_STAT_WIDTH), y1 = y0 + stats.at<int>(l, cv::CC_STAT_HEIGHT);
        // Enclosed: its box stays off the rim (a clear patch reaching the horizon is sky, not a hole).
        const bool inside = std::hypot(x0 - c, y0 - c) < r && std::hypot(x1 - c, y0 - c) < r &&
                            std::hypot(x0 - c, y1 - c) < r && std::hypot(x1 - c, y1 - c) < r;
        keep[l] = inside && stats.at<int>(l, cv::CC_STAT_AREA) < limit;
    }
    // Only the holes that reach the sun's surroundings.
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            if (const int l = labels.at<int>(y, x); keep[l] && share.at<float>(y, x) > 0.5f) hit[l] = 1;
    cv::Mat result = cv::Mat::zeros(alpha.size(), CV_8UC1);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            if (hit[labels.at<int>(y, x)]) result.at<uint8_t>(y, x) = 255;
    // With its soft edge (2 % of the image).
    const int grow = std::max(1, int(std::lround(0.02 * n)));
    cv::dilate(result, result, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * grow + 1, 2 * grow + 1)));
    return result & disc;
}

// How much of the clear background each pixel of the start hides (CV_32FC1, 0 clear .. 1 cloud): the
// sun transmittance's soft per-pixel rule (motion/sun_patch.h cloudiness) against the background
// made the start's own (clear_sky_field). Unlike the networks' red/blue rule it does not call the
// aureole or a hazy horizon cloud: they match the background.
// Near the sun (circumsolar share, 1 within 15 degrees) the aureole is white and bright, so a grey
// cloud in front of it departs from it by less than the rule's thresholds (procedural cumulus within
// 6 degrees of the sun: luminance 0.78, red/blue 1.12-1.15 of the clear sky's) and read clear: carried
// over the sun, it let the sun shine on. There the thresholds tighten towards what the start's own
// clear sky allows: kClearSpreadFactor x the median log departure of its clearly clear pixels
// from the clear-sky model (a 90th percentile takes in the rule's own clear band, up to 1.12 in
// colour), never under kTightestCloudRatio / kTightestBrightnessRatio and never over the
// rule's own. A sky that matches its clear model closely (procedural) is judged closely near the
// sun; a photograph's clear sky, with its camera's departures, keeps the rule as it was: one whose
// colour departs too far to tighten keeps its brightness threshold too (its calibration fitted the
// brightness to the model, so that alone tightened, to 1.4 x on the ARM clear morning, and the
// glare between a low sun and the horizon read as cloud over a whole sun, putting it out). Both the
// spread and the tightened rule compare with the clear-sky model itself (`model`), not with the
// background made the start's own: that field, smooth and fitted at 128 px, is off by 3-10 % beside
// clouds (procedural cumulus at 512 px), more than the tightened rule allows.
constexpr double kClearSpreadFactor = 4.0;
constexpr double kTightestCloudRatio = 1.06, kTightestBrightnessRatio = 1.12;

cv::Mat background_opacity(const cv::Mat& start, const cv::Mat& background, const NetworkFormParams& form,
                           const cv::Mat& share, const cv::Mat& model) {
    const int big = start.rows;
    cv::Mat opacity(big, big, CV_32FC1, cv::Scalar(0));
    const cv::Mat disc = sky_disc_mask(big);
    auto radiance = [&](const cv::Vec3f& u) {
        Color v;
        for (int c = 0; c < 3; ++c) v[c] = unit_to_radiance(u[c], form.unit_map);
        return v;
    };
    const SunTransmittanceParams rule;
    tbb::parallel_for(0, big, [&](int y) {
        const cv::Vec3f* s = start.ptr<cv::Vec3f>(y);
        const cv::Vec3f* b = background.ptr<cv::Vec3f>(y);
        const uint8_t* in = disc.ptr<uint8_t>(y);
        float* o = opacity.ptr<float>(y);
        for (int x = 0; x < big; ++x)
            if (in[x]) o[x] = float(cloudiness(radiance(s[x]), radiance(b[x]), rule));
    });
    if (share.empty() || model.empty() || cv::countNonZero(share > 0.0f) == 0) return opacity;
    // How far the start's clearly clear pixels, away from the sun, depart from the model (log units,
    // median; every fourth pixel each way is plenty).
    std::vector<double> colour, brightness;
    for (int y = 0; y < big; y += 4)
        for (int x = 0; x < big; x += 4) {
            if (!disc.at<uint8_t>(y, x) || opacity.at<float>(y, x) > 0.02f || share.at<float>(y, x) > 0.0f) continue;
            const Color v = radiance(start.at<cv::Vec3f>(y, x)), m = radiance(model.at<cv::Vec3f>(y, x));
            if (!(luminance(m) > 0) || !(m[2] > 0) || !(v[2] > 0)) continue;
            colour.push_back(std::abs(std::log((v[0] / v[2]) / (m[0] / m[2]))));
            brightness.push_back(std::abs(std::log(std::max(double(luminance(v)), 1e-12) / luminance(m))));
        }
    if (colour.size() < 100) return opacity;  // too little clear sky to say how closely it matches
    auto median = [](std::vector<double>& v) {
        std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
        return v[v.size() / 2];
    };
    const double log_c = std::log(rule.cloud_ratio), log_b = std::log(rule.brightness_ratio);
    const double spread_c = kClearSpreadFactor * median(colour);
    if (spread_c >= log_c) return opacity;  // a photograph's colours: the rule as it was
    const double tight_c = std::clamp(spread_c, std::log(kTightestCloudRatio), log_c);
    const double tight_b = std::clamp(kClearSpreadFactor * median(brightness), std::log(kTightestBrightnessRatio),
                                      log_b);
    tbb::parallel_for(0, big, [&](int y) {
        const cv::Vec3f* s = start.ptr<cv::Vec3f>(y);
        const cv::Vec3f* b = model.ptr<cv::Vec3f>(y);
        const float* sh = share.ptr<float>(y);
        const uint8_t* in = disc.ptr<uint8_t>(y);
        float* o = opacity.ptr<float>(y);
        for (int x = 0; x < big; ++x) {
            if (!in[x] || !(sh[x] > 0)) continue;
            SunTransmittanceParams p = rule;
            p.cloud_ratio = std::exp(log_c + (tight_c - log_c) * sh[x]);
            p.brightness_ratio = std::exp(log_b + (tight_b - log_b) * sh[x]);
            o[x] = std::max(o[x], float(cloudiness(radiance(s[x]), radiance(b[x]), p)));
        }
    });
    return opacity;
}

// Where a cloud hides the clear background (CV_32FC1): 1 within 15 degrees of the sun, 0 beyond 30
// (a smoothstep between); all 0 without a sun. The bright aureole is sunlight scattered along the
// line of sight, much of it beyond a low cloud. Elsewhere the clouds compose additively over the
// background, as the long rollouts were tuned with: a real cloud brightens towards the sun by its
// own forward scattering much as the clear sky does (with 25-45 degrees a 3-hour rollout of the
// ARM photograph dipped to 0.79 of its start, 0.82 additively, 0.805 so).
// A photograph's clipped glare around its sun (network form, start at n px): the pixels at one
// value, the camera's clip level as calibrated, joined to the ring 3-8 degrees from the sun, when
// most of that ring holds it. Empty when the ring is not mostly one value (any sky not clipped
// there: procedural, Hosek-Wilkie, a photograph exposed for its sun).
cv::Mat glare_plateau(const cv::Mat& start, const Vec3d& sun) {
    const int n = start.rows;
    if (!(sun.y() > 0) || start.type() != CV_32FC3) return cv::Mat();
    const Vec3d s = sun.normalized();
    const double c3 = std::cos(3.0 * kPiD / 180), c8 = std::cos(8.0 * kPiD / 180);
    std::vector<cv::Vec3f> ring;
    cv::Mat near(n, n, CV_8UC1, cv::Scalar(0));
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            if (fisheye::pixel_center_uv(x, y, n).squaredNorm() > 1) continue;
            const double c = fisheye::direction_from_pixel(double(x), double(y), n).dot(s);
            if (c >= c8) near.at<uint8_t>(y, x) = 255;
            if (c >= c8 && c <= c3) ring.push_back(start.at<cv::Vec3f>(y, x));
        }
    if (ring.size() < 8) return cv::Mat();
    cv::Vec3f level;
    for (int k = 0; k < 3; ++k) {
        std::vector<float> v;
        for (const cv::Vec3f& p : ring) v.push_back(p[k]);
        std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
        level[k] = v[v.size() / 2];
    }
    auto at_level = [&](const cv::Vec3f& p, float tolerance) {
        return std::abs(p[0] - level[0]) <= tolerance && std::abs(p[1] - level[1]) <= tolerance &&
               std::abs(p[2] - level[2]) <= tolerance;
    };
    const long flat = std::count_if(ring.begin(), ring.end(), [&](const cv::Vec3f& p) { return at_level(p, 0.002f); });
    if (flat < long(0.6 * double(ring.size())) || !(level[0] + level[1] + level[2] > 0)) return cv::Mat();
    cv::Mat plateau(n, n, CV_8UC1, cv::Scalar(0));
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            if (fisheye::pixel_center_uv(x, y, n).squaredNorm() <= 1 && at_level(start.at<cv::Vec3f>(y, x), 0.004f))
                plateau.at<uint8_t>(y, x) = 255;
    // Only the pieces that reach within 8 degrees of the sun (a clipped cloud elsewhere is a cloud).
    cv::Mat labels;
    const int count = cv::connectedComponents(plateau, labels, 8, CV_32S);
    std::vector<char> keep(size_t(count), 0);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            if (near.at<uint8_t>(y, x) && plateau.at<uint8_t>(y, x)) keep[size_t(labels.at<int>(y, x))] = 1;
    keep[0] = 0;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            if (!keep[size_t(labels.at<int>(y, x))]) plateau.at<uint8_t>(y, x) = 0;
    cv::dilate(plateau, plateau, cv::Mat(), cv::Point(-1, -1), 1);  // its edge, resampled half way
    return plateau;
}

// Within kGlareHaloDeg of a sun whose camera clipped around it (glare_plateau), or that the start
// shows whole, the start's glow beyond the model's background is measured once, at the start's sun:
// per channel and 1-degree ring, the lower quartile of start - background (at least 0, never more
// than the ring inside: a glow falls off away from the sun, a cloud stands out of its ring). It is
// added to the background around the sun of every step (halo_background), so the glow is neither
// cloud nor moved, and goes with the sun as the clock moves it. On a clear all-sky photograph
// (WSISEG 077) the camera's clipped glare was read as cloud next to the sun, carried onto it by the
// wind and put it out for 14 of 40 steps; a hazy sky's or a downloaded HDRI's aureole, brighter and
// whiter than the model's, was torn off the sun (a white crescent downwind, a pink hole at the sun),
// and a cloud then moved onto the sun did not dim it (the start's sun counted as covered already).
constexpr double kGlareHaloDeg = 35.0;
constexpr double kHaloSeenShare = 0.25;  // a ring's share of seen (not filled) pixels to be measured
// A glow rises towards the sun no faster than (angle)^-kHaloSteepest from the rings outside it,
// whose glow is taken as at least kHaloFloorShare of their background: a lens's glare and the
// atmosphere's aureole fall off as about the inverse square of the angle (a clipped plateau is
// flatter still). Without it, a broken-cumulus photograph whose sun sat amid cloud (ARM 17:19Z:
// every seen pixel 12-17 degrees out cloud-white) measured its cloud as glow: 60 W m^-2 sr^-1 out to
// 18 degrees, 2 beyond 24, a pale disc with a hard, coloured rim kept around the sun as its clouds
// moved off.
constexpr double kHaloSteepest = 4.0;
constexpr double kHaloFloorShare = 0.02;

// Angle from the sun (degrees) of each pixel of an n x n sky, -1 outside the disc or beyond the halo.
cv::Mat halo_angles(int n, const Vec3d& sun) {
    const Vec3d s = sun.normalized();
    cv::Mat angle(n, n, CV_32FC1, cv::Scalar(-1));
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            if (fisheye::pixel_center_uv(x, y, n).squaredNorm() > 1) continue;
            const double a = std::acos(std::clamp(fisheye::direction_from_pixel(double(x), double(y), n).dot(s), -1.0,
                                                  1.0)) *
                             180 / kPiD;
            if (a < kGlareHaloDeg) angle.at<float>(y, x) = float(a);
        }
    return angle;
}

}  // namespace

// Per ring, in radiance (a glow adds light; the network form is logarithmic, and an added glow's
// share of it changes with the sky under it around the ring). The pixels an import filled (a TSI's
// shadow band lies over the sun, its arm nearby) say nothing of the glow and are left out; a ring
// with none left takes the nearest ring outwards that has some (inside the first) or the ring
// inside (beyond the horizon). Of each ring, the pixels between the 20th and 30th percentile of
// the excess luminance give the excess, all three channels from the same pixels: taken per channel
// (lower quartiles of different pixels) an ARM photograph's glow came out magenta (R 20, G 14, B 20)
// and left a pink ring 30-35 degrees around the sun once the clouds moved off it.
std::vector<cv::Vec3f> halo_excess(const cv::Mat& start, const cv::Mat& background, const Vec3d& sun,
                                   const UnitMapParams& unit, const cv::Mat& filled) {
    const int n = start.rows, rings = int(kGlareHaloDeg);
    const cv::Mat angle = halo_angles(n, sun);
    cv::Mat hidden = filled;
    if (!hidden.empty() && hidden.size() != start.size())
        cv::resize(filled, hidden, start.size(), 0, 0, cv::INTER_NEAREST);
    std::vector<std::vector<std::pair<float, cv::Vec3f>>> values(static_cast<size_t>(rings));
    std::vector<int> in_ring(static_cast<size_t>(rings), 0);
    std::vector<double> background_sum(static_cast<size_t>(rings), 0.0);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            if (const float a = angle.at<float>(y, x); a >= 0) {
                ++in_ring[size_t(a)];
                const cv::Vec3f s = start.at<cv::Vec3f>(y, x), b = background.at<cv::Vec3f>(y, x);
                background_sum[size_t(a)] += luminance(unit_to_radiance(b[0], unit), unit_to_radiance(b[1], unit),
                                                       unit_to_radiance(b[2], unit));
                if (!hidden.empty() && hidden.at<uint8_t>(y, x)) continue;
                cv::Vec3f e;
                for (int k = 0; k < 3; ++k) e[k] = unit_to_radiance(s[k], unit) - unit_to_radiance(b[k], unit);
                values[size_t(a)].push_back({luminance(e[0], e[1], e[2]), e});
            }
    std::vector<cv::Vec3f> excess(size_t(rings), cv::Vec3f(0, 0, 0));
    std::vector<bool> known(size_t(rings), false);
    for (int r = 0; r < rings; ++r) {
        auto& v = values[size_t(r)];
        // A ring mostly hidden says little, and what it shows lies beside the hidden part (the
        // glare along a TSI's band): taken for the rings inside it, a few bright pixels made a
        // pale disc with a hard edge 12 degrees around the sun (ARM 17:51Z, 36 of 550 pixels seen).
        if (v.empty() || double(v.size()) < kHaloSeenShare * in_ring[size_t(r)]) continue;
        std::sort(v.begin(), v.end(), [](const auto& p, const auto& q) { return p.first < q.first; });
        const size_t lo = v.size() / 5, hi = std::max(lo + 1, (3 * v.size()) / 10);
        cv::Vec3f sum(0, 0, 0);
        for (size_t i = lo; i < hi; ++i) sum += v[i].second;
        const cv::Vec3f mean = sum * (1.0f / float(hi - lo));
        for (int k = 0; k < 3; ++k) excess[size_t(r)][k] = std::max(0.0f, mean[k]);
        known[size_t(r)] = true;
    }
    const auto first = std::find(known.begin(), known.end(), true);
    if (first == known.end()) return {};
    // No steeper than a glow can rise towards the sun (kHaloSteepest), from the nearest measured
    // ring outside (scaled as a whole, so the ring keeps its colour).
    const auto luminance_of = [](const cv::Vec3f& e) { return luminance(e[0], e[1], e[2]); };
    int outer = -1;
    for (int r = rings - 1; r >= 0; --r) {
        if (!known[size_t(r)]) continue;
        if (outer >= 0) {
            const double floor = kHaloFloorShare * background_sum[size_t(outer)] / std::max(1, in_ring[size_t(outer)]);
            const double cap = std::max(double(luminance_of(excess[size_t(outer)])), floor) *
                               std::pow((outer + 0.5) / (r + 0.5), kHaloSteepest);
            const double here = luminance_of(excess[size_t(r)]);
            if (here > cap) excess[size_t(r)] *= float(cap / here);
        }
        outer = r;
    }
    for (int r = 0; r < rings; ++r)
        if (!known[size_t(r)])
            excess[size_t(r)] = r < first - known.begin() ? excess[size_t(first - known.begin())]
                                                          : excess[size_t(r) - 1];
    // A glow falls off away from the sun: never more light than the ring inside (scaled as a whole,
    // so the ring keeps its colour).
    for (int r = 1; r < rings; ++r) {
        const float inside = luminance_of(excess[size_t(r) - 1]), here = luminance_of(excess[size_t(r)]);
        if (here > inside) excess[size_t(r)] *= here > 0 ? std::max(0.0f, inside) / here : 0.0f;
    }
    // None (a sky the model explains, as its own clear skies): nothing to add at any step.
    if (luminance_of(excess.front()) <= 0) return {};
    return excess;
}

namespace {

// angle: halo_angles of the background's size and the sun it is added around.
void halo_background(const std::vector<cv::Vec3f>& excess, const cv::Mat& angle, const UnitMapParams& unit,
                     cv::Mat* background) {
    const int n = background->rows, rings = int(excess.size());
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const float a = angle.at<float>(y, x);
            if (a < 0) continue;
            // Linear between ring centres, fading out over the last 5 degrees.
            const float f = std::clamp(a - 0.5f, 0.0f, float(rings - 1));
            const int r0 = int(f), r1 = std::min(rings - 1, r0 + 1);
            const cv::Vec3f e = (1 - (f - r0)) * excess[size_t(r0)] + (f - r0) * excess[size_t(r1)];
            const float fade = std::clamp((float(kGlareHaloDeg) - a) / 5.0f, 0.0f, 1.0f);
            cv::Vec3f& b = background->at<cv::Vec3f>(y, x);
            for (int k = 0; k < 3; ++k)
                if (e[k] > 0) b[k] = radiance_to_unit(unit_to_radiance(b[k], unit) + fade * e[k], unit);
        }
}

// The glow's share of the background it was added to (luminance, radiance; the background
// unweighted: the network form is logarithmic, and a weight scales it there, not in radiance) over
// its outer rings, 28 to 35 degrees from the sun, as halo_background adds it (fading out over the
// last 5 degrees); halo_angles `angle` of the background's size.
double outer_glow_share(const std::vector<cv::Vec3f>& excess, const cv::Mat& angle, const cv::Mat& background,
                        const UnitMapParams& unit) {
    double glow = 0, sky = 0;
    const int rings = int(excess.size());
    for (int y = 0; y < background.rows; ++y)
        for (int x = 0; x < background.cols; ++x) {
            const float a = angle.at<float>(y, x);
            if (a < 28 || int(a) >= rings) continue;
            const cv::Vec3f b = background.at<cv::Vec3f>(y, x), e = excess[size_t(a)];
            const double fade = std::clamp((kGlareHaloDeg - a) / 5.0, 0.0, 1.0);
            glow += fade * luminance(e[0], e[1], e[2]);
            sky += luminance(unit_to_radiance(b[0], unit), unit_to_radiance(b[1], unit), unit_to_radiance(b[2], unit));
        }
    return sky > 0 ? glow / sky : 0.0;
}

cv::Mat circumsolar_share(int n, const std::optional<Vec3d>& sun, double inner_deg, double outer_deg) {
    cv::Mat share(n, n, CV_32FC1, cv::Scalar(0));
    if (!sun) return share;
    const Vec3d s = sun->normalized();
    const double inner = std::cos(inner_deg * kPiD / 180), outer = std::cos(outer_deg * kPiD / 180);
    tbb::parallel_for(0, n, [&](int y) {
        float* o = share.ptr<float>(y);
        for (int x = 0; x < n; ++x) {
            const double c = fisheye::direction_from_pixel(double(x), double(y), n).dot(s);
            o[x] = float(smoothstep01((c - outer) / (inner - outer)));
        }
    });
    return share;
}

}  // namespace

cv::Mat filled_mask(const SkyImage& sky) {
    const int n = sky.resolution;
    if (sky.filled.size() != size_t(n) * n) return cv::Mat();
    return cv::Mat(n, n, CV_8UC1, const_cast<unsigned char*>(sky.filled.data())) * 255;  // a copy
}

double start_departs_from(const cv::Mat& start, const cv::Mat& background, const cv::Mat& disc) {
    cv::Mat d;
    cv::absdiff(start, background, d);
    std::vector<cv::Mat> ch;
    cv::split(d, ch);
    const cv::Mat departs = cv::max(ch[0], cv::max(ch[1], ch[2])) > kClearStartTolerance;
    return double(cv::countNonZero(departs & disc)) / std::max(1, cv::countNonZero(disc));
}

double network_trust_of_brightness(double median_radiance) {
    constexpr double kNone = 0.1, kFull = 1.0;  // W m^-2 sr^-1
    if (!(median_radiance > kNone)) return 0.0;
    return std::min(1.0, std::log(median_radiance / kNone) / std::log(kFull / kNone));
}

CloudRollout::CloudRollout(AdvectResidualNetwork* network, const cv::Mat& start, const CloudFlow& flow,
                           const cv::Mat& background, const cv::Mat& unseen, const std::optional<Vec3d>& sun,
                           bool sun_seen_whole, const cv::Mat& filled)
    : network_(network),
      flow_(flow),
      start_(start.clone()),
      state_(start.clone()),
      unseen_(unseen),
      filled_(filled),
      sun_seen_whole_(sun_seen_whole) {
    keep_large_allocations();  // each step's full-sky temporaries would page-fault in again
    const int n = network->info().resolution, big = start.rows;
    if (flow.measured.rows != big || flow.measured.cols != big || flow.measured.type() != CV_32FC2)
        throw Error("advect-residual: the flow must be CV_32FC2 at the state's resolution " + std::to_string(big));
    if (big < n) throw Error("advect-residual: the state is smaller than the network's " + std::to_string(n) + " px");
    flow_small_ = flow.resized(n);
    disc_big_ = sky_disc_mask(big), disc_n_ = sky_disc_mask(n);
    start_ext_ = extend_past_rim_exact(start_);
    if (!flow.recycle) {  // the composed source positions (with a wind the layer's paths serve instead)
        positions_ = cv::Mat(big, big, CV_32FC2);
        for (int y = 0; y < big; ++y)
            for (int x = 0; x < big; ++x) positions_.at<cv::Vec2f>(y, x) = cv::Vec2f(float(x), float(y));
    }
    corrections_ = cv::Mat(big, big, CV_32FC3, cv::Scalar::all(0));
    if (network->has_network()) {
        // The start's median radiance: its channels' mean in the log map, mapped back (about their
        // geometric mean), on about 13,000 pixels at any size.
        const int stride = std::max(1, big / 128);
        std::vector<float> radiance;
        for (int y = stride / 2; y < big; y += stride)
            for (int x = stride / 2; x < big; x += stride)
                if (disc_big_.at<unsigned char>(y, x)) {
                    const cv::Vec3f v = start_.at<cv::Vec3f>(y, x);
                    radiance.push_back(unit_to_radiance((v[0] + v[1] + v[2]) / 3, network->info().form.unit_map));
                }
        if (!radiance.empty()) network_trust_ = network_trust_of_brightness(median(std::move(radiance)));
    }
    if (!flow.hold_background) {
        // Held by the clear share of the start sky (the cloud rule on the networks' image).
        cv::Mat small;
        cv::resize(start_, small, cv::Size(n, n), 0, 0, cv::INTER_AREA);
        const double cover = double(cv::countNonZero(network_cloud_mask(small, network->info().form) & disc_n_)) /
                             std::max(1, cv::countNonZero(disc_n_));
        background_weight_ = std::clamp(1.0 - cover, 0.0, 1.0);
    }
    if (flow.recycle) {
        const bool relaxing = !flow.wind.empty() && flow.relax_steps > 0;
        const cv::Mat& wind = relaxing ? flow.wind : flow.measured;
        if (relaxing) {
            departure_ = flow.measured - flow.wind;
            if (!flow.detail.empty()) departure_ -= flow.detail, detail_ = flow.detail;
        }
        paths_ = std::make_unique<CloudLayerPaths>(big, layer_step_of_flow(wind));
    }
    set_background(background, sun);
}

void CloudRollout::set_background(const cv::Mat& given, const std::optional<Vec3d>& sun) {
    sun_ = sun;
    // A start that is the model's clear sky (within 0.01 of the log map, about 2 % in radiance,
    // on all but 2 % of the disc) has no cloud to grow or thin: the network is not asked. At
    // sunset the cloud rule reads a clear sky's red as cloud everywhere, and the network's
    // corrections brightened it 2.5 % on the first step and 4 % within ten (a compare of a clear
    // start over sunset read 6 % more light than the clear sky). Photographs of clear skies
    // depart from the model on 90 % of the disc and procedural cumulus on 60 %: unchanged.
    // Judged once, against the first background (the start's sun): the timeline gives a new one
    // each time the sun moves, and the start stays what it was.
    if (!clear_start_judged_ && !given.empty() && given.size() == start_.size()) {
        clear_start_judged_ = true;
        // Counted away from the sun (its cut pixels and glow depart from any model).
        const cv::Mat away = sun ? disc_big_ & ~sun_cone_mask(start_.rows, *sun, kClearStartSunDeg) : disc_big_;
        if (start_departs_from(start_, given, away) < kClearStartShare) network_trust_ = 0.0;
    }
    cv::Mat background, clipped, halo_angle;  // halo_angle: halo_angles of the sun, where a halo is added
    // An overcast start (the networks' cloud rule finds cloud on at least 90 % of the disc) shows no
    // clear sky: what stays where it is while its clouds move is its own light, the large-scale
    // brightening towards the sun, not the model's clear sky. Over the model's clear sky the grey
    // carried from the bright west to the zenith took the zenith's blue, and where the grey matched
    // the dim model at dusk it read clear: blue bands grew through the ARM dusk's overcast (cloud
    // cover 1.00 -> 0.73 in 6 steps). Its background is the start blurred over 20 degrees instead,
    // and all of it is cloud. Not a start that shows its sun whole: a clear sky at sunrise is red
    // enough all over for the cloud rule, and its sun went out.
    bool overcast = false;
    cv::Mat rule_cloud;
    if (!given.empty() && !sun_seen_whole_) {
        rule_cloud = network_cloud_mask(start_, network_->info().form) & disc_big_;
        const int disc_pixels = cv::countNonZero(disc_big_);
        overcast = disc_pixels > 0 && cv::countNonZero(rule_cloud) >= 0.9 * disc_pixels;
    }
    if (overcast) {
        cv::Mat weight, masked, blurred, spread;
        disc_big_.convertTo(weight, CV_32F, 1.0 / 255.0);
        cv::Mat weight3;
        cv::merge(std::vector<cv::Mat>{weight, weight, weight}, weight3);
        masked = start_.mul(weight3);
        // Blurred at most at 256 px and brought back up (a 20-degree blur holds nothing finer): at
        // the sky's own size the blur's cost grew as N^3, and one step of a 4096 px overcast did
        // not end in 5 minutes.
        const int small = std::min(start_.rows, 256);
        const cv::Size small_size(small, small);
        if (small < start_.rows) {
            cv::resize(masked, masked, small_size, 0, 0, cv::INTER_AREA);
            cv::resize(weight3, weight3, small_size, 0, 0, cv::INTER_AREA);
        }
        const double sigma = 20.0 / 180.0 * small;
        cv::GaussianBlur(masked, blurred, cv::Size(), sigma, sigma, cv::BORDER_CONSTANT);
        cv::GaussianBlur(weight3, spread, cv::Size(), sigma, sigma, cv::BORDER_CONSTANT);
        cv::divide(blurred, cv::max(spread, 1e-6), background);
        if (small < start_.rows) cv::resize(background, background, start_.size(), 0, 0, cv::INTER_LINEAR);
        background.setTo(cv::Scalar::all(0), ~disc_big_);
    } else if (!given.empty()) {
        // Where the model's clear sky clips (the sun's aureole) the start was filled in too: there
        // the background is the start itself, so nothing of the sun moves with the clouds.
        // The model's clear sky made the start's own where the start is clear (clear_sky_field):
        // only what differs from it moves.
        if (background_field_.empty()) background_field_ = clear_sky_field(start_, given, network_->info().form);
        background = given.mul(background_field_);
        cv::min(background, 1.0, background);
        background.setTo(cv::Scalar::all(0), ~disc_big_);
        std::vector<cv::Mat> ch;
        cv::split(given, ch);
        clipped = (ch[0] >= 0.999f) | (ch[1] >= 0.999f) | (ch[2] >= 0.999f);
        cv::dilate(clipped, clipped, cv::Mat(), cv::Point(-1, -1), 2);
        // A photograph's clipped glare around its sun stays with it, as does its halo; so does the
        // glow around a sun the start shows whole (no cloud on it): halo_excess.
        if (sun_) {
            const cv::Mat glare = glare_plateau(start_, *sun_);
            if (!halo_measured_) {
                halo_measured_ = true;
                if (!glare.empty() || sun_seen_whole_)
                    halo_excess_ = halo_excess(start_, given, *sun_, network_->info().form.unit_map, filled_);
            }
            if (!halo_excess_.empty()) {
                halo_angle = halo_angles(background.rows, *sun_);
                halo_background(halo_excess_, halo_angle, network_->info().form.unit_map, &background);
                cv::min(background, 1.0, background);
            }
            if (!glare.empty()) clipped |= glare;
        }
        start_.copyTo(background, clipped);
    }
    background_ = background.empty() ? cv::Mat() : background * background_weight_;
    background_ext_ = background_.empty() ? cv::Mat() : extend_past_rim_exact(background_);
    opacity_ext_ = cloud_own_ext_ = opacity_ = cv::Mat();
    if (!background_.empty()) {
        // A cloud hides the sun's aureole it covers, where it was seen and wherever it goes: a
        // pixel moving onto or off it moves as opacity x its own value + (1 - opacity) x (its
        // cloud signal over the background held still). Composed purely additively, a cloud moved onto the aureole kept
        // the aureole under it: 14-18 % too much light once a cloud had covered the sun on a
        // procedural sky (tests/motion/sun_transmittance_test.cpp). Only near the sun
        // (circumsolar_share): over the whole sky it darkened a 3-hour rollout of the ARM photograph
        // to 0.78 of its start (0.82 additively; tests/motion/advect_residual_test.cpp).
        share_ = circumsolar_share(start_.rows, sun_);
        // Judged against the model with the start's glow (halo_excess): a glow the model lacks is
        // not cloud near the sun either.
        cv::Mat model = given;
        if (!halo_angle.empty()) {
            model = given.clone();
            halo_background(halo_excess_, halo_angle, network_->info().form.unit_map, &model);
        }
        cv::Mat alpha = background_opacity(start_, background, network_->info().form, share_, model);
        if (overcast) {
            // Its clouds are opaque (they cover the sun), and compose additively over its own light
            // everywhere (nothing of the model's aureole to hide).
            alpha.setTo(1.0f, rule_cloud);
            share_.setTo(0.0f);
        }
        // The sun's pixels were cut out (darker than the clear sky's sun there, they would read as
        // cloud over it), and where the model's sky clips the background is the start itself: the
        // start says nothing there, so they take the opacity of the clouds around them. Counted
        // clear, a cloud at the sun's edge in the start was carried over the sun as clear sky (the
        // cut spans 4-6 degrees at 128 px): on 14 procedural skies whose cumulus crosses the sun
        // the sun shone on at full strength, up to 200 % over the truth (docs/animation.md).
        cv::Mat unknown = clipped.empty() ? cv::Mat() : clipped.clone();
        if (!unseen_.empty()) unknown = unknown.empty() ? unseen_.clone() : (unknown | unseen_);
        if (!filled_.empty()) unknown = unknown.empty() ? filled_.clone() : (unknown | filled_);
        if (!unknown.empty()) fill_from_around(&alpha, unknown & disc_big_, disc_big_);
        // A cloud lit by forward scattering can look as clear as the aureole: the sun it dimmed says
        // more. Its opacity goes on the cut and (nearly all of it) kSunCoverSpreadDeg around it, so
        // that it moves off the sun with the cloud that covers it: on the cut alone (4-6 degrees at
        // 128 px) it left the sun while the cloud was still over it, and the clear sun came back up
        // to 70 s early on 3 of 6 procedural skies whose sun starts covered (up to 171 % over the truth). Grown from
        // there over the pixels the start shows at least half cloudy it did not grow at all: the
        // forward-lit cloud around the sun reads clear (docs/animation.md).
        if (unseen_opacity_ > 0 && !unseen_.empty()) {
            cv::Mat region;
            const int r = std::max(1, int(std::lround(kSunCoverSpreadDeg * start_.rows / 180.0)));
            cv::dilate(unseen_, region, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * r + 1, 2 * r + 1)));
            region &= disc_big_;
            const double ring = kSunCoverRing * unseen_opacity_;
            alpha.setTo(cv::Scalar(ring), region & (alpha < ring));
            alpha.setTo(cv::Scalar(unseen_opacity_), unseen_ & disc_big_ & (alpha < unseen_opacity_));
        }
        // The start's glow (halo_excess) is background a cloud hides wherever it goes: the clouds
        // compose by opacity over all of it. Composed additively beyond 30 degrees, the clouds a
        // wind carried into its outer rings shone with it: a hazy Mobotix photograph (11:59 CEST,
        // its glow still half the sky's 30 degrees out) drew an orange ring 30-35 degrees around its
        // sun within two steps, where the glow ends.
        // Only where the glow there is more than a few percent of the sky (a procedural sky's,
        // 0.1 % at the sun, left the composition as it was: clouds near the sun brighten as they
        // come, as additive composition has them).
        const cv::Mat near_sun = share_.clone();
        if (!halo_excess_.empty() && !overcast && !halo_angle.empty()) {
            const double outer = outer_glow_share(halo_excess_, halo_angle, background, network_->info().form.unit_map);
            const double w = smoothstep01((outer - 0.02) / (0.08 - 0.02));
            if (w > 0)
                cv::max(share_, w * circumsolar_share(start_.rows, sun_, kGlareHaloDeg, kGlareHaloDeg + 10.0), share_);
        }
        cv::Mat alpha3, carried;
        cv::merge(std::vector<cv::Mat>{alpha, alpha, alpha}, alpha3);
        std::vector<cv::Mat> ch;
        cv::split(background_.mul(alpha3), ch);
        ch.push_back(alpha);
        ch.push_back(share_);
        cv::merge(ch, carried);
        opacity_ext_ = extend_past_rim_exact(carried);
        // What the recycled tile carries: a x the cloud's own radiance (start - (1 - a) x
        // background) and a. Where the start says nothing (the sun's cut, the clipped aureole) the
        // radiance of the clouds around: as the start there it was the background's, and a cloud
        // carried over the sun's place showed a clear hole where the sun had been.
        // So do clear holes inside a cloud near the sun: a cloud lit from behind matches the
        // aureole and reads clear there, and carried elsewhere it showed a blue hole.
        cv::Mat own = start_ - background_ + background_.mul(alpha3);
        cv::Mat tile_unknown = enclosed_clear_near_sun(alpha, near_sun, disc_big_);
        if (!unknown.empty()) tile_unknown |= unknown & disc_big_;
        std::vector<cv::Mat> oc;
        cv::split(own, oc);
        oc.push_back(alpha.clone());
        if (cv::countNonZero(tile_unknown) > 0)
            for (cv::Mat& c : oc) fill_from_around(&c, tile_unknown, disc_big_);
        cv::merge(oc, own);
        cloud_own_ext_ = extend_past_rim_exact(own);
        opacity_ = alpha;
        if (steps_ == 0) carried_opacity_ = alpha;
        // The tile's seam through the start's clearest sky (once: the opacity hardly changes as
        // the sun moves).
        if (paths_ && !seam_chosen_) paths_->choose_seam(alpha), seam_chosen_ = true;
    }
    clouds_ext_ = background_ext_.empty() ? start_ext_ : start_ext_ - background_ext_;
    clouds_ = background_.empty() ? start_ : start_ - background_;
    cloud_field_ = opacity_.empty() ? cloud_signal_field(clouds_)
                                    : cloud_brightness_field(start_, background_, opacity_);
    background_n_ = background_;
    const int n = network_->info().resolution;
    if (!background_.empty() && background_.rows != n) {
        cv::resize(background_, background_n_, cv::Size(n, n), 0, 0, cv::INTER_AREA);
        background_n_.setTo(cv::Scalar::all(0), ~disc_n_);
    }
}

const cv::Mat& CloudRollout::advance() {
    const int n = network_->info().resolution, big = start_.rows, k = ++steps_;
    // The flow of this step (fixed, or relaxing towards the wind).
    const cv::Mat f_big = flow_.at(k), f_n = flow_small_.at(k);
    cv::Mat compensation_n;
    if (!background_.empty()) compensation_n = background_n_ - warp_in_disc(background_n_, f_n);
    const cv::Mat sources = warp_sources(f_big);
    if (sun_) {
        const cv::Vec2f f = flow_at_direction(f_big, *sun_);
        sun_travel_ += cv::Vec2d(f[0], f[1]);
    }
    // The corrections ride along and fade (e-folding kCorrectionSteps = 1): what the network adds is
    // a short-lived change of the clouds; kept, a small bias per step adds up to weather nobody
    // asked for. On the validation frames (not the held-out ones) an e-folding of 6 steps lost
    // 0.4-0.5 dB to persistence 6 steps ahead on the clear ARM morning, and 1 step gained 0.5 dB
    // there and on the dusk, at a cost on the Mobotix morning (still ahead of both baselines).
    corrections_ = sample_exact(extend_past_rim_exact(corrections_), sources) * kCorrectionFade;
    cv::Mat moved;
    if (paths_) {
        // The clouds where the layer's paths lead (the background stays where it is).
        // The measured flow's departure from its wind moves the clouds too while it relaxes: a
        // displacement of the start image's clouds, read where each path starts (it rides with
        // the clouds). After kDepartureHoldSteps it fades out again (e-folding as long): kept for
        // hours, Farneback's local errors, summed over the relaxation, warp every cloud that
        // passes into smears; the first steps, where it counts, keep it all (+0.4 dB one step
        // ahead on held-out ARM frames over the wind alone).
        cv::Mat offset;
        if (!departure_.empty()) {
            departure_sum_ += std::exp(-(k - 1) / flow_.relax_steps);
            const double fade = k <= kDepartureHoldSteps ? 1.0
                                                         : std::exp(-(k - kDepartureHoldSteps) / kDepartureHoldSteps);
            offset = departure_ * (departure_sum_ * fade);
            // The confirmed detail moves them once, on the first step, and rides along (as much
            // as the departure keeps): iterated, a sharp flow folds the clouds into swirls.
            if (!detail_.empty()) offset += detail_ * fade;
        }
        CloudLayerPaths::Reads reads = paths_->at(k);
        moved = cv::Mat(big, big, CV_32FC3, cv::Scalar::all(0));
        if (!opacity_.empty()) carried_opacity_ = cv::Mat(big, big, CV_32FC1, cv::Scalar(0));
        for (int i = 0; i < CloudLayerPaths::kReadCount; ++i) {
            if (cv::countNonZero(reads.weights[i]) == 0) continue;
            const bool own = i == CloudLayerPaths::kOwnRead, real = i == CloudLayerPaths::kRealRead;
            if (!offset.empty() && !own) reads.positions[i] -= sample_exact(offset, reads.positions[i]);
            if (!own && !real && !opacity_.empty()) {
                // The recycled tile: a cloud composed over the background where it is shown, its
                // opacity x its own radiance (cloud_own_ext_), that radiance scaled by the clouds'
                // brightness around here over there (cloud_brightness_field), + (1 - a) x the
                // background here. Its cloud signal scaled instead (cloud_signal_field: how much
                // cloud is around each place) made an opaque cloud carried into a clear part of the
                // start translucent: a grey haze once the whole view had been carried away
                // (docs/networks-advect-residual.md).
                const cv::Mat there = sample_exact(cloud_own_ext_, reads.positions[i]);
                tbb::parallel_for(0, big, [&](int y) {
                    const cv::Vec2f* p = reads.positions[i].ptr<cv::Vec2f>(y);
                    const float* w = reads.weights[i].ptr<float>(y);
                    const float* here = cloud_field_.ptr<float>(y);
                    const cv::Vec4f* o = there.ptr<cv::Vec4f>(y);
                    const cv::Vec3f* b = background_.ptr<cv::Vec3f>(y);
                    cv::Vec3f* m = moved.ptr<cv::Vec3f>(y);
                    float* a = carried_opacity_.ptr<float>(y);
                    for (int x = 0; x < big; ++x) {
                        if (w[x] == 0) continue;
                        const int px = std::clamp(int(std::lround(p[x][0])), 0, big - 1);
                        const int py = std::clamp(int(std::lround(p[x][1])), 0, big - 1);
                        const float gain = std::clamp(here[x] / cloud_field_.at<float>(py, px), 0.5f, 2.0f);
                        m[x] += w[x] * (gain * cv::Vec3f(o[x][0], o[x][1], o[x][2]) - o[x][3] * b[x]);
                        a[x] += w[x] * o[x][3];
                    }
                });
                continue;
            }
            // The pixel itself (kOwnRead): the start as it was (not rim-extended).
            cv::Mat read = own ? clouds_ : sample_exact(clouds_ext_, reads.positions[i]);
            if (!own && !real) {
                // The recycled tile without opacities: the start's cloud signal scaled where it is
                // shown (cloud_signal_field).
                read = read.clone();
                tbb::parallel_for(0, big, [&](int y) {
                    const cv::Vec2f* p = reads.positions[i].ptr<cv::Vec2f>(y);
                    const float* w = reads.weights[i].ptr<float>(y);
                    const float* here = cloud_field_.ptr<float>(y);
                    cv::Vec3f* v = read.ptr<cv::Vec3f>(y);
                    for (int x = 0; x < big; ++x) {
                        if (w[x] == 0) continue;
                        const int px = std::clamp(int(std::lround(p[x][0])), 0, big - 1);
                        const int py = std::clamp(int(std::lround(p[x][1])), 0, big - 1);
                        const double gain = here[x] / cloud_field_.at<float>(py, px);
                        // (A field equal to within rounding leaves the clouds bit for bit as read.)
                        if (std::abs(gain - 1.0) > 1e-4) v[x] *= float(std::clamp(gain, 0.5, 2.0));
                    }
                });
            }
            // What a cloud hid where it was read stays hidden: its opacity x (the background there
            // - the background here), when either place is near the sun (circumsolar_share). The
            // pixel itself has nothing to add. Every read carries its opacity.
            const cv::Mat hidden = !real || opacity_ext_.empty() ? cv::Mat()
                                                                 : sample_exact(opacity_ext_, reads.positions[i]);
            tbb::parallel_for(0, big, [&](int y) {
                const float* w = reads.weights[i].ptr<float>(y);
                const cv::Vec3f* r = read.ptr<cv::Vec3f>(y);
                cv::Vec3f* m = moved.ptr<cv::Vec3f>(y);
                for (int x = 0; x < big; ++x) m[x] += w[x] * r[x];
                if (opacity_.empty()) return;
                float* a = carried_opacity_.ptr<float>(y);
                if (hidden.empty()) {
                    const float* read_alpha = opacity_.ptr<float>(y);
                    for (int x = 0; x < big; ++x) a[x] += w[x] * read_alpha[x];
                    return;
                }
                const Hidden* h = hidden.ptr<Hidden>(y);
                const cv::Vec3f* b = background_.ptr<cv::Vec3f>(y);
                const float* c = share_.ptr<float>(y);
                for (int x = 0; x < big; ++x) {
                    if (w[x] == 0) continue;
                    a[x] += w[x] * h[x][3];
                    m[x] += w[x] * std::max(h[x][4], c[x]) * (cv::Vec3f(h[x][0], h[x][1], h[x][2]) - h[x][3] * b[x]);
                }
            });
        }
        if (!background_.empty()) moved += background_;
    } else {
        positions_ = sample_exact(positions_, sources);
        // The clouds where their paths lead (the background stays where it is: + B - B(path)).
        moved = sample_exact(start_ext_, positions_);
        if (!background_.empty()) {
            moved += background_ - sample_exact(background_ext_, positions_);
            const cv::Mat hidden = sample_exact(opacity_ext_, positions_);  // as with the layer's paths
            carried_opacity_ = cv::Mat(big, big, CV_32FC1);
            tbb::parallel_for(0, big, [&](int y) {
                const Hidden* h = hidden.ptr<Hidden>(y);
                const cv::Vec3f* b = background_.ptr<cv::Vec3f>(y);
                const float* c = share_.ptr<float>(y);
                cv::Vec3f* m = moved.ptr<cv::Vec3f>(y);
                float* a = carried_opacity_.ptr<float>(y);
                for (int x = 0; x < big; ++x) {
                    m[x] += std::max(h[x][4], c[x]) * (cv::Vec3f(h[x][0], h[x][1], h[x][2]) - h[x][3] * b[x]);
                    a[x] = h[x][3];
                }
            });
        }
        // Sky whose path comes from beyond the horizon was never seen: it shows what the start showed
        // there (blended in over the last 3 % of the radius), not the rim's values dragged inwards, so
        // hours of wind neither streak the sky nor clear or fill it.
        const double c = (big - 1) / 2.0, rim = (1.0 - 1.5 / big) * big / 2.0, band = 0.03 * big / 2.0;
        tbb::parallel_for(0, big, [&](int y) {
            const cv::Vec2f* p = positions_.ptr<cv::Vec2f>(y);
            cv::Vec3f* m = moved.ptr<cv::Vec3f>(y);
            const cv::Vec3f* s0 = start_.ptr<cv::Vec3f>(y);
            float* o = carried_opacity_.empty() ? nullptr : carried_opacity_.ptr<float>(y);
            for (int x = 0; x < big; ++x) {
                const double r = std::hypot(p[x][0] - c, p[x][1] - c);
                if (r <= rim - band) continue;
                const float a = float(std::min(1.0, (r - (rim - band)) / band));
                m[x] = (1 - a) * m[x] + a * s0[x];
                if (o) o[x] = (1 - a) * o[x] + a * opacity_.at<float>(y, x);
            }
        });
    }
    const cv::Mat lagrangian = moved.clone();
    moved += corrections_;
    if (network_->has_network()) {
        // The network sees the last step's image at N, as it was trained; its correction (its
        // output minus the warp it was given) is added at the state's resolution.
        cv::Mat small = state_;
        if (big != n) {
            cv::resize(state_, small, cv::Size(n, n), 0, 0, cv::INTER_AREA);
            small.setTo(cv::Scalar::all(0), ~disc_n_);
        }
        cv::Mat base = warp_in_disc(small, f_n);
        if (!compensation_n.empty()) base += compensation_n;
        cv::Mat correction = network_->step_network(small, f_n, compensation_n) - base, up = correction;
        if (big != n) cv::resize(correction, up, cv::Size(big, big), 0, 0, cv::INTER_LINEAR);
        moved += up * (network_trust_ * (k == 1 ? flow_.correction_gain : 1.0));
    }
    cv::min(cv::max(moved, 0.0), 1.0, state_);
    state_.setTo(cv::Scalar::all(0), ~disc_big_);
    corrections_ = state_ - lagrangian;  // what clamping kept of them
    return state_;
}

namespace {

// The sun's weight from the clouds a rollout moved over it (CloudRollout::opacity), as the timeline
// takes it (motion/sun_patch.h opacity_sun_weight; start_look: the look around the start's sun), in
// [0, 1]; nullopt without a sun or a background (no opacity).
std::optional<double> rollout_sun_weight(const CloudRollout& rollout, const std::optional<Vec3d>& sun,
                                         double start_look, double input_sun_share) {
    if (!sun || rollout.opacity().empty() || rollout.start_opacity().empty()) return std::nullopt;
    return opacity_sun_weight(sun_transmittance_of_opacity(rollout.opacity(), *sun),
                              sun_transmittance_of_opacity(rollout.start_opacity(), *sun), start_look, input_sun_share,
                              sun_travel_fraction(rollout.sun_travel_px(), rollout.state().rows),
                              cloud_share(rollout.start_opacity()));
}

// How much of the clear sun a sky shows at its sun (sun_patch_share of the sun remove_sun would cut
// there: the sky's own, or where its brightest pixels put it); 0 without one.
double shown_sun_share(const SkyImage& sky, const std::optional<Vec3d>& sun) {
    if (!sun) return 0.0;
    SkyImage copy = sky;
    if (!copy.sun_direction) copy.sun_direction = sun->cast<float>();
    return sun_patch_share(remove_sun(&copy), sky.resolution, *sun);
}

cv::Mat at_most_256(const cv::Mat& map) {
    if (map.empty() || map.rows <= 256) return map.clone();
    cv::Mat small;
    cv::resize(map, small, cv::Size(256, 256), 0, 0, cv::INTER_AREA);
    return small;
}

}  // namespace

void AdvectResidualNetwork::rollout_network_form(const cv::Mat& start, const CloudFlow& flow, int steps,
                                                 const std::function<void(int, const cv::Mat&)>& on_step,
                                                 const cv::Mat& background) {
    CloudRollout rollout(this, start, flow, background);
    for (int k = 1; k <= steps; ++k) on_step(k, rollout.advance());
}

void AdvectResidualNetwork::rollout(const SkyImage& given, const CloudFlow& flow, int steps,
                                    const std::function<void(int, const SkyImage&)>& on_step, cv::Mat background) {
    validate_sky(given, given.source.empty() ? std::string("input sky") : given.source);
    const double scale = model_scale(given);
    const SkyImage sky = scaled_sky(given, scale);
    cv::Mat state = to_network_form(sky, info_.form);
    const cv::Mat sun = fill_saturated_pixels(&state);
    const bool has_sun = cv::countNonZero(sun) > 0;
    // A sky that does not carry its sun (no time and place) has it estimated from its brightest
    // pixels, for the clear background the clouds move over: without one the whole sky moved with
    // the wind, its gradient, horizon and the sun's glare included.
    std::optional<Vec3d> at;
    if (sky.sun_direction) at = sky.sun_direction->cast<double>();
    else at = sun_from_brightest_pixels(sky);
    if (background.empty() && at)
        background = this->background(at->cast<float>(), sky.resolution, clear_sky_turbidity(sky, *at));
    const double share = has_sun ? shown_sun_share(sky, at) : 0.0;
    // Around the sun, recorded or estimated, the clouds' look says nothing (glare, aureole): a
    // sunset HDRI without metadata had its glow judged cloud and dragged across the sky.
    CloudRollout rollout(this, state, flow, background, at ? sun_unseen_mask(sky.resolution, *at) : cv::Mat(), at,
                         share >= 0.5, filled_mask(sky));
    const double start_look = has_sun && at ? estimate_sun_transmittance(sky, *at) : 1.0;
    for (int k = 1; k <= steps; ++k) {
        SkyImage next = from_network_form(rollout.advance(), sky, info_.form);
        next.time_seconds = sky.time_seconds + k * info_.dt;
        // The sun estimated for a sky that did not record one is recorded in its steps: a prediction
        // continued from a step, whose sun a cloud may dim, looked for it again and lost it.
        if (!next.sun_direction && at) next.sun_direction = at->cast<float>();
        // What was cut out comes back dimmed by the cloud the rollout moved over the sun (as the
        // step model does).
        if (has_sun) {
            const double t = relative_sun_transmittance(next, sky, at);
            restore_pixels(&next, sky, sun,
                           std::min(t, rollout_sun_weight(rollout, at, start_look, share).value_or(1.0)));
        }
        on_step(k, scale == 1.0 ? next : scaled_sky(next, 1.0 / scale));
    }
}

NetworkFormPair network_form_pair(const SkyImage& previous, const SkyImage& current, const NetworkFormParams& form) {
    // A previous frame of another resolution is resampled to the sky's: only its motion is read.
    const SkyImage resampled = previous.resolution != current.resolution ? resampled_sky(previous, current.resolution)
                                                                         : SkyImage();
    const int w = std::min(256, current.resolution);
    NetworkFormPair pair{to_network_form(resampled.resolution > 0 ? resampled : previous, form, w),
                         to_network_form(current, form, w), cv::Mat()};
    cv::Mat untrusted = fill_saturated_pixels(&pair.previous) | fill_saturated_pixels(&pair.current);
    // Nor where an import filled either frame: a filled camera arm or band does not move.
    for (const SkyImage* sky : {&previous, &current})
        if (cv::Mat filled = filled_mask(*sky); !filled.empty()) {
            cv::resize(filled, filled, cv::Size(w, w), 0, 0, cv::INTER_AREA);
            untrusted |= filled > 0;
        }
    pair.seen = sky_disc_mask(w) & ~untrusted;
    return pair;
}

MeasuredMotion network_form_flow(const SkyImage& previous, const SkyImage& current, const NetworkFormParams& form,
                                 int n) {
    const NetworkFormPair pair = network_form_pair(previous, current, form);
    return measured_motion(pair.previous, pair.current, pair.seen).at_resolution(n);
}

double AdvectResidualNetwork::correction_gain(const cv::Mat& previous, const cv::Mat& current, const cv::Mat& seen,
                                              const cv::Mat& flow) {
    if (!has_network()) return 1.0;
    const int n = info_.resolution;
    cv::Mat p = previous, c = current, s = seen;
    if (previous.rows != n) {
        cv::resize(previous, p, cv::Size(n, n), 0, 0, cv::INTER_AREA);
        cv::resize(current, c, cv::Size(n, n), 0, 0, cv::INTER_AREA);
        cv::resize(seen, s, cv::Size(n, n), 0, 0, cv::INTER_AREA);
        s = s == 255;  // seen wholly
    }
    s = cv::Mat(s & sky_disc_mask(n));  // not &=: s may be the caller's `seen`
    const cv::Mat f = flow_at_resolution(flow, n), warped = warp_in_disc(p, f);
    const cv::Mat correction = step_network(p, f) - warped, missed = c - warped;
    double along = 0, norm = 0;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            if (s.at<uchar>(y, x)) {
                const cv::Vec3f a = correction.at<cv::Vec3f>(y, x), b = missed.at<cv::Vec3f>(y, x);
                along += a.dot(b), norm += a.dot(a);
            }
    return norm > 0 ? std::clamp(along / norm, 0.0, 1.0) : 1.0;
}

CloudFlow AdvectResidualNetwork::motion_flow(const SkyImage& sky, const CloudMotion& motion, double dt, int n) {
    if (motion.previous) {
        double gap = motion.previous_dt > 0 ? motion.previous_dt : dt;
        const double scale = model_scale(sky);  // both frames alike
        const SkyImage previous = scaled_sky(*motion.previous, scale), current = scaled_sky(sky, scale);
        const NetworkFormPair pair = network_form_pair(previous, current, info_.form);
        const MeasuredMotion measured = measured_motion(pair.previous, pair.current, pair.seen);
        const double gain = correction_gain(pair.previous, pair.current, pair.seen,
                                            measured.confirmed.empty() ? measured.smoothed : measured.confirmed);
        MeasuredMotion m = measured.at_resolution(n);
        // New buffers (not *=): at_resolution hands back `measured`'s own at this size.
        m.smoothed = cv::Mat(m.smoothed * (dt / gap));
        if (!m.confirmed.empty()) m.confirmed = cv::Mat(m.confirmed * (dt / gap));
        CloudFlow flow = CloudFlow::from_measured(m, dt, to_double(sky.sun_direction));
        flow.correction_gain = gain;
        return flow;
    }
    return CloudFlow::from_wind(wind_flow(n, motion.wind ? *motion.wind : Wind{}, dt));
}

double previous_frame_gap(const SkyImage& sky, const SkyImage& previous, double given, const std::string& sky_name,
                          const std::string& previous_name) {
    if (!(given >= 0) || !std::isfinite(given)) throw Error("--prev-dt: must be a positive number of seconds");
    if (given > 0) return given;
    // The sequence's clock (dynsky:time, read from both files; a sequence's first frame is at 0),
    // else the UTC times their imports recorded: two imported photographs both say 0, and a 60 s
    // pair taken as one 30 s step moved the clouds twice as fast. Neither: one medium step.
    double gap = 0;
    const char* clock = "clock (dynsky:time)";
    if (sky.has_clock && previous.has_clock && (sky.time_seconds != 0 || previous.time_seconds != 0)) {
        gap = sky.time_seconds - previous.time_seconds;
    } else {
        const auto a = sky_recorded_utc_seconds(previous), b = sky_recorded_utc_seconds(sky);
        if (!a || !b) return 0;
        gap = *b - *a, clock = "recorded time";
    }
    if (gap <= 0 || gap > 3600) {
        char text[160];
        std::snprintf(text, sizeof text, "%.0f s after", -gap);
        if (std::abs(gap) < 0.5) std::snprintf(text, sizeof text, "at the same time as");
        if (gap > 0) std::snprintf(text, sizeof text, "%.0f s (over an hour) before", gap);
        throw Error(previous_name + ": the previous frame's " + clock + " puts it " + text + " " + sky_name +
                    ": not a previous frame of the same sky (give --prev-dt to override)");
    }
    return gap;
}

std::string unknown_previous_gap_note(const std::string& sky_name, const std::string& previous_name) {
    return "dynsky: note: neither " + sky_name + " nor the previous frame " + previous_name +
           " says when it was taken (no clock, no recorded time): taken one medium step (Delta t) apart; give "
           "--prev-dt SECONDS if they are not\n";
}

std::string long_previous_gap_warning(double gap_seconds, const std::string& sky_name,
                                      const std::string& previous_name) {
    if (!(gap_seconds > kLongPreviousGapSeconds)) return "";
    char gap[32];
    std::snprintf(gap, sizeof gap, "%.0f s", gap_seconds);
    return "dynsky: warning: the previous frame " + previous_name + " is " + gap + " before " + sky_name +
           ": over more than " + std::to_string(int(kLongPreviousGapSeconds)) +
           " s clouds change shape and the motion measured between the two comes out slow (on the ARM day about "
           "half of it at 120 s, none at 300 s): give a frame closer to it, or the wind (--wind-from, "
           "--wind-speed)\n";
}

double model_scale(const SkyImage& sky) {
    if (sky.sun_direction) return 1.0;
    if (const RadianceScale measured = measure_radiance_scale(sky); measured.measured)
        return measured.apply ? 1.0 / measured.factor : 1.0;
    std::vector<float> values;
    for (int j = 0; j < sky.resolution; ++j)
        for (int i = 0; i < sky.resolution; ++i)
            if (sky.in_disc(i, j)) {
                const double l = luminance(sky.pixel(i, j));
                if (std::isfinite(l) && l > 0) values.push_back(float(l));
            }
    if (values.empty()) return 1.0;
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    const double median_lum = values[values.size() / 2];
    return std::clamp(kUnknownScaleMedian / median_lum, 1e-6, 1e6);
}

SkyImage scaled_sky(const SkyImage& sky, double factor) {
    SkyImage out = sky;
    if (factor != 1.0)
        for (float& v : out.rgb) v = float(v * factor);
    return out;
}

cv::Mat AdvectResidualNetwork::background(const Vec3& sun, int n, double turbidity) const {
    return background_at(sun, n, info_.form, turbidity);
}

AdvectResidualStepModel::AdvectResidualStepModel(AdvectResidualNetwork network, CloudMotion motion)
    : network_(std::move(network)), motion_(std::move(motion)) {}

std::string AdvectResidualStepModel::name() const {
    return network_.has_network() ? "network:" + network_.info().folder : std::string("advect");
}

SkyImage AdvectResidualStepModel::step(const std::vector<std::shared_ptr<const SkyImage>>& history, double dt) {
    const int k = int(history.size());  // this makes step k (S_k)
    const bool fresh = !rollout_ || flow_dt_ != dt || rollout_->steps() != k - 1 ||
                       rollout_input_ != history.front().get();
    const int given_resolution = history.front()->resolution;
    if (fresh) {
        // A sky smaller than the network works at its resolution (upsampled), its steps come back
        // at its own (area-averaged).
        const int n = network_.info().resolution;
        front_ = given_resolution < n ? resampled_sky(*history.front(), n) : SkyImage();
        // A sky of unknown scale works at the networks' (model_scale); its steps come back at its own.
        const SkyImage& front = front_.resolution > 0 ? front_ : *history.front();
        scale_ = model_scale(front);
        scaled_input_ = scale_ == 1.0 ? SkyImage() : scaled_sky(front, scale_);
    }
    const SkyImage& front = front_.resolution > 0 ? front_ : *history.front();
    const SkyImage& input = scale_ == 1.0 ? front : scaled_input_;
    if (fresh) {
        // One rollout from the input S_0 (its motion measured once), kept across the timeline's
        // calls so the clouds keep their detail (motion/advect_residual.h CloudRollout).
        flow_ = network_.motion_flow(front, motion_, dt, input.resolution);  // scales both frames
        flow_dt_ = dt;
        cv::Mat start = to_network_form(input, network_.info().form);
        sun_mask_ = fill_saturated_pixels(&start);
        input_sun_share_.reset(), input_sun_look_.reset();
        // A sky without its sun has it estimated from its brightest pixels (as rollout() does).
        estimated_sun_.reset();
        if (!input.sun_direction)
            if (const auto d = sun_from_brightest_pixels(input)) estimated_sun_ = d->cast<float>();
        // The timeline cut the input's sun out (motion/sun_patch.h remove_sun) where the input has it;
        // around it the clouds' look says nothing (sun_unseen_mask).
        // (Or where its brightest pixels put it: a sunset HDRI without metadata had its glow
        // judged cloud and dragged across the sky.)
        const std::optional<Vec3> unseen_sun = input.sun_direction ? input.sun_direction : estimated_sun_;
        const cv::Mat unseen = unseen_sun ? sun_unseen_mask(input.resolution, unseen_sun->cast<double>()) : cv::Mat();
        rollout_ = std::make_unique<CloudRollout>(&network_, start, flow_, cv::Mat(), unseen);
        rollout_->set_unseen_opacity(sun_cover_);
        rollout_->set_filled(filled_mask(input));
        background_ = cv::Mat();  // the new rollout needs its background (and opacity)
        rollout_input_ = history.front().get();
        turbidity_.reset();
        for (int j = 1; j < k; ++j) rollout_->advance();  // catch up (not the timeline's order)
    }
    const std::optional<Vec3> sun = sun_ ? sun_ : input.sun_direction ? input.sun_direction : estimated_sun_;
    if (sun && (background_.rows != input.resolution || (*sun - background_sun_).norm() > 0.0035)) {
        if (!turbidity_) turbidity_ = clear_sky_turbidity(input, sun->cast<double>());
        background_ = network_.background(*sun, input.resolution, *turbidity_);
        background_sun_ = *sun;
        if (!input_sun_share_) input_sun_share_ = shown_sun_share(input, sun->cast<double>());
        rollout_->set_sun_seen_whole(told_sun_share_ ? *told_sun_share_ >= 0.5
                                                     : cv::countNonZero(sun_mask_) > 0 && *input_sun_share_ >= 0.5);
        rollout_->set_background(background_, sun->cast<double>());
    }
    SkyImage next = from_network_form(rollout_->advance(), input, network_.info().form);
    // The rollout's flows are by destination (wind_flow); last_step_flow is by source.
    last_flow_ = flow_by_source(flow_at_resolution(flow_.at(rollout_->steps()), given_resolution));
    std::optional<Vec3d> at;
    if (sun) at = sun->cast<double>();
    last_opacity_ = at_most_256(rollout_->opacity());
    input_opacity_ = at_most_256(rollout_->start_opacity());
    if (cv::countNonZero(sun_mask_) > 0) {
        // Dimmed by the cloud the sky shows at the sun or, when more, by the clouds moved there.
        const double t = relative_sun_transmittance(next, input, at);
        if (!input_sun_share_) input_sun_share_ = shown_sun_share(input, at);
        if (!input_sun_look_) input_sun_look_ = at ? estimate_sun_transmittance(input, *at) : 1.0;
        restore_pixels(&next, input, sun_mask_,
                       std::min(t,
                                rollout_sun_weight(*rollout_, at, *input_sun_look_, *input_sun_share_).value_or(1.0)));
    }
    next.time_seconds = history.back()->time_seconds + dt;
    if (scale_ != 1.0) next = scaled_sky(next, 1.0 / scale_);
    return next.resolution == given_resolution ? next : resampled_sky(next, given_resolution);
}

}  // namespace dynsky
