#include "sky/cloud_model.h"

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
#include "sky/photo_import.h"
#include "sky/sky_metrics.h"
#include "util/atomic_file.h"
#include "util/error.h"

namespace dynsky {

namespace fs = std::filesystem;

namespace {

std::string shape_text(const cv::Mat& m) {
    if (m.empty()) return "an empty image";
    return std::to_string(m.cols) + " x " + std::to_string(m.rows) + " x " + std::to_string(m.channels()) +
           (m.depth() == CV_32F ? " float" : " non-float");
}

void check_input(const cv::Mat& m, int n, const char* what) {
    if (m.empty() || m.rows != n || m.cols != n || m.channels() != 3 || m.depth() != CV_32F)
        throw Error(std::string("cloud model: the ") + what + " must be " + std::to_string(n) + " x " +
                    std::to_string(n) + " x 3 float (the model's resolution), got " + shape_text(m));
}

// N x N x C planes -> a 1 x C x N x N blob (NCHW), as the ONNX graphs expect.
cv::Mat to_blob(const std::vector<cv::Mat>& images) {
    int channels = 0;
    for (const cv::Mat& m : images) channels += m.channels();
    const int n = images[0].rows, w = images[0].cols;
    int dims[4] = {1, channels, n, w};
    cv::Mat blob(4, dims, CV_32F);
    int c = 0;
    for (const cv::Mat& m : images) {
        std::vector<cv::Mat> planes;
        cv::split(m, planes);
        for (const cv::Mat& p : planes) {
            cv::Mat dst(n, w, CV_32F, blob.ptr<float>(0, c++));
            p.copyTo(dst);
        }
    }
    return blob;
}

cv::Mat from_blob(const cv::Mat& blob, const std::string& what) {
    if (blob.dims != 4 || blob.size[0] != 1)
        throw Error(what + ": the network returned a " + std::to_string(blob.dims) + "-d tensor, expected 1 x C x N x N");
    const int c = blob.size[1], n = blob.size[2], w = blob.size[3];
    std::vector<cv::Mat> planes;
    for (int k = 0; k < c; ++k) planes.push_back(cv::Mat(n, w, CV_32F, const_cast<float*>(blob.ptr<float>(0, k))).clone());
    cv::Mat out;
    cv::merge(planes, out);
    return out;
}

// OpenCV logs its own lines about a bad model before throwing; we report the problem ourselves.
struct QuietOpenCv {
    cv::utils::logging::LogLevel old = cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
    ~QuietOpenCv() { cv::utils::logging::setLogLevel(old); }
};

cv::dnn::Net read_onnx(const std::string& path) {
    QuietOpenCv quiet;
    if (!fs::exists(path)) throw_file_error(path, "model file not found");
    if (fs::file_size(path) == 0) throw_file_error(path, "model file is empty");
    try {
        cv::dnn::Net net = cv::dnn::readNetFromONNX(path);
        if (net.empty()) throw_file_error(path, "OpenCV could not build a network from this ONNX file");
        net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
        net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
        return net;
    } catch (const cv::Exception& e) {
        throw_file_error(path, "not an ONNX model OpenCV can load (" + std::string(e.err) + ")");
    }
}

cv::Mat run_net(cv::dnn::Net& net, const cv::Mat& blob, const std::string& what) {
    try {
        net.setInput(blob);
        return net.forward().clone();
    } catch (const cv::Exception& e) {
        throw Error(what + ": the network failed to run on a " + std::to_string(blob.size[1]) + " x " +
                    std::to_string(blob.size[2]) + " x " + std::to_string(blob.size[3]) + " input (" + e.err + ")");
    }
}

// The [0, 1] form cannot hold the sun: pixels where the forward map clips any channel (the sun's
// disc and the brightest aureole) are taken from the input sky instead.
cv::Mat saturated_pixels(const cv::Mat& unit) {
    std::vector<cv::Mat> ch;
    cv::split(unit, ch);
    return (ch[0] >= 0.999f) | (ch[1] >= 0.999f) | (ch[2] >= 0.999f);
}

}  // namespace

CloudModel CloudModel::load(const std::string& folder) {
    if (!fs::is_directory(folder)) throw_file_error(folder, "model folder not found");
    const std::string json_path = (fs::path(folder) / "model.json").string();
    if (!fs::exists(json_path)) throw_file_error(json_path, "model description not found (is this a model folder?)");
    CloudModel model;
    CloudModelInfo& info = model.info_;
    info.folder = folder;
    try {
        std::ifstream f(json_path);
        nlohmann::json j = nlohmann::json::parse(f);
        info.name = j.value("name", fs::path(folder).filename().string());
        info.resolution = j.at("resolution").get<int>();
        info.dt_seconds = j.at("dt_s").get<double>();
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
    if (!(info.dt_seconds > 0)) throw_file_error(json_path, "dt_s must be a positive number of seconds");
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
    cv::Mat f = from_blob(run_net(model.flownet_, to_blob({zero}), flow_path), flow_path);
    if (f.rows != n || f.cols != n || f.channels() != 3)
        throw_file_error(flow_path, "returns " + shape_text(f) + ", expected " + std::to_string(n) + " x " +
                                        std::to_string(n) + " x 3 (model.json's resolution)");
    cv::Mat c = from_blob(run_net(model.cloudnet_, to_blob({zero, f}), cloud_path), cloud_path);
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

cv::Mat CloudModel::decode_flow(const cv::Mat& encoded) const {
    cv::Mat out(encoded.size(), CV_32FC2);
    const float full = float(info_.flow_scale * info_.resolution);
    for (int y = 0; y < encoded.rows; ++y)
        for (int x = 0; x < encoded.cols; ++x) {
            cv::Vec3f e = encoded.at<cv::Vec3f>(y, x);
            float norm = std::max(std::hypot(e[0], e[1]), 1e-6f);
            float m = std::clamp(e[2], 0.0f, 1.0f) * full / norm;
            out.at<cv::Vec2f>(y, x) = cv::Vec2f(e[0] * m, e[1] * m);
        }
    return out;
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
    // input's radiance is put back into every output. The model does not predict the sun being
    // covered by cloud; a rollout keeps the input's sun as it is.
    cv::Mat sun = saturated_pixels(state);
    const bool has_sun = cv::countNonZero(sun) > 0;
    if (has_sun) {
        cv::dilate(sun, sun, cv::Mat());
        std::vector<cv::Mat> ch;
        cv::split(state, ch);
        for (cv::Mat& c : ch) {
            cv::Mat filled;
            cv::inpaint(c, sun, filled, 3.0, cv::INPAINT_TELEA);
            c = filled;
        }
        cv::merge(ch, state);
        state.setTo(cv::Scalar::all(0), ~disc_big);
    }
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
        next.time_seconds = sky.time_seconds + k * info_.dt_seconds;
        if (has_sun)
            for (int y = 0; y < big; ++y)
                for (int x = 0; x < big; ++x)
                    if (sun.at<uint8_t>(y, x)) next.set_pixel(x, y, sky.pixel(x, y));
        on_step(k, next);
    }
}

// ---- The networks' [0, 1] form ----

cv::Mat to_network_form(const SkyImage& sky, const NetworkFormParams& form, int resolution) {
    const int n = sky.resolution;
    Image unit = hdr_to_unit(sky, form.unit_map);
    cv::Mat image(n, n, CV_32FC3);
    std::copy(unit.pixels.begin(), unit.pixels.end(), image.ptr<float>());
    if (resolution > 0 && resolution != n) {
        cv::resize(image, image, cv::Size(resolution, resolution), 0, 0, cv::INTER_AREA);
        image.setTo(cv::Scalar::all(0), ~sky_disc_mask(resolution));
    }
    return image;
}

SkyImage from_network_form(const cv::Mat& image, const SkyImage& like, const NetworkFormParams& form) {
    if (image.rows != like.resolution || image.cols != like.resolution || image.type() != CV_32FC3)
        throw Error("from_network_form: the image must be CV_32FC3 at the sky's resolution");
    Image unit(image.cols, image.rows, 3);
    cv::Mat c = image.isContinuous() ? image : image.clone();
    std::copy(c.ptr<float>(), c.ptr<float>() + unit.pixels.size(), unit.pixels.begin());
    SkyImage out = unit_to_hdr(unit, form.unit_map);
    out.time_seconds = like.time_seconds;
    out.sun_direction = like.sun_direction;
    out.source = like.source;
    return out;
}

namespace {
// I_cm of an HDR sky at its own resolution, CV_8UC1 255 = cloud.
cv::Mat cloud_mask_of_sky(const SkyImage& sky, const NetworkFormParams& form) {
    const int n = sky.resolution;
    std::vector<unsigned char> in_disc(size_t(n) * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) in_disc[size_t(j) * n + i] = sky.in_disc(i, j);
    Image mask = cloud_mask(encode_sky_for_mask(sky), form.cloud_rule, &in_disc);
    cv::Mat m(n, n, CV_8UC1);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) m.at<uint8_t>(j, i) = mask.at(i, j, 0) > 0.7f ? 255 : 0;
    return m;
}
}  // namespace

cv::Mat network_cloud_mask(const cv::Mat& image, const NetworkFormParams& form) {
    SkyImage like(image.rows);
    cv::Mat clean;
    cv::min(cv::max(image, 0.0), 1.0, clean);
    cv::patchNaNs(clean, 0.0);
    return cloud_mask_of_sky(from_network_form(clean, like, form), form);
}

NetworkFrame resample_frame(const NetworkFrame& frame, int resolution) {
    const int n = resolution;
    if (frame.image.rows == n) return frame;
    NetworkFrame f;
    f.time_seconds = frame.time_seconds;
    const cv::Mat disc = sky_disc_mask(n);
    cv::resize(frame.image, f.image, cv::Size(n, n), 0, 0, cv::INTER_AREA);
    f.image.setTo(cv::Scalar::all(0), ~disc);
    cv::Mat seen, cloud;
    frame.valid.convertTo(seen, CV_32F, 1.0 / 255.0);
    cv::resize(seen, seen, cv::Size(n, n), 0, 0, cv::INTER_AREA);
    f.valid = (seen > 0.999f) & disc;
    frame.cloud.convertTo(cloud, CV_32F, 1.0 / 255.0);
    cv::resize(cloud, cloud, cv::Size(n, n), 0, 0, cv::INTER_AREA);
    f.cloud = (cloud > 0.5f) & disc;
    return f;
}

NetworkFrame network_frame(const SkyImage& sky, const std::vector<unsigned char>& not_sky, int resolution,
                           const NetworkFormParams& form) {
    const int big = sky.resolution;
    if (!not_sky.empty() && not_sky.size() != size_t(big) * big)
        throw Error("network_frame: the not-sky mask does not match the sky's resolution");
    NetworkFrame f;
    f.time_seconds = sky.time_seconds;
    f.image = to_network_form(sky, form);
    f.valid = sky_disc_mask(big);
    if (!not_sky.empty())
        for (int j = 0; j < big; ++j)
            for (int i = 0; i < big; ++i)
                if (not_sky[size_t(j) * big + i]) f.valid.at<uint8_t>(j, i) = 0;
    f.cloud = cloud_mask_of_sky(sky, form);
    return resample_frame(f, resolution > 0 ? resolution : big);
}

SkyImage import_preset_photo(const std::string& path, const std::string& preset, int import_resolution,
                             std::vector<unsigned char>* not_sky) {
    // The same steps, with the same defaults, as `dynsky sky import --preset P` (cli/sky_import_commands.cpp).
    CameraPreset cam = camera_preset(preset);
    PhotoImportParams params = cam.params;
    params.resolution = import_resolution;
    params.mask_path = find_preset_mask(preset, path);
    if (params.mask_path.empty()) params.detect_obstructions = true;
    ImportedPhoto photo = import_photo(path, params);
    SkyImage sky = photo.sky;
    const std::string time = time_from_file_name(path, cam.filename_utc_offset_hours);
    if (!time.empty() && photo.display_referred) {
        HdrCalibrationParams hp;
        hp.time = parse_utc_time(time);
        hp.location = GeoLocation{cam.latitude_deg, cam.longitude_deg, cam.elevation_m};
        hp.sun_search_deg = cam.sun_search_deg;
        sky = recover_hdr(photo, hp);
    }
    if (not_sky) *not_sky = photo.not_sky;
    return sky;
}

NetworkFrame network_frame_from_photo(const std::string& path, const std::string& preset, int import_resolution,
                                      int resolution, const NetworkFormParams& form) {
    std::vector<unsigned char> not_sky;
    SkyImage sky = import_preset_photo(path, preset, import_resolution, &not_sky);
    return network_frame(sky, not_sky, resolution, form);
}

// ---- .npy ----

NpyArray read_npy(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) throw_file_error(path, "cannot open the file");
    char magic[8];
    f.read(magic, 8);
    if (!f || std::memcmp(magic, "\x93NUMPY", 6) != 0) throw_file_error(path, "not a .npy file");
    uint32_t header_len = 0;
    if (magic[6] == 1) {
        unsigned char b[2];
        f.read(reinterpret_cast<char*>(b), 2);
        header_len = b[0] | (b[1] << 8);
    } else {
        unsigned char b[4];
        f.read(reinterpret_cast<char*>(b), 4);
        header_len = b[0] | (b[1] << 8) | (b[2] << 16) | (uint32_t(b[3]) << 24);
    }
    std::string header(header_len, '\0');
    f.read(header.data(), header_len);
    if (!f) throw_file_error(path, "truncated .npy header");
    auto field = [&](const std::string& key) {
        size_t p = header.find("'" + key + "'");
        if (p == std::string::npos) throw_file_error(path, ".npy header lacks '" + key + "'");
        return header.substr(header.find(':', p) + 1);
    };
    std::string descr = field("descr");
    bool is_f4 = descr.find("<f4") != std::string::npos, is_u1 = descr.find("|u1") != std::string::npos ||
                                                                   descr.find("|b1") != std::string::npos;
    if (!is_f4 && !is_u1) throw_file_error(path, "only float32 and uint8 .npy files are supported");
    std::string order = field("fortran_order");
    if (order.substr(0, order.find(',')).find("True") != std::string::npos)
        throw_file_error(path, "Fortran-order .npy is not supported");
    std::string s = field("shape");
    s = s.substr(s.find('(') + 1, s.find(')') - s.find('(') - 1);
    NpyArray a;
    std::stringstream ss(s);
    std::string item;
    size_t count = 1;
    while (std::getline(ss, item, ',')) {
        if (item.find_first_not_of(" ") == std::string::npos) continue;
        a.shape.push_back(std::stoull(item));
        count *= a.shape.back();
    }
    a.data.resize(count);
    if (is_f4) {
        f.read(reinterpret_cast<char*>(a.data.data()), std::streamsize(count * 4));
    } else {
        std::vector<unsigned char> b(count);
        f.read(reinterpret_cast<char*>(b.data()), std::streamsize(count));
        for (size_t i = 0; i < count; ++i) a.data[i] = b[i];
    }
    if (!f) throw_file_error(path, "truncated .npy data");
    return a;
}

