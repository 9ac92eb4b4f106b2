// dynsky animate: a lit scene under a moving sky, frame by frame, resumable.
//
// Every frame is a pure function of (scene, sky input, model, Delta t, frame time, seed): the
// medium steps are always computed from step 0 in order, and the path tracer's image depends only
// on its seed. So a frame range rendered alone, or a run resumed after being killed, gives the
// same pixels as one uninterrupted run. Frames are written atomically (util/image.h) and a frame
// counts as done when its EXR, PNG and sky PNG all exist.
#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <regex>

#include "cli/animation_support.h"
#include "cli/commands.h"
#include "renderer/integrator.h"
#include "util/error.h"
#include "util/exposure.h"

namespace dynsky::cli {

namespace fs = std::filesystem;

namespace {

struct AnimateOptions {
    SceneOptions scene;
    SkySourceOptions sky;
    double duration = 4.0;
    double fps = 12.0;
    int spp = 16;
    std::string resolution = "480x270";
    std::string out = "animation";
    std::string frames;
    uint64_t seed = 0;
    bool seed_per_frame = false;
    int threads = 0;
    int max_depth = 8;
    float exposure = std::numeric_limits<float>::quiet_NaN();
    bool no_video = false;
    bool quiet = false;
};

std::string frame_name(const std::string& dir, const char* prefix, int k, const char* ext) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s_%04d%s", prefix, k, ext);
    return (fs::path(dir) / buf).string();
}

bool frame_complete(const std::string& dir, int k) {
    return fs::exists(frame_name(dir, "frame", k, ".exr")) && fs::exists(frame_name(dir, "frame", k, ".png")) &&
           fs::exists(frame_name(dir, "sky", k, ".png"));
}

// ffmpeg (Debian's) through a subprocess, to a temporary name renamed when complete.
bool make_video(const std::string& dir, const char* prefix, double fps, const std::string& out, bool quiet) {
    std::string tmp = (fs::path(dir) / (std::string(".partial.") + fs::path(out).filename().string())).string();
    std::string pattern = (fs::path(dir) / (std::string(prefix) + "_%04d.png")).string();
    char rate[32];
    std::snprintf(rate, sizeof rate, "%g", fps);
    std::string cmd = "ffmpeg -y -loglevel error -framerate " + std::string(rate) + " -i " + shell_quote(pattern) +
                      " -vf 'scale=trunc(iw/2)*2:trunc(ih/2)*2' -c:v libx264 -pix_fmt yuv420p -crf 18 " + shell_quote(tmp) +
                      " </dev/null";
    int rc = std::system(cmd.c_str());
    if (rc != 0) {
        std::fprintf(stderr, "dynsky: warning: ffmpeg failed (exit %d) making %s; is ffmpeg installed?\n", rc, out.c_str());
        fs::remove(tmp);
        return false;
    }
    fs::rename(tmp, out);
    if (!quiet) std::fprintf(stderr, "wrote %s\n", out.c_str());
    return true;
}

// Up to 12 frames, evenly spaced, in a grid of 4 columns, each 320 pixels wide.
void make_contact_sheet(const std::string& dir, int total, const std::string& out) {
    int count = std::min(total, 12), columns = std::min(count, 4), rows = (count + columns - 1) / columns;
    std::vector<cv::Mat> tiles;
    int tw = 320, th = 0;
    for (int c = 0; c < count; ++c) {
        int k = count == 1 ? 0 : int(std::lround(double(c) * (total - 1) / (count - 1)));
        Image img = read_image(frame_name(dir, "frame", k, ".png"));
        cv::Mat m(img.height, img.width, CV_32FC(img.channels), img.pixels.data()), rgb, small;
        if (img.channels == 4) cv::cvtColor(m, rgb, cv::COLOR_RGBA2RGB);
        else if (img.channels == 1) cv::cvtColor(m, rgb, cv::COLOR_GRAY2RGB);
        else rgb = m.clone();
        th = std::max(1, int(std::lround(double(tw) * img.height / img.width)));
        cv::resize(rgb, small, cv::Size(tw, th), 0, 0, cv::INTER_AREA);
        tiles.push_back(small);
    }
    Image sheet;
    sheet.width = columns * tw, sheet.height = rows * th, sheet.channels = 3;
    sheet.pixels.assign(size_t(sheet.width) * sheet.height * 3, 0.0f);
    for (int c = 0; c < count; ++c) {
        const cv::Mat& t = tiles[size_t(c)];
        int x0 = (c % columns) * tw, y0 = (c / columns) * th;
        for (int y = 0; y < th; ++y)
            for (int x = 0; x < tw; ++x) {
                cv::Vec3f p = t.at<cv::Vec3f>(y, x);
                float* q = &sheet.pixels[(size_t(y0 + y) * sheet.width + x0 + x) * 3];
                q[0] = p[0], q[1] = p[1], q[2] = p[2];
            }
    }
    write_image(out, sheet);
}

void parse_frame_range(const std::string& text, int total, int* first, int* last) {
    *first = 0, *last = total - 1;
    if (text.empty()) return;
    std::smatch m;
    if (!std::regex_match(text, m, std::regex("^([0-9]+)(-([0-9]+))?$")))
        throw Error("--frames '" + text + "': expected A-B (inclusive, from 0) or a single frame number");
    *first = std::stoi(m[1]);
    *last = m[3].matched ? std::stoi(m[3]) : *first;
    if (*first > *last || *last >= total)
        throw Error("--frames '" + text + "': the animation has frames 0-" + std::to_string(total - 1));
}

int run_animate(const AnimateOptions& o) {
    int width, height;
    parse_frame_size(o.resolution, &width, &height);
    if (!(o.duration > 0)) throw Error("--duration must be positive");
    if (!(o.fps > 0 && o.fps <= 1000)) throw Error("--fps must be in (0, 1000]");
    if (o.spp < 1) throw Error("--spp must be at least 1");
    const int total = std::max(1, int(std::lround(o.duration * o.fps)));
    int first, last;
    parse_frame_range(o.frames, total, &first, &last);

    std::unique_ptr<tbb::global_control> threads;
    if (o.threads > 0) threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, o.threads);

