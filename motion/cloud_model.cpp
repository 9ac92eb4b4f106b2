#include "motion/cloud_model.h"

#include "motion/advect_residual.h"
#include "motion/onnx_net.h"

#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/photo.hpp>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "sky/fisheye.h"
#include "sky/hdr_recovery.h"
#include "motion/advection.h"
#include "motion/metrics.h"
#include "motion/sun_patch.h"
#include "util/atomic_file.h"
#include "util/error.h"

namespace dynsky {

namespace fs = std::filesystem;

namespace {

void check_input(const cv::Mat& m, int n, const char* what) {
    if (m.empty() || m.rows != n || m.cols != n || m.channels() != 3 || m.depth() != CV_32F)
        throw Error(std::string("cloud model: the ") + what + " must be " + std::to_string(n) + " x " +
                    std::to_string(n) + " x 3 float (the model's resolution), got " + shape_text(m));
}

}  // namespace

CloudModel CloudModel::load(const std::string& folder) {
    if (!fs::is_directory(folder)) throw_file_error(folder, "model folder not found");
    const std::string json_path = (fs::path(folder) / "model.json").string();
    if (!fs::exists(json_path)) throw_file_error(json_path, "model description not found (is this a model folder?)");
    const nlohmann::json j = read_model_description(folder);  // format checked, a whole version
    CloudModel model;
    CloudModelInfo& info = model.info_;
    info.folder = folder;
    try {
        // This reader knows version 1 only.
        if (j.value("kind", std::string("flownet-cloudnet")) != "flownet-cloudnet")
            throw Error("kind '" + j.value("kind", std::string()) +
                        "' is not a model kind this dynsky knows (advect-residual, flownet-cloudnet)");
        if (j.at("version").get<int>() != 1)
            throw Error("version " + j.at("version").dump() + " (this dynsky reads version 1)");
        info.name = j.value("name", fs::path(folder).filename().string());
        info.resolution = j.at("resolution").get<int>();
        info.dt = j.at("dt_s").get<double>();
        info.flow_scale = j.at("flow_scale").get<double>();
        info.flow_widths = j.value("flow_widths", std::vector<int>{});
        info.cloud_widths = j.value("cloud_widths", std::vector<int>{});
        info.form.unit_map.scale = j.value("unit_scale", info.form.unit_map.scale);
        info.form.unit_map.max_radiance = j.value("unit_max", info.form.unit_map.max_radiance);
        info.form.cloud_rule.rule = parse_cloud_rule(j.value("cloud_rule", std::string("rb")));
        info.form.cloud_rule.threshold = j.value("cloud_threshold", info.form.cloud_rule.threshold);
    } catch (const nlohmann::json::exception& e) {
        throw_file_error(json_path, std::string("not a valid model description: ") + e.what());
    } catch (const Error& e) {
        throw_file_error(json_path, e.what());
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

    const std::string flow_path = (fs::path(folder) / "flownet.onnx").string();
    const std::string cloud_path = (fs::path(folder) / "cloudnet.onnx").string();
    model.flownet_ = read_onnx(flow_path);
    model.cloudnet_ = read_onnx(cloud_path);
    const int n = info.resolution;
    model.disc_ = sky_disc_mask(n);

    // One run on zeros: a network that does not take (or give) N x N images fails here, not later,
    // with our message (OpenCV's own log lines about the failure are silenced meanwhile).
    QuietOpenCv quiet;
    cv::Mat zero(n, n, CV_32FC3, cv::Scalar::all(0));
    cv::Mat f = probe_net(model.flownet_, to_blob({zero}), flow_path, n);
    if (f.rows != n || f.cols != n || f.channels() != 3)
        throw_file_error(flow_path, "returns " + shape_text(f) + ", expected " + std::to_string(n) + " x " +
                                        std::to_string(n) + " x 3 (model.json's resolution)");
    cv::Mat c = probe_net(model.cloudnet_, to_blob({zero, f}), cloud_path, n);
    if (c.rows != n || c.cols != n || c.channels() != 3)
        throw_file_error(cloud_path, "returns " + shape_text(c) + ", expected " + std::to_string(n) + " x " +
                                         std::to_string(n) + " x 3 (model.json's resolution)");
    return model;
}

cv::Mat CloudModel::run_flownet(const cv::Mat& image) {
    check_input(image, info_.resolution, "FlowNet input image");
    return from_blob(run_net(flownet_, to_blob({image}), "FlowNet"), "FlowNet");
}

cv::Mat CloudModel::run_cloudnet(const cv::Mat& image, const cv::Mat& flow) {
    check_input(image, info_.resolution, "CloudNet input image");
    check_input(flow, info_.resolution, "CloudNet input flow");
    return from_blob(run_net(cloudnet_, to_blob({image, flow}), "CloudNet"), "CloudNet");
}

NetworkStep CloudModel::step_network(const cv::Mat& image) {
    NetworkStep s;
    s.flow = run_flownet(image);
    cv::Mat next = run_cloudnet(image, s.flow);
    cv::min(cv::max(next, 0.0), 1.0, next);
    next.setTo(cv::Scalar::all(0), ~disc_);
    s.next = next;
    return s;
}

SkyImage CloudModel::step(const SkyImage& sky) {
    SkyImage out;
    rollout(sky, 1, [&](int, const SkyImage& s) { out = s; });
    return out;
}

void CloudModel::rollout(const SkyImage& sky, int steps, const std::function<void(int, const SkyImage&)>& on_step) {
    validate_sky(sky, sky.source.empty() ? std::string("input sky") : sky.source);
    if (steps < 0) throw Error("cloud model: the number of steps must be >= 0");
    const int n = info_.resolution, big = sky.resolution;
    cv::Mat state = to_network_form(sky, info_.form);
    const cv::Mat disc_big = sky_disc_mask(big);
    // The sun (and any pixel the map clips) is not the networks' business: it is filled from its
    // surroundings before the first step, so it is neither moved nor smeared like a cloud, and the
    // input's radiance is put back into every output, dimmed by the cloud moved over the sun
    // (motion/sun_patch.h relative_sun_transmittance).
    const cv::Mat sun = fill_saturated_pixels(&state);
    const bool has_sun = cv::countNonZero(sun) > 0;
    for (int k = 1; k <= steps; ++k) {
        cv::Mat small = state;
        if (big != n) {
            cv::resize(state, small, cv::Size(n, n), 0, 0, cv::INTER_AREA);
            small.setTo(cv::Scalar::all(0), ~disc_);
        }
        NetworkStep s = step_network(small);
        if (big == n) {
            state = s.next;
        } else {
            // Carry the change back: the coarse prediction, plus the input's finer detail (what the
            // coarse image does not hold) moved the way the model moved the coarse image. That
            // motion is measured (Farneback between the model's input and output): it is smooth
            // and covers clear sky too, unlike FlowNet's cloud-masked flow, whose edges tear detail.
            cv::Mat up_small, up_next, up_flow;
            cv::resize(small, up_small, cv::Size(big, big), 0, 0, cv::INTER_LINEAR);
            cv::resize(s.next, up_next, cv::Size(big, big), 0, 0, cv::INTER_LINEAR);
            cv::resize(farneback_flow(small, s.next), up_flow, cv::Size(big, big), 0, 0, cv::INTER_LINEAR);
            up_flow *= double(big) / n;
            cv::Mat detail = advect_by_flow(state - up_small, up_flow, 1.0);
            state = up_next + detail;
            cv::min(cv::max(state, 0.0), 1.0, state);
            state.setTo(cv::Scalar::all(0), ~disc_big);
        }
        SkyImage next = from_network_form(state, sky, info_.form);
        next.time_seconds = sky.time_seconds + k * info_.dt;
        if (has_sun) restore_pixels(&next, sky, sun, relative_sun_transmittance(next, sky));
        on_step(k, next);
    }
}

}  // namespace dynsky
