#include "motion/advect_residual.h"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "motion/advection.h"
#include "motion/onnx_net.h"
#include "motion/sun_patch.h"
#include "sky/fisheye.h"
#include "util/error.h"
#include "util/json_file.h"

namespace dynsky {

namespace fs = std::filesystem;

std::string cloud_model_kind(const std::string& folder) {
    const std::string path = (fs::path(folder) / "model.json").string();
    if (!fs::is_directory(folder)) throw_file_error(folder, "model folder not found");
    if (!fs::exists(path)) throw_file_error(path, "model description not found (is this a model folder?)");
    nlohmann::json j = read_json(path);
    if (!j.is_object()) throw_file_error(path, "not a model description (expected a JSON object)");
    if (j.contains("format") && j["format"] != "dynsky-cloud-model")
        throw_file_error(path, "format is not dynsky-cloud-model");
    return j.value("kind", std::string("flownet-cloudnet"));
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
    const std::string kind = cloud_model_kind(folder);
    const std::string json_path = (fs::path(folder) / "model.json").string();
    if (kind != "advect-residual")
        throw_file_error(json_path, "kind '" + kind + "' is not an advect-residual model");
    AdvectResidualNetwork m;
    AdvectResidualInfo& info = m.info_;
    info.folder = folder;
    try {
        nlohmann::json j = read_json(json_path);
        const int version = j.value("version", 0);
        if (version != 2) throw_file_error(json_path, "version " + std::to_string(version) + " (this dynsky reads version 2)");
        info.name = j.value("name", fs::path(folder).filename().string());
        info.resolution = j.at("resolution").get<int>();
        info.import_resolution = j.value("import_resolution", 4 * info.resolution);
        info.dt = j.at("dt_s").get<double>();
        info.flow_scale = j.value("flow_scale", 0.08);
        info.compensated = j.value("base", std::string("warp")) == "compensated";
        info.form.unit_map.scale = j.value("unit_scale", info.form.unit_map.scale);
        info.form.unit_map.max_radiance = j.value("unit_max", info.form.unit_map.max_radiance);
        info.form.cloud_rule.rule = parse_cloud_rule(j.value("cloud_rule", std::string("rb")));
        info.form.cloud_rule.threshold = j.value("cloud_threshold", info.form.cloud_rule.threshold);
    } catch (const nlohmann::json::exception& e) {
        throw_file_error(json_path, std::string("not a valid model description: ") + e.what());
    }
    if (info.resolution < 8 || info.resolution > 4096)
        throw_file_error(json_path, "resolution " + std::to_string(info.resolution) + " is not in 8..4096");
    if (!(info.dt > 0)) throw_file_error(json_path, "dt_s must be a positive number of seconds");
    if (!(info.flow_scale > 0)) throw_file_error(json_path, "flow_scale must be positive");
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
    cv::Mat out = from_blob(run_net(m.net_, to_blob({cv::Mat(n, n, CV_32FC(8), cv::Scalar::all(0))}), onnx), onnx);
    if (out.rows != n || out.cols != n || out.channels() != 3)
        throw_file_error(onnx, "returns " + shape_text(out) + ", expected " + std::to_string(n) + " x " + std::to_string(n) +
                                   " x 3 (model.json's resolution)");
    return m;
}

cv::Mat AdvectResidualNetwork::network_input(const cv::Mat& image, const cv::Mat& flow,
                                             const cv::Mat& compensation) const {
    const int n = info_.resolution;
    if (image.rows != n || image.cols != n || image.type() != CV_32FC3)
        throw Error("advect-residual: the image must be " + std::to_string(n) + " x " + std::to_string(n) +
                    " x 3 float, got " + shape_text(image));
    if (flow.rows != n || flow.cols != n || flow.type() != CV_32FC2)
        throw Error("advect-residual: the flow must be " + std::to_string(n) + " x " + std::to_string(n) + " x 2 float");
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

// The clear background at n, computed at most at 256 px and upsampled (it is smooth).
cv::Mat background_at(const Vec3& sun, int n, const NetworkFormParams& form) {
    const int w = std::min(n, 256);
    cv::Mat b = clear_background(sun.cast<double>(), w, form);
    if (w == n) return b;
    cv::Mat up;
    cv::resize(extend_past_rim(b), up, cv::Size(n, n), 0, 0, cv::INTER_LINEAR);
    up.setTo(cv::Scalar::all(0), ~sky_disc_mask(n));
    return up;
}

cv::Mat resize_flow(const cv::Mat& flow, int n) {
    if (flow.rows == n) return flow;
    cv::Mat out;
    cv::resize(flow, out, cv::Size(n, n), 0, 0, n < flow.rows ? cv::INTER_AREA : cv::INTER_LINEAR);
    return out * (double(n) / flow.rows);
}

}  // namespace

void AdvectResidualNetwork::rollout_network_form(const cv::Mat& start, const cv::Mat& flow, int steps,
                                                 const std::function<void(int, const cv::Mat&)>& on_step,
                                                 const cv::Mat& background) {
    const int n = info_.resolution, big = start.rows;
    if (flow.rows != big || flow.cols != big || flow.type() != CV_32FC2)
        throw Error("advect-residual: the flow must be CV_32FC2 at the state's resolution " + std::to_string(big));
    if (big < n) throw Error("advect-residual: the state is smaller than the network's " + std::to_string(n) + " px");
    const cv::Mat disc_big = sky_disc_mask(big), disc_n = sky_disc_mask(n);
    const cv::Mat flow_n = resize_flow(flow, n);
    // B - warp(B) is the same every step (the flow is fixed): computed once, at both sizes.
    cv::Mat compensation, compensation_n;
    if (!background.empty()) {
        compensation = background - warp_in_disc(background, flow);
        cv::Mat background_n = background;
        if (big != n) {
            cv::resize(background, background_n, cv::Size(n, n), 0, 0, cv::INTER_AREA);
            background_n.setTo(cv::Scalar::all(0), ~disc_n);
        }
        compensation_n = background_n - warp_in_disc(background_n, flow_n);
    }
    cv::Mat state = start.clone();
    for (int k = 1; k <= steps; ++k) {
        if (big == n) {
            state = step_network(state, flow_n, compensation_n);
        } else {
            // The state moves at its own resolution; the network's correction is added from N.
            cv::Mat moved = warp_in_disc(state, flow);
            if (!compensation.empty()) moved += compensation;
            if (has_network()) {
                cv::Mat small;
                cv::resize(state, small, cv::Size(n, n), 0, 0, cv::INTER_AREA);
                small.setTo(cv::Scalar::all(0), ~disc_n);
                cv::Mat base = warp_in_disc(small, flow_n);
                if (!compensation_n.empty()) base += compensation_n;
                cv::Mat correction = step_network(small, flow_n, compensation_n) - base, up;
                cv::resize(correction, up, cv::Size(big, big), 0, 0, cv::INTER_LINEAR);
                moved += up;
            }
            cv::min(cv::max(moved, 0.0), 1.0, state);
            state.setTo(cv::Scalar::all(0), ~disc_big);
        }
        on_step(k, state);
    }
}

void AdvectResidualNetwork::rollout(const SkyImage& sky, const cv::Mat& flow, int steps,
                                    const std::function<void(int, const SkyImage&)>& on_step, cv::Mat background) {
    validate_sky(sky, sky.source.empty() ? std::string("input sky") : sky.source);
    cv::Mat state = to_network_form(sky, info_.form);
    const cv::Mat sun = fill_saturated_pixels(&state);
    const bool has_sun = cv::countNonZero(sun) > 0;
    if (background.empty() && sky.sun_direction) background = this->background(*sky.sun_direction, sky.resolution);
    rollout_network_form(state, flow, steps, [&](int k, const cv::Mat& s) {
        SkyImage next = from_network_form(s, sky, info_.form);
        next.time_seconds = sky.time_seconds + k * info_.dt;
        if (has_sun) restore_pixels(&next, sky, sun);
        on_step(k, next);
    }, background);
}

cv::Mat network_form_flow(const SkyImage& previous, const SkyImage& current, const NetworkFormParams& form, int n) {
    if (previous.resolution != current.resolution)
        throw Error("previous frame: its resolution (" + std::to_string(previous.resolution) +
                    ") differs from the sky's (" + std::to_string(current.resolution) + ")");
    const int w = std::min(256, current.resolution);
    cv::Mat a = to_network_form(previous, form, w), b = to_network_form(current, form, w);
    fill_saturated_pixels(&a);
    fill_saturated_pixels(&b);
    return resize_flow(smooth_motion(farneback_flow(a, b)), n);
}

cv::Mat AdvectResidualNetwork::motion_flow(const SkyImage& sky, const CloudMotion& motion, double dt, int n) const {
    if (motion.previous) {
        double gap = motion.previous_dt > 0 ? motion.previous_dt : dt;
        return network_form_flow(*motion.previous, sky, info_.form, n) * (dt / gap);
    }
    return wind_flow(n, motion.wind ? *motion.wind : Wind{}, dt);
}

cv::Mat AdvectResidualNetwork::background(const Vec3& sun, int n) const { return background_at(sun, n, info_.form); }

AdvectResidualStepModel::AdvectResidualStepModel(AdvectResidualNetwork network, CloudMotion motion)
    : network_(std::move(network)), motion_(std::move(motion)) {}

std::string AdvectResidualStepModel::name() const {
    return network_.has_network() ? "network:" + network_.info().folder : std::string("advect");
}

SkyImage AdvectResidualStepModel::step(const std::vector<std::shared_ptr<const SkyImage>>& history, double dt) {
    const SkyImage& last = *history.back();
    if (flow_.empty() || flow_dt_ != dt || flow_.rows != last.resolution) {
        // Fixed from the first step on (constant velocity), measured against the input S_0.
        flow_ = network_.motion_flow(*history.front(), motion_, dt, last.resolution);
        flow_dt_ = dt;
    }
    if (last.sun_direction &&
        (background_.rows != last.resolution || (*last.sun_direction - background_sun_).norm() > 0.0035)) {
        background_ = network_.background(*last.sun_direction, last.resolution);
        background_sun_ = *last.sun_direction;
    }
    SkyImage next;
    network_.rollout(last, flow_, 1, [&](int, const SkyImage& s) { next = s; }, last.sun_direction ? background_ : cv::Mat());
    next.time_seconds = last.time_seconds + dt;
    return next;
}

}  // namespace dynsky
