// dynsky compare: one frame under the clear sky and under the cloudy sky of the same sun position,
// side by side with a difference image, and the illuminance at chosen points over time.
// dynsky temporal: temporal quality of an animation folder (popping at medium-step boundaries,
// Monte Carlo flicker between frames).
#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <regex>
#include <sstream>

#include "cli/animation_support.h"
#include "cli/commands.h"
#include "util/exposure.h"
#include "renderer/integrator.h"
#include "sky/clear_sky.h"
#include "util/error.h"
#include "util/atomic_file.h"

namespace dynsky::cli {

namespace fs = std::filesystem;

namespace {

// Line chart of a CSV (first column = x, every other column a line) with matplotlib, via
// /usr/bin/python3. A column named "boundary" (0/1) shades those x instead of being drawn.
const char* kChartScript = R"PY(
import csv, sys
import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt
path, out, title, xlabel, ylabel, logy = sys.argv[1:7]
rows = list(csv.reader(open(path)))
head, data = rows[0], [[float(v) for v in r] for r in rows[1:]]
x = [r[0] for r in data]
fig, ax = plt.subplots(figsize=(9, 4.5), dpi=110)
for c in range(1, len(head)):
    if head[c] == 'boundary':
        for r in data:
            if r[c] > 0.5: ax.axvline(r[0], color='0.8', lw=6, zorder=0)
        continue
    ax.plot(x, [r[c] for r in data], marker='o', ms=3, label=head[c])
if logy == '1': ax.set_yscale('log')
ax.set_title(title); ax.set_xlabel(xlabel); ax.set_ylabel(ylabel); ax.grid(alpha=0.3); ax.legend(fontsize=8)
fig.tight_layout(); fig.savefig(out)
)PY";

void make_chart(const std::string& csv, const std::string& png, const std::string& title, const std::string& xlabel,
                const std::string& ylabel, bool logy) {
    std::string script = (fs::path(png).parent_path() / ".chart.py").string();
    std::ofstream(script) << kChartScript;
    std::string tmp = (fs::path(png).parent_path() / ".partial.chart.png").string();
    std::string cmd = "/usr/bin/python3 " + shell_quote(script) + " " + shell_quote(csv) + " " + shell_quote(tmp) + " " +
                      shell_quote(title) + " " + shell_quote(xlabel) + " " + shell_quote(ylabel) + (logy ? " 1" : " 0");
    int rc = std::system(cmd.c_str());
    fs::remove(script);
    if (rc != 0) {
        fs::remove(tmp);
        std::fprintf(stderr, "dynsky: warning: matplotlib chart %s failed (exit %d); the data is in %s\n", png.c_str(), rc, csv.c_str());
        return;
    }
    fs::rename(tmp, png);
}

Image render_frame(const Accel& accel, EnvLight& light, const Camera& camera, std::shared_ptr<const SkyImage> sky, int w, int h,
                   int spp, uint64_t seed) {
    light.set_sky(std::move(sky));
    RenderSettings s;
    s.width = w, s.height = h, s.spp = spp, s.seed = seed, s.quiet = true;
    PathIntegrator integrator(accel, light, s);
    return integrator.render(camera).color;
}

// Mean luminance (cd m^-2 = 683 Y) of a (2r+1)^2 window around pixel (x, y).
double window_luminance(const Image& im, int x, int y, int r = 2) {
    double sum = 0;
    int n = 0;
    for (int j = std::max(0, y - r); j <= std::min(im.height - 1, y + r); ++j)
        for (int i = std::max(0, x - r); i <= std::min(im.width - 1, x + r); ++i) {
            const float* p = &im.pixels[(size_t(j) * im.width + i) * im.channels];
            sum += 683.0 * luminance(Color(p[0], p[1], p[2])), ++n;
        }
    return sum / std::max(n, 1);
}

struct CompareOptions {
    SceneOptions scene;
    SkySourceOptions sky;
    std::string resolution = "640x360";
    int spp = 32;
    std::string out = "compare";
    std::string points = "0.5,0.3;0.25,0.75;0.75,0.75";
    double duration = 60.0;
    int chart_frames = 13;
    std::string chart_resolution = "160x90";
    int chart_spp = 8;
    uint64_t seed = 0;
    int threads = 0;
};

std::vector<std::pair<double, double>> parse_points(const std::string& text) {
    std::vector<std::pair<double, double>> out;
    std::stringstream ss(text);
    std::string item;
    std::regex re("^\\s*([0-9.]+)\\s*,\\s*([0-9.]+)\\s*$");
    while (std::getline(ss, item, ';')) {
        std::smatch m;
        if (!std::regex_match(item, m, re)) throw Error("--points '" + text + "': expected X,Y;X,Y;... with X, Y in [0, 1]");
        double x = std::stod(m[1]), y = std::stod(m[2]);
        if (x > 1 || y > 1) throw Error("--points '" + text + "': coordinates are fractions of the image, in [0, 1]");
        out.emplace_back(x, y);
    }
    if (out.empty()) throw Error("--points: give at least one point");
    return out;
}

int run_compare(const CompareOptions& o) {
    int w, h, cw, ch;
    parse_frame_size(o.resolution, &w, &h);
    parse_frame_size(o.chart_resolution, &cw, &ch);
    if (o.spp < 1 || o.chart_spp < 1) throw Error("--spp and --chart-spp must be at least 1");
    if (o.chart_frames < 2) throw Error("--chart-frames must be at least 2");
    if (!(o.duration > 0)) throw Error("--duration must be positive");
    auto points = parse_points(o.points);
    std::unique_ptr<tbb::global_control> threads;
    if (o.threads > 0) threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, o.threads);

