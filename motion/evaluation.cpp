#include "motion/evaluation.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "motion/advection.h"
#include "motion/cloud_model.h"
#include "motion/flow.h"
#include "motion/metrics.h"
#include "motion/photo_sequence.h"
#include "util/atomic_file.h"
#include "util/error.h"
#include "util/image.h"
#include "util/json_file.h"
#include "util/math.h"
#include "util/parse.h"
#include "util/progress.h"

namespace dynsky {

namespace {

namespace fs = std::filesystem;

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
                    {left + pw - 430, top + 25 + 22 * int(s)}, cv::FONT_HERSHEY_SIMPLEX, 0.55, colours[s % 3], 1,
                    cv::LINE_AA);
    }
    for (int k = 0; k <= 4; ++k) {
        char label[32];
        std::snprintf(label, sizeof label, "%.2g", max_value * k / 4);
        int x = left + k * pw / 4;
        cv::line(img, {x, top + ph}, {x, top + ph + 6}, cv::Scalar(0, 0, 0));
        cv::putText(img, label, {x - 12, top + ph + 24}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1,
                    cv::LINE_AA);
    }
    cv::putText(img, title, {left, 32}, cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    cv::putText(img, xlabel, {left + pw / 2 - 160, h - 18}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1,
                cv::LINE_AA);
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

}  // namespace

void evaluate_cloud_model(const EvaluationOptions& o) {
    const std::vector<int> horizons = parse_int_list(o.horizons, "--horizons");
    PhotoSequence seq = named_photo_sequence(o.sequence, o.shared.empty() ? default_shared_dir() : o.shared);
    CloudModel model = CloudModel::load(o.model);
    const CloudModelInfo& info = model.info();
    const std::string split_path = (fs::path(o.model) / "split.json").string();
    nlohmann::json split = read_json(split_path);
    if (!split.contains(seq.name))
        throw_file_error(split_path, "has no split for sequence '" + seq.name + "': the model was not trained on it");
    const int lo = split[seq.name].at("heldout").at(0).get<int>();
    int hi = split[seq.name].at("heldout").at(1).get<int>();
    if (lo < 1 || hi > int(seq.photos.size()) || hi - lo < 2)
        throw_file_error(split_path,
                         "held-out range does not fit the sequence's " + std::to_string(seq.photos.size()) + " frames");
    if (std::abs(seq.dt - info.dt) > 1e-6)
        throw Error("the model steps " + std::to_string(info.dt) + " s but the sequence's cadence is " +
                    std::to_string(seq.dt) + " s");
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
    cv::Mat flow = lo + hmax < hi ? flow_at_resolution(farneback_flow(frame_big(lo - 1).image, frame_big(lo).image), n)
                                  : cv::Mat();
    for (int t = lo; t + hmax < hi; ++t) {
        cv::Mat next_flow = flow_at_resolution(farneback_flow(frame_big(t).image, frame_big(t + 1).image), n);
        append_magnitudes(next_flow, frame(t).cloud & frame(t).valid & frame(t + 1).valid, &real_mag);
        cv::Mat state = frame(t).image;
        for (int h = 1; h <= hmax; ++h) {
            NetworkStep s = model.step_network(state);
            if (h == 1) append_magnitudes(model.decode_flow(s.flow), frame(t).cloud & frame(t).valid, &flownet_mag);
            append_magnitudes(farneback_flow(state, s.next), network_cloud_mask(state, info.form) & frame(t).valid,
                              &rollout_mag);
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
                  lo, hi - 1, seq.photos.size(), info.dt, n, n, hmax, big);
    md << line;
    md << "| horizon | ahead | model PSNR | model SSIM | persistence PSNR | persistence SSIM | Farneback PSNR | "
          "Farneback SSIM | model MSE | persistence MSE | Farneback MSE | frames |\n";
    md << "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (int h : horizons) {
        std::snprintf(line, sizeof line,
                      "| %d | %g s | %.2f dB | %.3f | %.2f dB | %.3f | %.2f dB | %.3f | %.5f | %.5f | %.5f | %zu |\n",
                      h, h * info.dt, Scores::mean(sm[h].psnr), Scores::mean(sm[h].ssim),
                      Scores::mean(sp[h].psnr), Scores::mean(sp[h].ssim), Scores::mean(sf[h].psnr),
                      Scores::mean(sf[h].ssim), Scores::mean(sm[h].mse), Scores::mean(sp[h].mse),
                      Scores::mean(sf[h].mse), sm[h].psnr.size());
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
                   {{"real frames (Farneback)", real_mag},
                    {"model rollout (Farneback)", rollout_mag},
                    {"FlowNet output", flownet_mag}});
    write_file_atomic(o.report, md.str());
    if (!o.quiet) std::printf("%s\nwrote %s and %s\n", md.str().c_str(), o.report.c_str(), o.histogram.c_str());
}

}  // namespace dynsky
