#include "motion/training_set.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "motion/flow.h"
#include "motion/photo_sequence.h"
#include "util/atomic_file.h"
#include "util/error.h"
#include "util/parse.h"
#include "util/image.h"
#include "util/json_file.h"
#include "util/npy.h"
#include "util/progress.h"

namespace dynsky {

namespace {

namespace fs = std::filesystem;

std::vector<float> stack(const std::vector<cv::Mat>& mats) {
    std::vector<float> out;
    for (const cv::Mat& m : mats) {
        cv::Mat c = m.isContinuous() ? m : m.clone();
        out.insert(out.end(), c.ptr<float>(), c.ptr<float>() + c.total() * c.channels());
    }
    return out;
}
std::vector<unsigned char> stack_mask(const std::vector<cv::Mat>& mats) {
    std::vector<unsigned char> out;
    for (const cv::Mat& m : mats)
        for (int y = 0; y < m.rows; ++y)
            for (int x = 0; x < m.cols; ++x) out.push_back(m.at<uint8_t>(y, x) ? 1 : 0);
    return out;
}

}  // namespace

void build_training_sequence(const TrainingSetOptions& o) {
    if (o.out.empty()) throw Error("--out: an output folder is required");
    if (o.sequence.empty() == o.procedural.empty())
        throw Error(
            "--sequence, --procedural: give exactly one of --sequence (real photographs) and --procedural (a `sky procedural` folder)");
    check_import_resolution(o.import_resolution);
    if (o.resolution < 8 || o.import_resolution < o.resolution || o.import_resolution % o.resolution != 0)
        throw Error("--sky-res " + std::to_string(o.resolution) + ": must be >= 8 and divide --import-res " +
                    std::to_string(o.import_resolution));
    if (fs::exists(o.out) && !fs::is_directory(o.out)) throw_file_error(o.out, "exists and is not a folder");
    NetworkFormParams form = o.form;
    form.cloud_rule.rule = parse_cloud_rule(o.cloud_rule);
    if (!(form.unit_map.max_radiance > form.unit_map.scale))
        throw Error("--unit-max " + number_text(form.unit_map.max_radiance) + ": must exceed --unit-scale " +
                    number_text(form.unit_map.scale));
    validate_unit_map(form.unit_map);

    const int n = o.resolution, big = o.import_resolution;
    std::vector<NetworkFrame> frames_big;
    std::vector<cv::Mat> exact;
    std::vector<std::string> names;
    std::vector<double> capture_utc;  // photographs only: UTC seconds (utc_seconds), NaN unknown
    nlohmann::ordered_json meta;
    double dt = 0;
    if (!o.sequence.empty()) {
        PhotoSequence seq = named_photo_sequence(o.sequence, o.shared.empty() ? default_shared_dir() : o.shared);
        dt = seq.dt;
        meta["source"] = "photographs in " + seq.folder + ", imported with camera preset " + seq.preset;
        meta["preset"] = seq.preset;
        ProgressBar progress(long(seq.photos.size()), "import " + seq.name, o.quiet);
        for (size_t k = 0; k < seq.photos.size(); ++k) {
            frames_big.push_back(network_frame_from_photo(seq.photos[k], seq.preset, big, big, form));
            frames_big.back().time_seconds = k * dt;
            names.push_back(fs::path(seq.photos[k]).filename().string());
            capture_utc.push_back(k < seq.utc.size() ? seq.utc[k] : std::nan(""));
            progress.advance();
        }
        progress.finish();
    } else {
        nlohmann::json m = read_json((fs::path(o.procedural) / "manifest.json").string());
        dt = m.at("dt_s").get<double>();
        meta["source"] = "procedural sequence in " + o.procedural;
        meta["procedural"] = {{"seed", m.value("seed", 0)},
                              {"coverage", m.value("coverage", 0.0)},
                              {"layers", m["layers"]}};
        ProgressBar progress(long(m.at("frames").size()), "procedural frames", o.quiet);
        for (const auto& fr : m.at("frames")) {
            SkyImage sky = load_sky((fs::path(o.procedural) / fr.at("image").get<std::string>()).string());
            if (sky.resolution != big)
                throw_file_error(o.procedural, "frames are " + std::to_string(sky.resolution) +
                                                   " px; generate them at --import-res " + std::to_string(big));
            frames_big.push_back(network_frame(sky, {}, big, form));
            frames_big.back().time_seconds = fr.at("time_s").get<double>();
            names.push_back(fr.at("image").get<std::string>());
            Image flow = read_image((fs::path(o.procedural) / fr.at("flow").get<std::string>()).string());
            cv::Mat fxy(flow.height, flow.width, CV_32FC2);
            for (int y = 0; y < flow.height; ++y)
                for (int x = 0; x < flow.width; ++x)
                    fxy.at<cv::Vec2f>(y, x) = cv::Vec2f(flow.at(x, y, 0), flow.at(x, y, 1));
            exact.push_back(flow_at_resolution(fxy, n));
            progress.advance();
        }
        progress.finish();
    }
    const size_t count = frames_big.size();
    if (count < 2)
        throw_file_error(o.procedural.empty() ? o.sequence : o.procedural,
                         "the sequence has " + std::to_string(count) + " frame(s): a training pair needs two");
    std::vector<cv::Mat> images, valid, cloud, flows;
    std::vector<double> times;
    std::vector<cv::Mat> backgrounds;
    std::vector<float> suns;
    for (const NetworkFrame& fb : frames_big) {
        NetworkFrame f = resample_frame(fb, n);
        images.push_back(f.image), valid.push_back(f.valid), cloud.push_back(f.cloud), times.push_back(f.time_seconds);
        // The clear background under the clouds (the advect-residual model moves only what differs).
        backgrounds.push_back(f.sun_direction ? clear_background(f.sun_direction->cast<double>(), n, form)
                                              : cv::Mat(n, n, CV_32FC3, cv::Scalar::all(0)));
        const Vec3 sun = f.sun_direction ? *f.sun_direction : Vec3(0, 0, 0);
        suns.insert(suns.end(), {sun.x(), sun.y(), sun.z()});
    }
    ProgressBar progress(long(count - 1), "farneback", o.quiet);
    for (size_t k = 0; k + 1 < count; ++k) {
        flows.push_back(flow_at_resolution(farneback_flow(frames_big[k].image, frames_big[k + 1].image), n));
        progress.advance();
    }
    progress.finish();

    fs::create_directories(o.out);
    auto path = [&](const char* name) { return (fs::path(o.out) / name).string(); };
    const size_t t = count, nn = size_t(n);
    write_npy(path("images.npy"), {t, nn, nn, 3}, stack(images).data());
    write_npy(path("valid.npy"), {t, nn, nn}, stack_mask(valid).data());
    write_npy(path("cloud.npy"), {t, nn, nn}, stack_mask(cloud).data());
    write_npy(path("background.npy"), {t, nn, nn, 3}, stack(backgrounds).data());
    write_npy(path("sun.npy"), {t, 3}, suns.data());
    write_npy(path("flow_farneback.npy"), {t - 1, nn, nn, 2}, stack(flows).data());
    if (!exact.empty())
        write_npy(path("flow_exact.npy"), {t - 1, nn, nn, 2},
                  stack(std::vector<cv::Mat>(exact.begin(), exact.end() - 1)).data());
    meta["dt_s"] = dt;
    meta["resolution"] = n;
    meta["import_resolution"] = big;
    meta["frame_count"] = t;
    meta["times_s"] = times;
    meta["frames"] = names;
    // When each photograph was taken, so that a split of this data set says which photographs a
    // model trained on wherever they are evaluated (frame numbers alone are this folder's).
    if (!capture_utc.empty()) {
        nlohmann::json utc = nlohmann::json::array();
        for (double t : capture_utc) utc.push_back(std::isfinite(t) ? nlohmann::json(t) : nlohmann::json());
        meta["frames_utc_s"] = utc;
    }
    meta["flow_farneback"] =
        "OpenCV calcOpticalFlowFarneback (pyr 0.5, 3 levels, window 15, 3 iterations, poly 5 / 1.2) "
        "frame k -> k+1 on the luminance at the import resolution, area-averaged to N, pixels of N";
    meta["unit_scale"] = form.unit_map.scale;
    meta["unit_max"] = form.unit_map.max_radiance;
    meta["cloud_rule"] = cloud_rule_name(form.cloud_rule.rule);
    meta["cloud_threshold"] = form.cloud_rule.threshold;
    meta["images"] = "hdr_to_unit (sky/hdr_recovery.h): log(1 + L / unit_scale) / log(1 + unit_max / unit_scale)";
    meta["cloud"] =
        "sky/cloud_mask.h rule on the sky encoded as a camera would (encode_sky_for_mask) at the import "
        "resolution, then majority over the pixels under each pixel of N";
    write_file_atomic(path("meta.json"), meta.dump(2) + "\n");
    if (!o.quiet) std::printf("wrote %zu frames at %d px to %s\n", count, n, o.out.c_str());
}

}  // namespace dynsky