    SkySourceOptions so = o.sky;
    if (so.time.empty()) throw Error("--time is required: the clear and cloudy skies share the sun of that moment");
    SkyTimeline cloudy = make_sky_timeline(so);
    LoadedScene scene = load_scene(o.scene, float(w) / h);
    fs::create_directories(o.out);
    const UtcTime t0 = start_time(so);
    const GeoLocation where{so.latitude, so.longitude, 0};
    const int sky_n = cloudy.step(0)->resolution;
    auto clear_at = [&](double t) {
        ClearSkyParams p;
        p.sun_direction = compute_sun_position(add_seconds(t0, t), where).direction();
        p.turbidity = 3;
        auto s = std::make_shared<SkyImage>(make_clear_sky(p, sky_n));
        s->time_seconds = t;
        return s;
    };

    Accel accel(scene.scene);
    EnvLight light(o.scene.ground_albedo);
    auto clear0 = clear_at(0.0);
    auto cloudy0 = std::make_shared<const SkyImage>(cloudy.sky_at(0.0));
    Image a = render_frame(accel, light, scene.camera, clear0, w, h, o.spp, o.seed);
    float ev = exposure_for_irradiance(light.sky_irradiance());
    Color e_clear = light.sky_irradiance();
    Image b = render_frame(accel, light, scene.camera, cloudy0, w, h, o.spp, o.seed);
    Color e_cloudy = light.sky_irradiance();
    write_image((fs::path(o.out) / "clear.exr").string(), a);
    write_image((fs::path(o.out) / "cloudy.exr").string(), b);
    Image da = tonemap_to_display(a, ev), db = tonemap_to_display(b, ev);
    Image side;
    side.width = 2 * w + 8, side.height = h, side.channels = 3;
    side.pixels.assign(size_t(side.width) * h * 3, 1.0f);
    Image diff = side;
    diff.width = w;
    diff.pixels.assign(size_t(w) * h * 3, 0.0f);
    cv::Mat ratio8(h, w, CV_8UC1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            for (int c = 0; c < 3; ++c) {
                side.pixels[(size_t(y) * side.width + x) * 3 + c] = da.pixels[(size_t(y) * w + x) * da.channels + c];
                side.pixels[(size_t(y) * side.width + x + w + 8) * 3 + c] = db.pixels[(size_t(y) * w + x) * db.channels + c];
            }
            const float* pa = &a.pixels[(size_t(y) * w + x) * a.channels];
            const float* pb = &b.pixels[(size_t(y) * w + x) * b.channels];
            double la = luminance(Color(pa[0], pa[1], pa[2])), lb = luminance(Color(pb[0], pb[1], pb[2]));
            // log2(cloudy / clear) in [-3, 3] stops -> 0..255 (128: no change)
            double stops = std::log2((lb + 1e-6) / (la + 1e-6));
            ratio8.at<uint8_t>(y, x) = uint8_t(std::lround(std::clamp(128.0 + stops / 3.0 * 127.0, 0.0, 255.0)));
        }
    cv::Mat coloured;
    cv::applyColorMap(ratio8, coloured, cv::COLORMAP_TWILIGHT_SHIFTED);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            cv::Vec3b p = coloured.at<cv::Vec3b>(y, x);  // BGR
            for (int c = 0; c < 3; ++c) diff.pixels[(size_t(y) * w + x) * 3 + c] = p[2 - c] / 255.0f;
        }
    write_image((fs::path(o.out) / "side_by_side.png").string(), side);
    write_image((fs::path(o.out) / "difference.png").string(), diff);
    std::fprintf(stderr,
                 "wrote %s/side_by_side.png (clear | cloudy, same exposure %.2f EV) and difference.png (log2 cloudy/clear, "
                 "-3..+3 stops, colormap TWILIGHT_SHIFTED: mid = no change)\n"
                 "global horizontal illuminance at t=0: clear %.0f lx, cloudy %.0f lx\n",
                 o.out.c_str(), ev, 683.0 * luminance(e_clear), 683.0 * luminance(e_cloudy));

    // Illuminance over time at the chosen points, under both skies (the sun follows the clock).
    std::string csv = (fs::path(o.out) / "illuminance.csv").string();
    {
        std::ostringstream f;  // written whole at the end: a stopped run leaves no half table
        f << "time_s,clear sky horizontal (lx / 100),cloudy sky horizontal (lx / 100)";
        for (size_t p = 0; p < points.size(); ++p) f << ",cloudy point " << p + 1 << " (cd/m2),clear point " << p + 1 << " (cd/m2)";
        f << '\n';
        for (int k = 0; k < o.chart_frames; ++k) {
            double t = o.duration * k / (o.chart_frames - 1);
            Image ic = render_frame(accel, light, scene.camera, clear_at(t), cw, ch, o.chart_spp, o.seed);
            double ec = 683.0 * luminance(light.sky_irradiance());
            Image iy = render_frame(accel, light, scene.camera, std::make_shared<const SkyImage>(cloudy.sky_at(t)), cw, ch,
                                    o.chart_spp, o.seed);
            double ey = 683.0 * luminance(light.sky_irradiance());
            f << t << ',' << ec / 100 << ',' << ey / 100;
            for (auto [px, py] : points) {
                int x = std::min(cw - 1, int(px * cw)), y = std::min(ch - 1, int(py * ch));
                f << ',' << window_luminance(iy, x, y) << ',' << window_luminance(ic, x, y);
            }
            f << '\n';
            std::fprintf(stderr, "chart frame %d/%d (t = %.1f s)\n", k + 1, o.chart_frames, t);
        }
        write_file_atomic(csv, f.str());
    }
    make_chart(csv, (fs::path(o.out) / "illuminance.png").string(),
               "Clear vs cloudy sky: illuminance and luminance at chosen points", "time (s)", "lux / 100, cd/m^2", true);
    std::fprintf(stderr, "wrote %s and illuminance.png\n", csv.c_str());
    return 0;
}