    SkyTimeline timeline = make_sky_timeline(o.sky);
    LoadedScene scene = load_scene(o.scene, float(width) / height);
    fs::create_directories(o.out);

    if (!o.quiet)
        std::fprintf(stderr, "scene: %s (%zu triangles); sky: %s, model %s, Delta t %g s; %d frames at %g fps, rendering %d-%d\n",
                     o.scene.scene.c_str(), scene.scene.triangle_count(), timeline.step(0)->source.c_str(),
                     timeline.model().name().c_str(), timeline.dt(), total, o.fps, first, last);

    // One exposure for the whole animation (per-frame auto exposure would flicker), from the sky
    // at t = 0 so every frame range agrees on it.
    EnvLight light(o.scene.ground_albedo);
    auto sky0 = std::make_shared<const SkyImage>(timeline.sky_at(0.0));
    light.set_sky(sky0);
    const float ev = std::isnan(o.exposure) ? exposure_for_irradiance(light.sky_irradiance()) : o.exposure;
    const float sky_ev = exposure_log_average(sky_to_image(*sky0));

    Accel accel(scene.scene);
    std::ofstream timings((fs::path(o.out) / "timings.csv").string(), std::ios::app);
    if (timings.tellp() == 0) timings << "frame,time_s,sky_ms,distribution_ms,render_ms,medium_steps_so_far\n";
    double sum_sky = 0, sum_build = 0, sum_render = 0;
    int rendered = 0, skipped = 0;
    std::shared_ptr<SkyImage> sky_buffers[2];
    for (int k = first; k <= last; ++k) {
        if (frame_complete(o.out, k)) {
            ++skipped;
            continue;
        }
        const double t = k / o.fps;
        // Two sky buffers, alternated: the light keeps the last frame's while the next is written.
        std::shared_ptr<SkyImage>& buffer = sky_buffers[k % 2];
        if (!buffer || buffer.use_count() > 1) buffer = std::make_shared<SkyImage>();
        auto t0 = std::chrono::steady_clock::now();
        timeline.sky_at(t, buffer.get());
        double sky_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::shared_ptr<const SkyImage> sky = buffer;
        light.set_sky(sky);

        RenderSettings settings;
        settings.width = width, settings.height = height, settings.spp = o.spp, settings.max_depth = o.max_depth;
        settings.seed = o.seed_per_frame ? o.seed + uint64_t(k) * 0x9E3779B97F4A7C15ull : o.seed;
        settings.quiet = true;
        PathIntegrator integrator(accel, light, settings);
        RenderResult result = integrator.render(scene.camera);

        Image& image = result.color;
        image.metadata.numbers["dynsky:frame"] = k;
        image.metadata.numbers["dynsky:time"] = t;
        image.metadata.numbers["dynsky:fps"] = o.fps;
        image.metadata.numbers["dynsky:spp"] = o.spp;
        image.metadata.numbers["dynsky:seed"] = double(settings.seed);
        image.metadata.numbers["dynsky:sky_seconds"] = sky_s;
        image.metadata.numbers["dynsky:sky_distribution_seconds"] = light.last_build_seconds();
        image.metadata.numbers["dynsky:render_seconds"] = result.stats.seconds;
        image.metadata.numbers["dynsky:medium_step_seconds"] = timeline.dt();
        image.metadata.numbers["dynsky:png_exposure_ev"] = ev;
        image.metadata.strings["dynsky:sky"] = sky->source;
        image.metadata.strings["dynsky:sky_model"] = timeline.model().name();
        image.metadata.strings["dynsky:scene"] = o.scene.scene;
        image.metadata.strings["dynsky:camera"] = scene.camera.name;
        write_image(frame_name(o.out, "frame", k, ".exr"), image);
        write_image(frame_name(o.out, "frame", k, ".png"), tonemap_to_display(image, ev));
        write_image(frame_name(o.out, "sky", k, ".png"), tonemap_to_display(sky_to_image(*sky), sky_ev));

        sum_sky += sky_s, sum_build += light.last_build_seconds(), sum_render += result.stats.seconds, ++rendered;
        timings << k << ',' << t << ',' << sky_s * 1e3 << ',' << light.last_build_seconds() * 1e3 << ','
                << result.stats.seconds * 1e3 << ',' << timeline.timings().medium_steps << '\n';
        timings.flush();
        if (!o.quiet)
            std::fprintf(stderr, "frame %d/%d t=%.3f s: sky %.1f ms, distribution %.1f ms, render %.1f ms\n", k, total - 1, t,
                         sky_s * 1e3, light.last_build_seconds() * 1e3, result.stats.seconds * 1e3);
    }
    if (!o.quiet) {
        std::fprintf(stderr, "%d frame(s) rendered, %d already complete (kept)\n", rendered, skipped);
        if (rendered > 0)
            std::fprintf(stderr,
                         "per frame (mean): sky %.1f ms (Gamma + amortised xi: %d medium step(s) this run), distribution %.1f ms, "
                         "render %.1f ms; sky work %.2f%% of the frame\n",
                         sum_sky / rendered * 1e3, timeline.timings().medium_steps, sum_build / rendered * 1e3,
                         sum_render / rendered * 1e3, 100.0 * (sum_sky + sum_build) / (sum_sky + sum_build + sum_render));
    }

