// The sun dimmed by passing clouds over many procedural skies (docs/animation.md, "The sun and
// passing clouds"): frozen cumulus under a steady wind, moved by pure advection along the same
// wind (the `advect` model), the horizontal illuminance of the moved sky with its sun put back
// against the procedural sky's own, frame by frame. The seeds are chosen by a rule, not by how
// they fare: the first `crossing` seeds whose sun starts clear and is covered within the run, and
// the first `clearing` seeds whose sun starts covered and comes out. Writes OUT/sun-seeds.csv
// (one row a frame) and prints per-seed worst and mean errors; scripts/sun_seeds_chart.py draws
// OUT/sun-seeds.png from the CSV.
//
//   build/bench/sun_seeds [OUT=docs] [CROSSING=14] [CLEARING=6] [PNG_SEED=0] [RES=128]
// PNG_SEED > 0: also writes OUT/sun-seed-S/ crops of the sky around the sun (truth, moved, the
// carried opacity) for that seed, to look at.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "motion/network_step_model.h"
#include "motion/sky_timeline.h"
#include "motion/sun_patch.h"
#include "sky/clear_sky.h"
#include "sky/fisheye.h"
#include "sky/procedural_clouds.h"
#include "tests/sky/frozen_cumulus.h"
#include "util/atomic_file.h"
#include "util/error.h"
#include "util/parse.h"

using namespace dynsky;
namespace fs = std::filesystem;

namespace {

constexpr double kDuration = 120, kDt = 10, kFrame = 5;

// The sun tests' sky (tests/sky/frozen_cumulus.h), so the bench's seeds are theirs.
ProceduralSkyParams cumulus(uint64_t seed) { return test::frozen_cumulus(seed); }

// 1: the sun starts clear and is covered within the run; 2: starts covered and comes out; 0: neither.
int kind_of(const ProceduralSkyParams& p) {
    ProceduralSky sky(p);
    const double t0 = sky.sun_transmittance(0);
    for (double t = kDt; t <= kDuration; t += kDt) {
        const double tt = sky.sun_transmittance(t);
        if (t0 >= 0.95 && tt < 0.1) return 1;
        if (t0 < 0.1 && tt >= 0.95) return 2;
    }
    return 0;
}

// A crop of +-20 degrees around the sun, log-scaled to 8 bits (1 stop a 20th of the range) and
// enlarged 4x; the sun's pixel marked.
void write_crop(const std::string& path, const SkyImage& sky, const Vec3d& sun) {
    double sx, sy;
    fisheye::pixel_from_direction(sun, sky.resolution, &sx, &sy);
    const int r = int(std::ceil(20.0 / 90 * sky.resolution / 2));
    cv::Mat out(2 * r + 1, 2 * r + 1, CV_8UC3, cv::Scalar::all(0));
    for (int y = -r; y <= r; ++y)
        for (int x = -r; x <= r; ++x) {
            const int i = int(sx) + x, j = int(sy) + y;
            if (i < 0 || j < 0 || i >= sky.resolution || j >= sky.resolution || !sky.in_disc(i, j)) continue;
            const Color c = sky.pixel(i, j);
            for (int k = 0; k < 3; ++k) {
                const double v = std::log2(std::max(double(c[k]), 1.0)) / 16.0;  // 1 .. 65536 W
                out.at<cv::Vec3b>(y + r, x + r)[2 - k] = cv::saturate_cast<uint8_t>(255 * v);
            }
        }
    cv::resize(out, out, cv::Size(), 4, 4, cv::INTER_NEAREST);
    cv::imwrite(path, out);
}

void write_opacity(const std::string& path, const cv::Mat& opacity, const Vec3d& sun) {
    if (opacity.empty()) return;
    double sx, sy;
    fisheye::pixel_from_direction(sun, opacity.rows, &sx, &sy);
    const int r = int(std::ceil(20.0 / 90 * opacity.rows / 2));
    cv::Mat out(2 * r + 1, 2 * r + 1, CV_8UC1, cv::Scalar(0));
    for (int y = -r; y <= r; ++y)
        for (int x = -r; x <= r; ++x) {
            const int i = int(sx) + x, j = int(sy) + y;
            if (i < 0 || j < 0 || i >= opacity.cols || j >= opacity.rows) continue;
            out.at<uint8_t>(y + r, x + r) = cv::saturate_cast<uint8_t>(255 * opacity.at<float>(j, i));
        }
    cv::resize(out, out, cv::Size(), 4, 4, cv::INTER_NEAREST);
    cv::imwrite(path, out);
}

}  // namespace