namespace {
void write_npy_raw(const std::string& path, const std::vector<size_t>& shape, const char* descr, const void* data,
                   size_t bytes_count) {
    std::string dict = std::string("{'descr': '") + descr + "', 'fortran_order': False, 'shape': (";
    for (size_t i = 0; i < shape.size(); ++i) dict += std::to_string(shape[i]) + (shape.size() == 1 || i + 1 < shape.size() ? "," : "");
    dict += "), }";
    size_t total = 10 + dict.size() + 1;
    dict += std::string((64 - total % 64) % 64, ' ') + "\n";
    std::string bytes("\x93NUMPY\x01\x00", 8);
    bytes += char(dict.size() & 0xff), bytes += char(dict.size() >> 8);
    bytes += dict;
    bytes.append(static_cast<const char*>(data), bytes_count);
    write_file_atomic(path, bytes);
}
size_t element_count(const std::vector<size_t>& shape) {
    size_t n = 1;
    for (size_t s : shape) n *= s;
    return n;
}
}  // namespace

void write_npy(const std::string& path, const std::vector<size_t>& shape, const float* data) {
    write_npy_raw(path, shape, "<f4", data, element_count(shape) * 4);
}
void write_npy(const std::string& path, const std::vector<size_t>& shape, const unsigned char* data) {
    write_npy_raw(path, shape, "|u1", data, element_count(shape));
}

}  // namespace dynsky