struct TemporalOptions {
    std::string folder;
};

std::vector<std::string> frame_files(const std::string& dir) {
    std::vector<std::string> out;
    std::regex re("^frame_[0-9]{4}\\.exr$");
    for (const auto& e : fs::directory_iterator(dir))
        if (std::regex_match(e.path().filename().string(), re)) out.push_back(e.path().string());
    std::sort(out.begin(), out.end());
    return out;
}

int run_temporal(const TemporalOptions& o) {
    if (!fs::is_directory(o.folder)) throw_file_error(o.folder, "not a folder (give the --out folder of 'dynsky animate')");
    auto files = frame_files(o.folder);
    if (files.size() < 3) throw_file_error(o.folder, "needs at least 3 frame_NNNN.exr files");
    std::string csv = (fs::path(o.folder) / "temporal.csv").string();
    std::ostringstream f;  // written whole once every frame is read: a bad frame leaves no table
    f << "time_s,relative change (%),boundary\n";
    Image prev = read_image(files[0]);
    double sum_b = 0, sum_w = 0;
    int nb = 0, nw = 0;
    for (size_t k = 1; k < files.size(); ++k) {
        Image cur = read_image(files[k]);
        if (cur.width != prev.width || cur.height != prev.height) throw_file_error(files[k], "size differs from the previous frame");
        double t0 = prev.metadata.numbers["dynsky:time"], t1 = cur.metadata.numbers["dynsky:time"];
        double dt = cur.metadata.numbers["dynsky:medium_step_seconds"];
        double num = 0, den = 0;
        for (size_t p = 0; p < cur.pixels.size(); p += size_t(cur.channels)) {
            double la = luminance(Color(prev.pixels[p], prev.pixels[p + 1], prev.pixels[p + 2]));
            double lb = luminance(Color(cur.pixels[p], cur.pixels[p + 1], cur.pixels[p + 2]));
            num += std::abs(lb - la), den += 0.5 * (la + lb);
        }
        double change = 100.0 * num / std::max(den, 1e-12);
        // The pair straddles (or ends on) a medium-step boundary i * Delta t.
        bool boundary = dt > 0 && std::floor(t1 / dt + 1e-9) > std::floor(t0 / dt + 1e-9);
        (boundary ? sum_b : sum_w) += change;
        (boundary ? nb : nw) += 1;
        f << t1 << ',' << change << ',' << (boundary ? 1 : 0) << '\n';
        prev = std::move(cur);
    }
    write_file_atomic(csv, f.str());
    make_chart(csv, (fs::path(o.folder) / "temporal.png").string(),
               "Frame-to-frame change (shaded: pairs across a medium-step boundary)", "time of the later frame (s)",
               "mean |dL| / L (%)", false);
    std::printf("frames: %zu; mean frame-to-frame luminance change: across medium-step boundaries %.3f%% (%d pairs), "
                "within intervals %.3f%% (%d pairs); ratio %.2f\n",
                files.size(), nb ? sum_b / nb : 0.0, nb, nw ? sum_w / nw : 0.0, nw,
                (nb && nw && sum_w > 0) ? (sum_b / nb) / (sum_w / nw) : 0.0);
    std::printf("wrote %s and temporal.png\n", csv.c_str());
    return 0;
}

}  // namespace