int run(int argc, char** argv) {
    const fs::path out_dir = argc > 1 ? argv[1] : "docs";
    const int want_crossing = argc > 2 ? int(parse_whole_number(argv[2], "CROSSING", 0, 200)) : 14;
    const int want_clearing = argc > 3 ? int(parse_whole_number(argv[3], "CLEARING", 0, 200)) : 6;
    if (want_crossing + want_clearing == 0) throw Error("CROSSING and CLEARING: give at least one seed to measure");
    const uint64_t png_seed = argc > 4 ? uint64_t(parse_whole_number(argv[4], "PNG_SEED", 0, 999)) : 0;
    const int res = argc > 5 ? int(parse_whole_number(argv[5], "RES", 32, 2048)) : 128;  // the skies'
    fs::create_directories(out_dir);
    std::vector<std::pair<uint64_t, int>> seeds;
    int crossing = 0, clearing = 0;
    for (uint64_t seed = 1; seed < 1000 && (crossing < want_crossing || clearing < want_clearing); ++seed) {
        const int k = kind_of(cumulus(seed));
        if (k == 1 && crossing < want_crossing) seeds.push_back({seed, k}), ++crossing;
        if (k == 2 && clearing < want_clearing) seeds.push_back({seed, k}), ++clearing;
    }
    if (png_seed) seeds = {{png_seed, kind_of(cumulus(png_seed))}};
    // Written once every seed is done (atomically: never a half-written table).
    std::ostringstream csv;
    csv << "seed,kind,t_s,truth_lx,moved_lx,truth_sun_T,sun_weight,undimmed_lx\n";
    double sum_worst = 0, sum_mean = 0;
    for (auto [seed, kind] : seeds) {
        const ProceduralSkyParams p = cumulus(seed);
        ProceduralSky truth(p);
        SkyImage input = truth.render(0, res);
        CloudMotion motion;
        motion.wind = Wind{p.layers[0].wind_from_deg, p.layers[0].wind_speed_mps, p.layers[0].altitude_m};
        std::unique_ptr<MediumStepModel> model = make_network_step_model("advect", motion);
        const MediumStepModel* raw = model.get();
        SkyTimeline timeline(input, std::move(model), kDt);
        SkyImage cut = input;
        remove_sun(&cut);
        const double sun_lx = horizontal_illuminance(input) - horizontal_illuminance(cut);
        const Vec3d sun = p.clear_sky.sun_direction;
        const fs::path png_dir = out_dir / ("sun-seed-" + std::to_string(seed));
        if (png_seed) {
            fs::create_directories(png_dir);
            // The start's pixels within 15 degrees of the sun: the truth's cloud opacity against
            // what their look says (radiance relative to the clear sky).
            Image flow;
            const SkyImage s0 = truth.render(0, res, &flow, 1.0);
            ClearSkyParams cp;
            cp.sun_direction = sun;
            cp.sun_disc = false;
            const ClearSkyModel clear(cp, false);
            std::ofstream px(png_dir / "pixels.csv");
            px << "i,j,angle_deg,alpha,r,g,b,cr,cg,cb,cloudiness\n";
            for (int j = 0; j < res; ++j)
                for (int i = 0; i < res; ++i) {
                    if (!s0.in_disc(i, j)) continue;
                    const Vec3d w = fisheye::direction_from_pixel(i, j, res);
                    const double a = std::acos(std::clamp(w.dot(sun), -1.0, 1.0)) * 180 / kPiD;
                    if (a > 30) continue;
                    const Color v = s0.pixel(i, j), m = clear.sky_radiance(w);
                    px << i << ',' << j << ',' << a << ',' << flow.at(i, j, 2) << ',' << v[0] << ',' << v[1] << ','
                       << v[2] << ',' << m[0] << ',' << m[1] << ',' << m[2] << ',' << cloudiness(v, m) << '\n';
                }
        }
        double worst = 0, sum = 0, t_cover = -1;
        int frames = 0;
        for (double t = 0; t <= kDuration + 1e-9; t += kFrame) {
            const SkyImage want_sky = truth.render(t, res);
            const SkyImage frame = timeline.sky_at(t);
            const double want = horizontal_illuminance(want_sky), got = horizontal_illuminance(frame);
            const double w = timeline.last_sun_weight(), undimmed = got + (1 - w) * sun_lx,
                         err = std::abs(got / want - 1);
            worst = std::max(worst, err), sum += err, ++frames;
            if (t_cover < 0 && (truth.sun_transmittance(t) < 0.5) != (kind == 2)) t_cover = t;
            char row[256];
            std::snprintf(row, sizeof row, "%llu,%d,%.0f,%.1f,%.1f,%.4f,%.4f,%.1f\n", (unsigned long long)seed, kind, t,
                          want, got, truth.sun_transmittance(t), w, undimmed);
            csv << row;
            if (png_seed) {
                char name[64];
                std::snprintf(name, sizeof name, "%03d", int(t));
                write_crop((png_dir / (std::string("truth_") + name + ".png")).string(), want_sky, sun);
                write_crop((png_dir / (std::string("moved_") + name + ".png")).string(), frame, sun);
                if (std::fmod(t, kDt) < 1e-9) {
                    const cv::Mat o = t == 0 ? raw->input_cloud_opacity() : raw->last_cloud_opacity();
                    write_opacity((png_dir / (std::string("opacity_") + name + ".png")).string(), o, sun);
                    std::printf("  T(opacity) %.2f  T(start opacity) %.2f  T(look) %.2f\n",
                                sun_transmittance_of_opacity(o, sun),
                                sun_transmittance_of_opacity(raw->input_cloud_opacity(), sun),
                                estimate_sun_transmittance(frame, sun));
                }
                std::printf("t %5.1f  truth %7.0f lx T %.2f  moved %7.0f lx weight %.2f\n", t, want,
                            truth.sun_transmittance(t), got, w);
            }
        }
        sum_worst += worst, sum_mean += sum / frames;
        std::printf("seed %3llu %-8s (sun %s at %3.0f s): worst %6.1f %%  mean %5.1f %%\n", (unsigned long long)seed,
                    kind == 1 ? "crossing" : "clearing", kind == 1 ? "covered" : "clear", t_cover, 100 * worst,
                    100 * sum / frames);
        std::fflush(stdout);
    }
    std::printf("%zu seeds: mean of worst %.1f %%, mean of means %.1f %%\n", seeds.size(),
                100 * sum_worst / seeds.size(), 100 * sum_mean / seeds.size());
    write_file_atomic((out_dir / (png_seed ? "sun-seed.csv" : "sun-seeds.csv")).string(), csv.str());
    return 0;
}

int main(int argc, char** argv) {
    if (argc > 1 && (std::string(argv[1]) == "-h" || std::string(argv[1]) == "--help")) {
        std::printf(
            "usage: sun_seeds [OUT=docs] [CROSSING=14] [CLEARING=6] [PNG_SEED=0] [RES=128]\n"
            "The moved sky's horizontal illuminance against the procedural truth on the first CROSSING seeds\n"
            "whose sun starts clear and is covered, and the first CLEARING whose sun starts covered and comes\n"
            "out; writes OUT/sun-seeds.csv (scripts/sun_seeds_chart.py draws the chart). PNG_SEED > 0: that\n"
            "seed alone, with crops of the sky around the sun in OUT/sun-seed-S/. RES: the skies' resolution.\n");
        return 0;
    }
    try {
        return run(argc, argv);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "sun_seeds: %s\n", e.what());
        return 1;
    }
}
