// The pace of the two in-betweens (motion/sky_timeline.h GammaKind), frame by frame: the cloud
// displacement between consecutive frames (Farneback, motion/flow.h, mean over the sky disc) and
// the second difference of the horizontal illuminance the sky gives a scene. Writes
// OUT/gamma-pace.csv; scripts/gamma_pace_chart.py draws docs/gamma-pace.png from it.
//
//   build/bench/gamma_pace [OUT=docs] [MODEL=paper] [SKY_RES=256]
// The sky: the procedural cumulus of `animate`'s defaults; the model: the paper's networks (their
// washed-out steps change brightness from step to step, as in issue 11), Delta t their own.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "frame/sky_source.h"
#include "motion/flow.h"
#include "sky/fisheye.h"
#include "util/atomic_file.h"
#include "util/parse.h"

using namespace dynsky;

namespace {

// Mean flow magnitude over the inner sky disc (r < 0.9), degrees (equidistant: n / 2 px = 90 deg).
double mean_displacement_deg(const SkyImage& a, const SkyImage& b) {
    cv::Mat f = estimate_sky_flow(a, b);
    const int n = a.resolution;
    double sum = 0;
    int count = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            double x = (i + 0.5) / n * 2 - 1, y = (j + 0.5) / n * 2 - 1;
            if (x * x + y * y > 0.81) continue;
            cv::Vec2f v = f.at<cv::Vec2f>(j, i);
            sum += std::hypot(v[0], v[1]), ++count;
        }
    return sum / std::max(count, 1) * 180.0 / n;
}

}  // namespace

int run(int argc, char** argv);

int main(int argc, char** argv) {
    if (argc > 1 && (std::string(argv[1]) == "-h" || std::string(argv[1]) == "--help")) {
        std::printf(
            "usage: gamma_pace [OUT=docs] [MODEL=paper] [SKY_RES=256]\n"
            "The pace of the constant and the paper's in-between over three medium steps: per-frame cloud\n"
            "displacement and the second difference of horizontal illuminance; writes OUT/gamma-pace.csv\n"
            "(scripts/gamma_pace_chart.py draws the chart).\n");
        return 0;
    }
    try {
        return run(argc, argv);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "gamma_pace: %s\n", e.what());
        return 1;
    }
}

int run(int argc, char** argv) {
    const std::string out = argc > 1 ? argv[1] : "docs";
    SkySourceSpec sky;
    sky.sky_resolution = argc > 3 ? int(parse_whole_number(argv[3], "SKY_RES", 16, 4096)) : 256;
    StepModelSpec model;
    model.model = argc > 2 ? argv[2] : "paper";
    const int intervals = 3, per_interval = 12;
    std::vector<double> times;
    std::vector<std::vector<double>> lux(2), moved(2);
    double dt = 0;
    for (int g = 0; g < 2; ++g) {
        model.gamma = g == 0 ? "constant" : "paper";
        SkyTimeline timeline = make_sky_timeline(sky, model);
        dt = timeline.dt();
        SkyImage previous;
        for (int k = 0; k <= intervals * per_interval; ++k) {
            double t = dt * k / per_interval;
            if (g == 0) times.push_back(t);
            SkyImage frame = timeline.sky_at(t);
            lux[g].push_back(horizontal_illuminance(frame));
            moved[g].push_back(k == 0 ? std::nan("") : mean_displacement_deg(previous, frame));
            previous = std::move(frame);
            std::fprintf(stderr, "%s t = %.2f s: %.0f lx\n", model.gamma.c_str(), t, lux[g].back());
        }
    }
    std::ostringstream csv;
    csv << "time_s,boundary,displacement_constant_deg,displacement_paper_deg,illuminance_constant_lx,"
           "illuminance_paper_lx,d2_illuminance_constant_lx,d2_illuminance_paper_lx\n";
    for (size_t k = 0; k < times.size(); ++k) {
        auto d2 = [&](int g) {
            return k == 0 || k + 1 == times.size() ? std::nan("") : lux[g][k + 1] - 2 * lux[g][k] + lux[g][k - 1];
        };
        csv << times[k] << ',' << (k % per_interval == 0 ? 1 : 0) << ',' << moved[0][k] << ',' << moved[1][k] << ','
            << lux[0][k] << ',' << lux[1][k] << ',' << d2(0) << ',' << d2(1) << '\n';
    }
    std::filesystem::create_directories(out);
    const std::string path = (std::filesystem::path(out) / "gamma-pace.csv").string();
    write_file_atomic(path, csv.str());
    std::printf("wrote %s (model %s, Delta t %g s, %d frames per interval)\n", path.c_str(), model.model.c_str(), dt,
                per_interval);
    return 0;
}