void register_compare_command(CLI::App& app) {
    auto o = std::make_shared<CompareOptions>();
    CLI::App* cmd = app.add_subcommand(
        "compare",
        "The same frame under the clear sky and the cloudy sky of the same sun position: side_by_side.png, difference.png,\n"
        "clear.exr, cloudy.exr, and illuminance.csv/.png (sky illuminance and luminance at chosen points over time)");
    add_scene_options(cmd, &o->scene);
    add_sky_source_options(cmd, &o->sky);
    cmd->add_option("--res", o->resolution, "Size of the side-by-side frames, WIDTHxHEIGHT")->capture_default_str();
    cmd->add_option("--spp", o->spp, "Samples per pixel of the side-by-side frames")->capture_default_str();
    cmd->add_option("--out,-o", o->out, "Output folder")->capture_default_str();
    cmd->add_option("--points", o->points, "Chart points as fractions of the image: X,Y;X,Y;... (0,0 = top left)")->capture_default_str();
    cmd->add_option("--duration", o->duration, "Chart: seconds of sky time")->capture_default_str();
    cmd->add_option("--chart-frames", o->chart_frames, "Chart: frames rendered over --duration")->capture_default_str();
    cmd->add_option("--chart-res", o->chart_resolution, "Chart: frame size")->capture_default_str();
    cmd->add_option("--chart-spp", o->chart_spp, "Chart: samples per pixel (the same seed every frame)")->capture_default_str();
    cmd->add_option("--seed", o->seed, "Random seed")->capture_default_str();
    cmd->add_option("--threads", o->threads, "Worker threads (0: all cores)")->capture_default_str();
    cmd->callback([o] { run_compare(*o); });

    auto t = std::make_shared<TemporalOptions>();
    CLI::App* tc = app.add_subcommand(
        "temporal",
        "Temporal quality of a 'dynsky animate' folder: frame-to-frame luminance change, pairs across medium-step\n"
        "boundaries vs within intervals (popping), charted to temporal.png with temporal.csv. Run it on animations\n"
        "rendered with and without --seed-per-frame to measure Monte Carlo flicker");
    tc->add_option("folder", t->folder, "The animation folder (frame_NNNN.exr with their metadata)")->required();
    tc->callback([t] { run_temporal(*t); });
}

}  // namespace dynsky::cli
