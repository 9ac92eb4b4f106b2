// dynsky sky predict | evaluate | training-data: the medium-timescale cloud model (motion/cloud_model.h)
// run on skies, scored against real sequences and the two baselines, and the C++ half of the
// training-set builder (networks/dataset.py drives it; docs/networks.md).
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli/commands.h"
#include "motion/cloud_model.h"
#include "sky/sky_image.h"
#include "motion/advection.h"
#include "motion/metrics.h"
#include "motion/sun_patch.h"
#include "sky/preset_import.h"
#include "util/npy.h"
#include "util/data_path.h"
#include "util/error.h"
#include "util/exposure.h"
#include "util/atomic_file.h"
#include "util/image.h"
#include "util/math.h"
#include "util/progress.h"

namespace dynsky::cli {

namespace {

namespace fs = std::filesystem;

std::vector<int> parse_int_list(const std::string& text, const std::string& option) {
    std::vector<int> out;
    std::stringstream ss(text);
    std::string item;
    while (std::getline(ss, item, ',')) {
        try {
            size_t used = 0;
            int v = std::stoi(item, &used);
            if (used != item.size() || v < 1) throw std::invalid_argument("");
            out.push_back(v);
        } catch (const std::exception&) {
            throw Error(option + ": '" + item + "' is not a positive whole number (write e.g. 1,2,3,6)");
        }
    }
    if (out.empty()) throw Error(option + ": give at least one value");
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
}

nlohmann::json read_json(const std::string& path) {
    if (!fs::exists(path)) throw_file_error(path, "not found");
    try {
        std::ifstream f(path);
        return nlohmann::json::parse(f);
    } catch (const nlohmann::json::exception& e) {
        throw_file_error(path, std::string("not valid JSON: ") + e.what());
    }
}

// ---- real sequences in ../shared ----

struct RealSequence {
    std::string name;    // the dataset's and split's name ("arm_tsi")
    std::string preset;  // camera preset of the import
    std::string folder;
    double dt_s = 0;
    std::vector<std::string> photos;  // in time order
};

std::string default_shared_dir() {
    // The shared data sits beside the source tree (the tests' ../shared).
    try {
        return (fs::path(data_path("sky")).parent_path().parent_path() / "shared").string();
    } catch (const Error&) {
        return "../shared";
    }
}

RealSequence real_sequence(const std::string& name, const std::string& shared_dir) {
    RealSequence s;
    if (name == "arm-tsi" || name == "arm_tsi") {
        s = {"arm_tsi", "arm-tsi", (fs::path(shared_dir) / "skies" / "arm_tsi_sgp_20170524").string(), 30.0, {}};
    } else if (name == "mobotix") {
        s = {"mobotix", "mobotix", (fs::path(shared_dir) / "skies" / "mobotix_sophia_20200812_morning").string(), 60.0, {}};
    } else {
        throw Error("--sequence: unknown sequence '" + name + "' (known: arm-tsi, mobotix)");
    }
    const std::string csv = (fs::path(s.folder) / "frames.csv").string();
    if (fs::exists(csv)) {
        std::ifstream f(csv);
        std::string line;
        std::getline(f, line);  // header
        while (std::getline(f, line))
            if (!line.empty()) s.photos.push_back((fs::path(s.folder) / line.substr(0, line.find(','))).string());
    } else if (fs::is_directory(fs::path(s.folder) / "images")) {
        for (const auto& e : fs::directory_iterator(fs::path(s.folder) / "images"))
            if (e.path().extension() == ".jpg" || e.path().extension() == ".png") s.photos.push_back(e.path().string());
        std::sort(s.photos.begin(), s.photos.end());
    } else {
        throw_file_error(s.folder, "sequence folder not found (give the shared data folder with --shared)");
    }
    if (s.photos.size() < 2) throw_file_error(s.folder, "fewer than two frames");
    return s;
}

// Farneback at the import resolution (sharper motion estimates), area-averaged to N and rescaled
// to N's pixels.
cv::Mat flow_at(const cv::Mat& flow_big, int n) {
    if (flow_big.rows == n) return flow_big;
    cv::Mat small;
    cv::resize(flow_big, small, cv::Size(n, n), 0, 0, cv::INTER_AREA);
    return small * (double(n) / flow_big.rows);
}

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

// ---- dynsky sky training-data ----

struct TrainingDataOptions {
    std::string sequence, procedural, shared, out;
    int resolution = 128, import_resolution = 256;
    NetworkFormParams form;
    std::string cloud_rule = "rb";
    bool quiet = false;
};

void run_training_data(const TrainingDataOptions& o) {
    if (o.out.empty()) throw Error("--out: an output folder is required");
    if (o.sequence.empty() == o.procedural.empty())
        throw Error("give exactly one of --sequence (real photographs) and --procedural (a `sky procedural` folder)");
    if (o.resolution < 8 || o.import_resolution < o.resolution || o.import_resolution % o.resolution != 0)
        throw Error("--res must be >= 8 and divide --import-res");
    if (fs::exists(o.out) && !fs::is_directory(o.out)) throw_file_error(o.out, "exists and is not a folder");
    NetworkFormParams form = o.form;
    form.cloud_rule.rule = parse_cloud_rule(o.cloud_rule);
    validate_unit_map(form.unit_map);

    const int n = o.resolution, big = o.import_resolution;
    std::vector<NetworkFrame> frames_big;
    std::vector<cv::Mat> exact;
    std::vector<std::string> names;
    nlohmann::ordered_json meta;
    double dt = 0;
    if (!o.sequence.empty()) {
        RealSequence seq = real_sequence(o.sequence, o.shared.empty() ? default_shared_dir() : o.shared);
        dt = seq.dt_s;
        meta["source"] = "photographs in " + seq.folder + ", imported with camera preset " + seq.preset;
        meta["preset"] = seq.preset;
        ProgressBar progress(long(seq.photos.size()), "import " + seq.name, o.quiet);
        for (size_t k = 0; k < seq.photos.size(); ++k) {
            frames_big.push_back(network_frame_from_photo(seq.photos[k], seq.preset, big, big, form));
            frames_big.back().time_seconds = k * dt;
            names.push_back(fs::path(seq.photos[k]).filename().string());
            progress.advance();
        }
        progress.finish();
    } else {
        nlohmann::json m = read_json((fs::path(o.procedural) / "manifest.json").string());
        dt = m.at("dt_s").get<double>();
        meta["source"] = "procedural sequence in " + o.procedural;
        meta["procedural"] = {{"seed", m.value("seed", 0)}, {"coverage", m.value("coverage", 0.0)}, {"layers", m["layers"]}};
        ProgressBar progress(long(m.at("frames").size()), "procedural frames", o.quiet);
        for (const auto& fr : m.at("frames")) {
            SkyImage sky = load_sky((fs::path(o.procedural) / fr.at("image").get<std::string>()).string());
            if (sky.resolution != big)
                throw_file_error(o.procedural, "frames are " + std::to_string(sky.resolution) + " px; generate them at --import-res " +
                                                   std::to_string(big));
            frames_big.push_back(network_frame(sky, {}, big, form));
            frames_big.back().time_seconds = fr.at("time_s").get<double>();
            names.push_back(fr.at("image").get<std::string>());
            Image flow = read_image((fs::path(o.procedural) / fr.at("flow").get<std::string>()).string());
            cv::Mat fxy(flow.height, flow.width, CV_32FC2);
            for (int y = 0; y < flow.height; ++y)
                for (int x = 0; x < flow.width; ++x) fxy.at<cv::Vec2f>(y, x) = cv::Vec2f(flow.at(x, y, 0), flow.at(x, y, 1));
            exact.push_back(flow_at(fxy, n));
            progress.advance();
        }
        progress.finish();
    }
    const size_t count = frames_big.size();
    if (count < 2) throw Error("the sequence has fewer than two frames");
    std::vector<cv::Mat> images, valid, cloud, flows;
    std::vector<double> times;
    for (const NetworkFrame& fb : frames_big) {
        NetworkFrame f = resample_frame(fb, n);
        images.push_back(f.image), valid.push_back(f.valid), cloud.push_back(f.cloud), times.push_back(f.time_seconds);
    }
    ProgressBar progress(long(count - 1), "farneback", o.quiet);
    for (size_t k = 0; k + 1 < count; ++k) {
        flows.push_back(flow_at(farneback_flow(frames_big[k].image, frames_big[k + 1].image), n));
        progress.advance();
    }
    progress.finish();

    fs::create_directories(o.out);
    auto path = [&](const char* name) { return (fs::path(o.out) / name).string(); };
    const size_t t = count, nn = size_t(n);
    write_npy(path("images.npy"), {t, nn, nn, 3}, stack(images).data());
    write_npy(path("valid.npy"), {t, nn, nn}, stack_mask(valid).data());
    write_npy(path("cloud.npy"), {t, nn, nn}, stack_mask(cloud).data());
    write_npy(path("flow_farneback.npy"), {t - 1, nn, nn, 2}, stack(flows).data());
    if (!exact.empty()) write_npy(path("flow_exact.npy"), {t - 1, nn, nn, 2}, stack(std::vector<cv::Mat>(exact.begin(), exact.end() - 1)).data());
    meta["dt_s"] = dt;
    meta["resolution"] = n;
    meta["import_resolution"] = big;
    meta["frame_count"] = t;
    meta["times_s"] = times;
    meta["frames"] = names;
    meta["flow_farneback"] = "OpenCV calcOpticalFlowFarneback (pyr 0.5, 3 levels, window 15, 3 iterations, poly 5 / 1.2) "
                             "frame k -> k+1 on the luminance at the import resolution, area-averaged to N, pixels of N";
    meta["unit_scale"] = form.unit_map.scale;
    meta["unit_max"] = form.unit_map.max_radiance;
    meta["cloud_rule"] = cloud_rule_name(form.cloud_rule.rule);
    meta["cloud_threshold"] = form.cloud_rule.threshold;
    meta["images"] = "hdr_to_unit (sky/hdr_recovery.h): log(1 + L / unit_scale) / log(1 + unit_max / unit_scale)";
    meta["cloud"] = "sky/cloud_mask.h rule on the sky encoded as a camera would (encode_sky_for_mask) at the import "
                    "resolution, then majority over the pixels under each pixel of N";
    write_file_atomic(path("meta.json"), meta.dump(2) + "\n");
    if (!o.quiet) std::printf("wrote %zu frames at %d px to %s\n", count, n, o.out.c_str());
}

// ---- dynsky sky predict ----

struct PredictOptions {
    std::string model, in, out, stats;
    int steps = 1, every = 1;
    bool preview = false, quiet = false;
};

// High-frequency energy: mean squared difference between the image and its Gaussian blur
// (sigma 2 px at N), inside the disc. A rollout that blurs loses it; one that runs away gains it.
double high_frequency_energy(const cv::Mat& image, const cv::Mat& mask) {
    cv::Mat blurred, diff;
    cv::GaussianBlur(image, blurred, cv::Size(0, 0), 2.0, 2.0, cv::BORDER_REFLECT);
    cv::subtract(image, blurred, diff);
    diff = diff.mul(diff);
    cv::Scalar s = cv::sum(diff.setTo(0, ~mask));
    return (s[0] + s[1] + s[2]) / (3.0 * cv::countNonZero(mask));
}

void run_predict(const PredictOptions& o) {
    if (o.steps < 1 || o.steps > 100000) throw Error("--steps: must be in 1..100000");
    if (o.every < 1) throw Error("--every: must be >= 1");
    if (fs::exists(o.out) && !fs::is_directory(o.out)) throw_file_error(o.out, "exists and is not a folder");
    CloudModel model = CloudModel::load(o.model);
    SkyImage sky = load_sky(o.in);
    const int n = model.info().resolution;
    const cv::Mat disc = sky_disc_mask(n);
    fs::create_directories(o.out);
    std::ostringstream csv;
    csv << "step,time_s,mean_luminance,mean_unit,min_unit,max_unit,cloud_coverage,hf_energy,nonfinite\n";
    auto stats_row = [&](int k, const SkyImage& s) {
        double lum = 0;
        long nonfinite = 0, count = 0;
        for (int j = 0; j < s.resolution; ++j)
            for (int i = 0; i < s.resolution; ++i) {
                if (!s.in_disc(i, j)) continue;
                Color c = s.pixel(i, j);
                if (!c.isFinite().all()) {
                    ++nonfinite;
                    continue;
                }
                lum += luminance(c), ++count;
            }
        cv::Mat unit = to_network_form(s, model.info().form, n);
        cv::Mat finite_unit = unit.clone();
        cv::patchNaNs(finite_unit, 0.0);
        double mn, mx;
        cv::minMaxLoc(finite_unit.reshape(1), &mn, &mx, nullptr, nullptr, cv::repeat(disc, 1, 3).reshape(1, n));
        cv::Scalar mean = cv::mean(finite_unit, disc);
        double coverage = double(cv::countNonZero(network_cloud_mask(finite_unit, model.info().form) & disc)) / cv::countNonZero(disc);
        char line[256];
        std::snprintf(line, sizeof line, "%d,%.3f,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%ld\n", k, s.time_seconds,
                      count ? lum / count : 0.0, (mean[0] + mean[1] + mean[2]) / 3, mn, mx, coverage,
                      high_frequency_energy(finite_unit, disc), nonfinite);
        csv << line;
    };
    if (!o.stats.empty()) stats_row(0, sky);
    // One exposure for every preview (the input's), so they do not flicker.
    const float preview_ev = exposure_log_average(sky_to_image(sky));
    ProgressBar progress(o.steps, "predict", o.quiet);
    int written = 0;
    model.rollout(sky, o.steps, [&](int k, const SkyImage& s) {
        if (k % o.every == 0 || k == o.steps) {
            char name[32];
            std::snprintf(name, sizeof name, "step_%04d", k);
            std::string base = (fs::path(o.out) / name).string();
            save_sky(base + ".exr", s);
            if (o.preview) write_image(base + ".png", tonemap_to_display(sky_to_image(s), preview_ev));
            ++written;
        }
        if (!o.stats.empty()) stats_row(k, s);
        progress.advance();
    });
    progress.finish();
    if (!o.stats.empty()) write_file_atomic(o.stats, csv.str());
    if (!o.quiet)
        std::printf("wrote %d predicted skies (Delta t = %g s, %d steps) to %s\n", written, model.info().dt_seconds,
                    o.steps, o.out.c_str());
}

// ---- dynsky sky evaluate ----

struct EvaluateOptions {
    std::string model, sequence, shared, horizons = "1,2,3,6", report = "docs/networks-evaluation.md",
                                         histogram = "docs/networks-flow-histogram.png";
    int import_resolution = 0, limit = 0;
    bool quiet = false;
};

struct Scores {
    std::vector<double> mse, psnr, ssim;
    void add(const ImageComparison& c) { mse.push_back(c.mse), psnr.push_back(c.psnr), ssim.push_back(c.ssim); }
    static double mean(const std::vector<double>& v) {
        double s = 0;
        for (double x : v) s += x;
        return v.empty() ? std::nan("") : s / v.size();
    }
};

// A two- or three-series histogram drawn with OpenCV (no plotting library needed at run time).
void draw_histogram(const std::string& path, const std::string& title, const std::string& xlabel, double max_value,
                    const std::vector<std::pair<std::string, std::vector<float>>>& series) {
    const int bins = 40, w = 900, h = 520, left = 80, right = 20, top = 50, bottom = 70;
    const cv::Scalar colours[] = {cv::Scalar(200, 120, 40), cv::Scalar(40, 110, 230), cv::Scalar(60, 170, 60)};
    std::vector<std::vector<double>> hist(series.size(), std::vector<double>(bins, 0.0));
    double peak = 1e-9;
    for (size_t s = 0; s < series.size(); ++s) {
        for (float v : series[s].second) hist[s][std::clamp(int(v / max_value * bins), 0, bins - 1)] += 1;
        for (double& b : hist[s]) b /= std::max<size_t>(1, series[s].second.size()), peak = std::max(peak, b);
    }
    cv::Mat img(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
    const int pw = w - left - right, ph = h - top - bottom;
    cv::rectangle(img, cv::Rect(left, top, pw, ph), cv::Scalar(0, 0, 0), 1);
    for (size_t s = 0; s < series.size(); ++s) {
        std::vector<cv::Point> pts;
        for (int b = 0; b < bins; ++b) {
            int x0 = left + b * pw / bins, x1 = left + (b + 1) * pw / bins;
            int y = top + ph - int(hist[s][b] / peak * (ph - 10));
            pts.push_back({x0, y}), pts.push_back({x1, y});
        }
        cv::polylines(img, pts, false, colours[s % 3], 2, cv::LINE_AA);
        cv::putText(img, series[s].first + " (" + std::to_string(series[s].second.size()) + " px)",
                    {left + pw - 430, top + 25 + 22 * int(s)}, cv::FONT_HERSHEY_SIMPLEX, 0.55, colours[s % 3], 1, cv::LINE_AA);
    }
    for (int k = 0; k <= 4; ++k) {
        char label[32];
        std::snprintf(label, sizeof label, "%.2g", max_value * k / 4);
        int x = left + k * pw / 4;
        cv::line(img, {x, top + ph}, {x, top + ph + 6}, cv::Scalar(0, 0, 0));
        cv::putText(img, label, {x - 12, top + ph + 24}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    }
    cv::putText(img, title, {left, 32}, cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    cv::putText(img, xlabel, {left + pw / 2 - 160, h - 18}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    cv::putText(img, "fraction", {8, top + ph / 2}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    Image out(w, h, 3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) out.at(x, y, c) = img.at<cv::Vec3b>(y, x)[2 - c] / 255.0f;  // BGR drawing
    if (!fs::path(path).parent_path().empty()) fs::create_directories(fs::path(path).parent_path());
    write_image(path, out);
}

void append_magnitudes(const cv::Mat& flow, const cv::Mat& mask, std::vector<float>* out) {
    for (int y = 0; y < flow.rows; ++y)
        for (int x = 0; x < flow.cols; ++x)
            if (mask.at<uint8_t>(y, x)) {
                cv::Vec2f f = flow.at<cv::Vec2f>(y, x);
                out->push_back(std::hypot(f[0], f[1]));
            }
}

void run_evaluate(const EvaluateOptions& o) {
    const std::vector<int> horizons = parse_int_list(o.horizons, "--horizons");
    RealSequence seq = real_sequence(o.sequence, o.shared.empty() ? default_shared_dir() : o.shared);
    CloudModel model = CloudModel::load(o.model);
    const CloudModelInfo& info = model.info();
    const std::string split_path = (fs::path(o.model) / "split.json").string();
    nlohmann::json split = read_json(split_path);
    if (!split.contains(seq.name))
        throw_file_error(split_path, "has no split for sequence '" + seq.name + "': the model was not trained on it");
    const int lo = split[seq.name].at("heldout").at(0).get<int>();
    int hi = split[seq.name].at("heldout").at(1).get<int>();
    if (lo < 1 || hi > int(seq.photos.size()) || hi - lo < 2)
        throw_file_error(split_path, "held-out range does not fit the sequence's " + std::to_string(seq.photos.size()) + " frames");
    if (std::abs(seq.dt_s - info.dt_seconds) > 1e-6)
        throw Error("the model steps " + std::to_string(info.dt_seconds) + " s but the sequence's cadence is " +
                    std::to_string(seq.dt_s) + " s");
    const int hmax = horizons.back();
    if (hi - lo <= hmax) throw Error("--horizons: the held-out part has only " + std::to_string(hi - lo) + " frames");
    if (o.limit < 0) throw Error("--limit: must be >= 0");
    if (o.limit > 0) hi = std::min(hi, lo + o.limit + hmax);  // only the frames the first --limit starts need

    nlohmann::json mj = read_json((fs::path(o.model) / "model.json").string());
    const int n = info.resolution;
    const int big = o.import_resolution > 0 ? o.import_resolution : mj.value("import_resolution", 2 * n);

    // The held-out frames and the one before them (the Farneback baseline's previous frame).
    std::vector<NetworkFrame> frames, frames_big;
    ProgressBar progress(hi - lo + 1, "import held-out frames", o.quiet);
    for (int k = lo - 1; k < hi; ++k) {
        frames_big.push_back(network_frame_from_photo(seq.photos[k], seq.preset, big, big, info.form));
        frames.push_back(resample_frame(frames_big.back(), n));
        progress.advance();
    }
    progress.finish();
    auto frame = [&](int k) -> const NetworkFrame& { return frames[k - (lo - 1)]; };
    auto frame_big = [&](int k) -> const NetworkFrame& { return frames_big[k - (lo - 1)]; };

    std::map<int, Scores> sm, sp, sf;
    std::vector<float> real_mag, rollout_mag, flownet_mag;
    ProgressBar progress2(hi - hmax - lo, "evaluate", o.quiet);
    // The flow of the pair ending at t (the baseline's) is the one measured from t at the step before.
    cv::Mat flow = lo + hmax < hi ? flow_at(farneback_flow(frame_big(lo - 1).image, frame_big(lo).image), n) : cv::Mat();
    for (int t = lo; t + hmax < hi; ++t) {
        cv::Mat next_flow = flow_at(farneback_flow(frame_big(t).image, frame_big(t + 1).image), n);
        append_magnitudes(next_flow, frame(t).cloud & frame(t).valid & frame(t + 1).valid, &real_mag);
        cv::Mat state = frame(t).image;
        for (int h = 1; h <= hmax; ++h) {
            NetworkStep s = model.step_network(state);
            if (h == 1) append_magnitudes(model.decode_flow(s.flow), frame(t).cloud & frame(t).valid, &flownet_mag);
            append_magnitudes(farneback_flow(state, s.next), network_cloud_mask(state, info.form) & frame(t).valid, &rollout_mag);
            state = s.next;
            if (!std::binary_search(horizons.begin(), horizons.end(), h)) continue;
            const cv::Mat& truth = frame(t + h).image;
            const cv::Mat mask = frame(t + h).valid & frame(t).valid;
            sm[h].add(compare_images(state, truth, mask));
            sp[h].add(compare_images(frame(t).image, truth, mask));
            sf[h].add(compare_images(advect_by_flow(frame(t).image, flow, h), truth, mask));
        }
        flow = next_flow;
        progress2.advance();
    }
    progress2.finish();

    std::ostringstream md;
    char line[512];
    md << "# Cloud model evaluation: " << info.name << " on " << seq.name << " (held-out frames)\n\n";
    md << "Written by `dynsky sky evaluate --model " << o.model << " --sequence " << o.sequence << " --horizons "
       << o.horizons << "`.\n\n";
    std::snprintf(line, sizeof line,
                  "Held-out frames %d..%d of %zu (the last part in time, from the model's split.json); "
                  "Delta t = %g s; images compared at the model's %d x %d in the networks' [0, 1] form, "
                  "inside the sky disc minus pixels the camera could not see (arm, shadow band); PSNR and SSIM "
                  "are means of per-frame values. Model: %d recursive steps from the real frame. Persistence: the "
                  "frame itself. Farneback: the frame advected h times by the flow of the previous pair "
                  "(computed at %d px).\n\n",
                  lo, hi - 1, seq.photos.size(), info.dt_seconds, n, n, hmax, big);
    md << line;
    md << "| horizon | ahead | model PSNR | model SSIM | persistence PSNR | persistence SSIM | Farneback PSNR | "
          "Farneback SSIM | model MSE | persistence MSE | Farneback MSE | frames |\n";
    md << "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (int h : horizons) {
        std::snprintf(line, sizeof line,
                      "| %d | %g s | %.2f dB | %.3f | %.2f dB | %.3f | %.2f dB | %.3f | %.5f | %.5f | %.5f | %zu |\n", h,
                      h * info.dt_seconds, Scores::mean(sm[h].psnr), Scores::mean(sm[h].ssim), Scores::mean(sp[h].psnr),
                      Scores::mean(sp[h].ssim), Scores::mean(sf[h].psnr), Scores::mean(sf[h].ssim),
                      Scores::mean(sm[h].mse), Scores::mean(sp[h].mse), Scores::mean(sf[h].mse), sm[h].psnr.size());
        md << line;
    }
    auto median_or_0 = [](const std::vector<float>& v) { return v.empty() ? 0.0f : median(v); };
    std::snprintf(line, sizeof line,
                  "\nFlow magnitude on cloud pixels, pixels per step at %d px (median): real frames (Farneback) %.3f, "
                  "model rollout frames (Farneback) %.3f, FlowNet output %.3f. Histogram: `%s`.\n",
                  n, median_or_0(real_mag), median_or_0(rollout_mag), median_or_0(flownet_mag), o.histogram.c_str());
    md << line;
    float top = std::max({median_or_0(real_mag), median_or_0(rollout_mag), median_or_0(flownet_mag), 0.05f}) * 4.0f;
    draw_histogram(o.histogram, "Cloud motion per step, " + seq.name + " held-out (" + info.name + ")",
                   "flow magnitude on cloud pixels (px per step at " + std::to_string(n) + " px)", top,
                   {{"real frames (Farneback)", real_mag}, {"model rollout (Farneback)", rollout_mag},
                    {"FlowNet output", flownet_mag}});
    write_file_atomic(o.report, md.str());
    if (!o.quiet) std::printf("%s\nwrote %s and %s\n", md.str().c_str(), o.report.c_str(), o.histogram.c_str());
}

}  // namespace

void register_sky_model_commands(CLI::App& sky) {
    {
        auto o = std::make_shared<PredictOptions>();
        CLI::App* cmd = sky.add_subcommand(
            "predict",
            "Move the clouds of a sky forward with a trained cloud model (docs/networks.md): K recursive\n"
            "medium steps of Delta t (the model's, e.g. 30 s), xi(I) = CloudNet(I, FlowNet(I)). Writes\n"
            "DIR/step_0001.exr ... (canonical fisheye radiance; the sun of the input is kept).");
        cmd->add_option("--model", o->model, "Model folder (flownet.onnx, cloudnet.onnx, model.json), e.g. networks/models/arm_tsi_128")
            ->required();
        cmd->add_option("--in", o->in, "Input sky (canonical fisheye EXR, any resolution)")->required();
        cmd->add_option("--out", o->out, "Output folder (created if missing)")->required();
        cmd->add_option("--steps", o->steps, "Number of medium steps K (1..100000)")->capture_default_str();
        cmd->add_option("--every", o->every, "Write only every M-th step (and the last)")->capture_default_str();
        cmd->add_option("--stats", o->stats,
                        "CSV of per-step statistics (mean luminance, mean/min/max of the [0,1] form, cloud\n"
                        "coverage, high-frequency energy, non-finite pixel count), step 0 = the input");
        cmd->add_flag("--preview", o->preview, "Also write tone-mapped PNGs beside the EXRs (the input's auto exposure)");
        cmd->add_flag("--quiet", o->quiet, "No progress bar or summary");
        cmd->callback([o]() { run_predict(*o); });
    }
    {
        auto o = std::make_shared<EvaluateOptions>();
        CLI::App* cmd = sky.add_subcommand(
            "evaluate",
            "Score a cloud model on the held-out (last, in time) part of a real sequence against the\n"
            "persistence and Farneback-extrapolation baselines, in the same run: MSE, PSNR and SSIM per\n"
            "horizon, as a markdown table, plus a histogram of cloud motion (real vs rollout) as PNG.");
        cmd->add_option("--model", o->model, "Model folder (with split.json naming the held-out frames)")->required();
        cmd->add_option("--sequence", o->sequence, "Real sequence: arm-tsi (30 s) or mobotix (60 s)")->required();
        cmd->add_option("--horizons", o->horizons, "Steps ahead to score, comma-separated")->capture_default_str();
        cmd->add_option("--shared", o->shared, "The shared data folder (default: ../shared beside the source tree)");
        cmd->add_option("--report", o->report, "Markdown file to write")->capture_default_str();
        cmd->add_option("--histogram", o->histogram, "PNG of the flow-magnitude histogram")->capture_default_str();
        cmd->add_option("--import-res", o->import_resolution,
                        "Resolution the photographs are imported at before area-averaging to the model's\n"
                        "(default: the model's training value)");
        cmd->add_option("--limit", o->limit, "Score only the first K held-out start frames (0: all; for quick checks)")
            ->capture_default_str();
        cmd->add_flag("--quiet", o->quiet, "No progress bars; the table is still written");
        cmd->callback([o]() { run_evaluate(*o); });
    }
    {
        auto o = std::make_shared<TrainingDataOptions>();
        CLI::App* cmd = sky.add_subcommand(
            "training-data",
            "Build one sequence of a cloud-model training set (networks/dataset.py runs this): frames in the\n"
            "networks' [0, 1] form at --res, seen-sky and cloud masks, Farneback flow frame k -> k+1 and, for\n"
            "procedural sequences, the exact flow, as .npy files plus meta.json in --out.");
        cmd->add_option("--sequence", o->sequence, "Real sequence to import: arm-tsi or mobotix");
        cmd->add_option("--procedural", o->procedural, "Folder written by `dynsky sky procedural` (with manifest.json)");
        cmd->add_option("--shared", o->shared, "The shared data folder (default: ../shared beside the source tree)");
        cmd->add_option("--res", o->resolution, "Resolution N of the training images")->capture_default_str();
        cmd->add_option("--import-res", o->import_resolution,
                        "Resolution frames are imported (and Farneback flow computed) at; a multiple of --res")
            ->capture_default_str();
        cmd->add_option("--unit-scale", o->form.unit_map.scale,
                        "HDR -> [0, 1] log map (sky/hdr_recovery.h): radiance scale, W m^-2 sr^-1")
            ->capture_default_str();
        cmd->add_option("--unit-max", o->form.unit_map.max_radiance,
                        "HDR -> [0, 1] log map: radiance that maps to 1 (brighter clips; the sun is re-inserted on output)")
            ->capture_default_str();
        cmd->add_option("--cloud-rule", o->cloud_rule, "Cloud mask rule: rb (red / blue > t) or nbr ((b - r) / (b + r) < t)")
            ->capture_default_str();
        cmd->add_option("--cloud-threshold", o->form.cloud_rule.threshold, "Cloud mask threshold t")->capture_default_str();
        cmd->add_option("--out", o->out, "Output folder")->required();
        cmd->add_flag("--quiet", o->quiet, "No progress bars or summary");
        cmd->callback([o]() { run_training_data(*o); });
    }
}

}  // namespace dynsky::cli
