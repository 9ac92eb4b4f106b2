#include "motion/prediction.h"

#include <cstdio>
#include <functional>
#include <memory>
#include <optional>
#include <filesystem>
#include <sstream>

#include "motion/advect_residual.h"
#include "motion/cloud_model.h"
#include "motion/network_step_model.h"
#include "motion/radiance_scale.h"
#include "sky/latlong.h"
#include "motion/sun_patch.h"
#include "util/data_path.h"
#include "motion/metrics.h"
#include "util/atomic_file.h"
#include "util/error.h"
#include "util/exposure.h"
#include "util/frame_names.h"
#include "util/parse.h"
#include "util/progress.h"

namespace dynsky {

namespace fs = std::filesystem;

void write_prediction(const PredictionOptions& given) {
    PredictionOptions o = given;
    if (o.in.empty()) throw Error("--sky: give the input sky (a canonical fisheye .exr)");
    // A captured or imported sequence (a folder of skies), as animate and compare take one: on from
    // its last sky, the one before it the previous frame (unless --prev or a wind is given).
    if (fs::is_directory(o.in)) {
        o.in = sequence_start(o.in, o.previous.empty() && !o.wind, &o.previous, o.quiet);
    }
    if (o.out.empty()) throw Error("--out: an output folder is required");
    if (o.steps < 1 || o.steps > 100000) throw Error("--steps: must be in 1..100000");
    if (o.every < 1) throw Error("--every: must be >= 1");
    if (fs::exists(o.out) && !fs::is_directory(o.out)) throw_file_error(o.out, "exists and is not a folder");
    const std::string folder = resolve_cloud_model(o.model);
    const bool advect_kind = folder == "advect" || cloud_model_kind(folder) == "advect-residual";
    std::optional<CloudModel> paper;
    std::optional<AdvectResidualNetwork> advect;
    if (advect_kind)
        advect = folder == "advect" ? AdvectResidualNetwork::pure_advection() : AdvectResidualNetwork::load(folder);
    else paper = CloudModel::load(folder);
    if (!advect_kind && (!o.previous.empty() || o.wind))
        throw Error("--prev and --wind-*: the paper's model (" + folder + ") takes its motion from the sky alone");
    // A 2:1 lat-long (a downloaded HDRI) is taken as render takes it: its upper half (the ground
    // does not move).
    std::shared_ptr<SkyImage> unused_ground;
    const SkyFileOptions taken{o.resolution, kMovingLatlongLimit, o.turn_deg};
    SkyImage sky = load_sky_or_latlong(o.in, &unused_ground, taken);
    if (unused_ground && !o.quiet)
        std::fprintf(stderr, "%s\n", moving_latlong_note(o.in, sky.resolution, o.resolution > 0).c_str());
    CloudMotion motion;
    motion.wind = o.wind;
    motion.previous_dt = o.previous_dt;
    if (!o.previous.empty()) {
        if (o.wind) throw Error("--prev and --wind-*: give one source of motion, not both");
        motion.previous = std::make_shared<const SkyImage>(load_sky_or_latlong(o.previous, &unused_ground, taken));
        motion.previous_dt = previous_frame_gap(sky, *motion.previous, o.previous_dt, o.in, o.previous);
        if (motion.previous_dt == 0 && !o.quiet)
            std::fputs(unknown_previous_gap_note(o.in, o.previous).c_str(), stderr);
        std::fputs(long_previous_gap_warning(motion.previous_dt, o.in, o.previous).c_str(), stderr);  // under -q too
    }
    // A sky in other units than the models' (motion/radiance_scale.h) moves divided by its scale; every
    // step is written multiplied back.
    const RadianceScale scale = bring_to_model_scale(&sky, &motion.previous);
    if (scale.apply && !o.quiet)
        std::fprintf(stderr,
                     "dynsky: note: %s is %s: its clouds are moved at the model's scale and the steps written "
                     "in its own units\n",
                     o.in.c_str(), scale.describe().c_str());
    const NetworkFormParams form = advect ? advect->info().form : paper->info().form;
    const int n = advect ? advect->info().resolution : paper->info().resolution;
    const double dt = advect ? advect->info().dt : paper->info().dt;
    // A sky smaller than the network is stepped at the network's resolution (upsampled) and each
    // step written at its own (area-averaged).
    const SkyImage work = advect && sky.resolution < n ? resampled_sky(sky, n) : SkyImage();
    const SkyImage& stepped = work.resolution > 0 ? work : sky;
    CloudFlow flow;
    if (advect) flow = advect->motion_flow(stepped, motion, dt, stepped.resolution);
    if (advect && flow.fitted_wind && !o.quiet)
        std::fprintf(stderr,
                     "dynsky: note: the motion measured from %s -> %s is a wind from %.0f deg at %.1f m/s (clouds "
                     "taken at %.0f m), the flow relaxing to it over %.0f steps\n",
                     o.previous.c_str(), o.in.c_str(), flow.fitted_wind->from_deg, flow.fitted_wind->speed_mps,
                     flow.fitted_wind->cloud_height_m, flow.relax_steps);
    if (advect && advect->has_network() && motion.previous && !o.quiet)
        std::fprintf(stderr,
                     "dynsky: note: the pair %s -> %s supports %.0f %% of the network's correction; the first step "
                     "takes that much (docs/networks-advect-residual.md)\n",
                     o.previous.c_str(), o.in.c_str(), 100 * flow.correction_gain);
    auto rollout = [&](const std::function<void(int, const SkyImage&)>& on_step) {
        if (!advect) return paper->rollout(sky, o.steps, on_step);
        advect->rollout(stepped, flow, o.steps, [&](int k, const SkyImage& s) {
            on_step(k, s.resolution == sky.resolution ? s : resampled_sky(s, sky.resolution));
        });
    };
    const cv::Mat disc = sky_disc_mask(n);
    const OutputFolder out_folder(o.out);  // removed again if this run fails before writing anything
    // Steps of an earlier run into the same folder are removed before the first is written: those
    // this run does not write (more steps, another --every) would read as this sky's future
    // (`animate --sky` took a stale one as its last frame), and a run stopped midway left the
    // earlier run's later steps after its own, and its --stats. Never this run's inputs (a
    // prediction continued from its own last step into its folder); one it would overwrite is refused.
    auto is_input = [&](const fs::path& p) {
        std::error_code ec;
        for (const std::string& input : {o.in, o.previous})
            if (!input.empty() && fs::exists(input, ec) && fs::equivalent(p, input, ec)) return true;
        return false;
    };
    // Only the skies and previews dynsky wrote (their header's dynsky:layout): files of the user's that
    // happen to be named step_NNNN (notes, holiday photos in `-o .`) were deleted too.
    auto is_sky_of_ours = [](const fs::path& p) {
        return !image_header_strings(p.string(), {"dynsky:layout"}).front().empty();
    };
    std::vector<fs::path> stale, foreign;
    for (const auto& e : fs::directory_iterator(o.out)) {
        const std::string ext = e.path().extension().string();
        const std::optional<int> k = numbered_index(e.path().string(), "step");
        if (!e.is_regular_file() || !k || (ext != ".exr" && ext != ".png")) continue;
        const bool written = *k >= 1 && *k <= o.steps && (*k % o.every == 0 || *k == o.steps) &&
                             (ext == ".exr" || o.preview);
        if (is_input(e.path())) {
            if (written)
                throw_file_error(e.path().string(),
                                 "is an input of this prediction and one of the steps it writes "
                                 "into " +
                                     o.out + "; refusing to overwrite it: move it or choose another --out");
        } else if (is_sky_of_ours(e.path())) {
            stale.push_back(e.path());
        } else {
            if (written)
                throw_file_error(e.path().string(),
                                 "is not a sky dynsky wrote, and this prediction would write over "
                                 "it: move it or choose another --out");
            foreign.push_back(e.path());
        }
    }
    for (const fs::path& p : stale) fs::remove(p);
    for (const fs::path& p : foreign)  // a warning: under -q too
        std::fprintf(stderr, "dynsky: warning: %s is named as a step but is not a sky dynsky wrote: left as it is\n",
                     p.string().c_str());
    if (!o.stats.empty()) remove_stale_marker(o.stats);
    if (!stale.empty() && !o.quiet)
        std::fprintf(stderr, "dynsky: note: removed %zu step file(s) of an earlier prediction from %s\n", stale.size(),
                     o.out.c_str());
    std::ostringstream csv;
    csv << "step,time_s,mean_luminance,mean_unit,min_unit,max_unit,cloud_coverage,hf_energy,"
           "mean_luminance_without_sun,nonfinite\n";
    // The start's sun (the pixels the networks' form clips, restored into every step and dimmed
    // when a cloud covers it): left out of the last column, which follows the clouds alone.
    cv::Mat sun_pixels;
    if (!o.stats.empty()) {
        cv::Mat start_form = to_network_form(sky, form);
        sun_pixels = fill_saturated_pixels(&start_form);
    }
    auto stats_row = [&](int k, const SkyImage& s) {
        double lum = 0, lum_without_sun = 0;
        long nonfinite = 0, count = 0, count_without_sun = 0;
        for (int j = 0; j < s.resolution; ++j)
            for (int i = 0; i < s.resolution; ++i) {
                if (!s.in_disc(i, j)) continue;
                Color c = s.pixel(i, j);
                if (!c.isFinite().all()) {
                    ++nonfinite;
                    continue;
                }
                lum += luminance(c), ++count;
                if (!sun_pixels.at<uint8_t>(j, i)) lum_without_sun += luminance(c), ++count_without_sun;
            }
        cv::Mat unit = to_network_form(s, form, n);
        cv::Mat finite_unit = unit.clone();
        cv::patchNaNs(finite_unit, 0.0);
        double mn, mx;
        cv::minMaxLoc(finite_unit.reshape(1), &mn, &mx, nullptr, nullptr, cv::repeat(disc, 1, 3).reshape(1, n));
        cv::Scalar mean = cv::mean(finite_unit, disc);
        double coverage = double(cv::countNonZero(network_cloud_mask(finite_unit, form) & disc)) /
                          cv::countNonZero(disc);
        char line[256];
        std::snprintf(line, sizeof line, "%d,%.3f,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%ld\n", k, s.time_seconds,
                      count ? lum / count : 0.0, (mean[0] + mean[1] + mean[2]) / 3, mn, mx, coverage,
                      high_frequency_energy(finite_unit, disc),
                      count_without_sun ? lum_without_sun / count_without_sun : 0.0, nonfinite);
        csv << line;
    };
    if (!o.stats.empty()) stats_row(0, sky);
    // One exposure for every preview (the input's), so they do not flicker.
    const float preview_ev = exposure_log_average(sky_to_image(sky));
    // What made each step, for its dynsky:source (the steps of two models had identical headers).
    std::string motion_text = "its own motion";
    if (advect) {
        char wind[160];
        const Wind w = o.wind.value_or(Wind{});
        std::snprintf(wind, sizeof wind, "%s wind %g m/s from %g deg at %g m", o.wind ? "a" : "the default",
                      w.speed_mps, w.from_deg, w.cloud_height_m);
        motion_text = motion.previous
                          ? "the motion from " + o.previous + " (" + number_text(motion.previous_dt) + " s before)"
                          : std::string(wind);
    }
    std::string taken_as;                   // how the input was taken, when not as it is
    if (o.resolution > 0 || unused_ground)  // asked, or a lat-long's own size (at most kMovingLatlongLimit)
        taken_as += ", taken at " + std::to_string(sky.resolution) + " px";
    if (o.turn_deg != 0) taken_as += ", turned " + number_text(o.turn_deg, 10) + " deg about the zenith";
    const std::string made_by = "dynsky sky predict from " + o.in + taken_as + " (" + sky.source + "), model " +
                                folder + ", Delta t " + number_text(dt) + " s, " + motion_text + ", step ";
    ProgressBar progress(o.steps, "predict", o.quiet);
    int written = 0;
    rollout([&](int k, const SkyImage& s) {
        if (k % o.every == 0 || k == o.steps) {
            std::string base = numbered_path(o.out, "step", k, "", o.steps + 1);
            // In the input's units (the statistics stay at the models' scale, where the form is defined).
            SkyImage given = s;
            given.source = made_by + std::to_string(k) + " of " + std::to_string(o.steps);
            if (scale.apply) scale_radiance(&given, scale.factor);
            save_sky(base + ".exr", given);
            if (o.preview) write_image(base + ".png", tonemap_to_display(sky_to_image(s), preview_ev));
            ++written;
        }
        if (!o.stats.empty()) stats_row(k, s);
        progress.advance();
    });
    progress.finish();
    if (!o.stats.empty()) write_file_atomic(o.stats, csv.str());
    if (!o.quiet)
        std::printf("wrote %d predicted sk%s (Delta t = %g s, %d step%s) to %s\n", written, written == 1 ? "y" : "ies",
                    dt, o.steps, o.steps == 1 ? "" : "s", o.out.c_str());
}

}  // namespace dynsky