    bool all = true;
    for (int k = 0; k < total && all; ++k) all = frame_complete(o.out, k);
    if (!all) {
        if (!o.quiet) std::fprintf(stderr, "not every frame of 0-%d exists yet: videos and contact sheet left for later\n", total - 1);
        return 0;
    }
    make_contact_sheet(o.out, total, (fs::path(o.out) / "contact_sheet.png").string());
    if (!o.quiet) std::fprintf(stderr, "wrote %s\n", (fs::path(o.out) / "contact_sheet.png").string().c_str());
    if (!o.no_video) {
        make_video(o.out, "frame", o.fps, (fs::path(o.out) / "animation.mp4").string(), o.quiet);
        make_video(o.out, "sky", o.fps, (fs::path(o.out) / "sky.mp4").string(), o.quiet);
    }
    return 0;
}

}  // namespace

void register_animate_command(CLI::App& app) {
    auto o = std::make_shared<AnimateOptions>();
    CLI::App* cmd = app.add_subcommand(
        "animate",
        "Render a scene under a moving sky: numbered linear EXR + PNG frames, sky frames, MP4s and a contact sheet.\n"
        "Resumable: frames already complete in --out are kept and skipped; kill it at any moment and run it again.");
    // A repeated option takes its last value, so wrappers (scripts/demo.sh) can be overridden.
    cmd->option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
    add_scene_options(cmd, &o->scene);
    add_sky_source_options(cmd, &o->sky);
    cmd->add_option("--duration", o->duration, "Length of the animation in seconds of sky time")->capture_default_str();
    cmd->add_option("--fps", o->fps, "Frames per second (frame k shows the sky at t = k / fps)")->capture_default_str();
    cmd->add_option("--spp", o->spp, "Samples per pixel")->capture_default_str();
    cmd->add_option("--res", o->resolution, "Frame size WIDTHxHEIGHT")->capture_default_str();
    cmd->add_option("--out,-o", o->out,
                    "Output folder: frame_NNNN.exr/.png, sky_NNNN.png, timings.csv, contact_sheet.png, animation.mp4, sky.mp4")
        ->capture_default_str();
    cmd->add_option("--frames", o->frames, "Render only frames A-B (inclusive, numbered from 0), e.g. 0-11 or 5");
    cmd->add_option("--seed", o->seed, "Random seed of the path tracer")->capture_default_str();
    cmd->add_flag("--seed-per-frame", o->seed_per_frame,
                  "A different seed every frame (independent noise; default: the same seed every frame, i.e. correlated\n"
                  "sampling, which keeps Monte Carlo noise from flickering between frames)");
    cmd->add_option("--threads", o->threads, "Worker threads (0: all cores)")->capture_default_str();
    cmd->add_option("--max-depth", o->max_depth, "Maximum path length (bounces)")->capture_default_str();
    cmd->add_option("--exposure", o->exposure,
                    "PNG exposure in stops for every frame (default: from the sky's irradiance at t = 0, the same for all frames)");
    cmd->add_flag("--no-video", o->no_video, "Do not run ffmpeg (no MP4s)");
    cmd->add_flag("--quiet,-q", o->quiet, "No per-frame report");
    cmd->callback([o] { run_animate(*o); });
}

}  // namespace dynsky::cli
