#include "frame/animation.h"

#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>

#include "frame/frame_metadata.h"
#include "frame/frame_store.h"
#include "frame/video.h"
#include "renderer/accel.h"
#include "renderer/env_light.h"
#include "renderer/integrator.h"
#include "util/error.h"
#include "util/exposure.h"

namespace dynsky {

namespace fs = std::filesystem;

AnimationReport render_animation(const AnimationSettings& o) {
    const int width = o.width, height = o.height;
    if (width < 1 || height < 1) throw Error("animation: the frame size must be positive");
    if (!(o.duration > 0)) throw Error("--duration must be positive");
    if (!(o.fps > 0 && o.fps <= 1000)) throw Error("--fps must be in (0, 1000]");
    if (o.spp < 1) throw Error("--spp must be at least 1");
    const double frames = std::round(o.duration * o.fps);
    if (!(frames <= kMaxAnimationFrames)) {
        char text[200];
        std::snprintf(text, sizeof text,
                      "--duration %g s at --fps %g is %.4g frames, more than the %.0f one animation may have",
                      o.duration, o.fps, frames, kMaxAnimationFrames);
        throw Error(text);
    }
    const int total = std::max(1, int(frames));
    int first, last;
    parse_frame_range(o.frames, total, &first, &last);

    std::unique_ptr<tbb::global_control> threads;
    if (o.threads > 0)
        threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, o.threads);

    SkyTimeline timeline = make_sky_timeline(o.sky, o.model);
    LoadedScene scene = load_scene(o.scene, float(width) / height);
    fs::create_directories(o.out);
    const FrameStore store(o.out);

    if (!o.quiet)
        std::fprintf(
            stderr,
            "scene: %s (%zu triangles); sky: %s, model %s, Delta t %g s; %d frames at %g fps, rendering %d-%d\n",
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
    std::ofstream timings(store.file("timings.csv"), std::ios::app);
    if (timings.tellp() == 0) timings << "frame,time_s,sky_ms,distribution_ms,render_ms,medium_steps_so_far\n";
    double sum_sky = 0, sum_build = 0, sum_render = 0;
    int rendered = 0, skipped = 0;
    std::shared_ptr<SkyImage> sky_buffers[2];
    for (int k = first; k <= last; ++k) {
        if (store.is_complete(k)) {
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
        FrameMetadata meta;
        meta.frame = k, meta.time_seconds = t, meta.fps = o.fps, meta.spp = o.spp, meta.seed = settings.seed;
        meta.sky_seconds = sky_s, meta.distribution_seconds = light.last_build_seconds();
        meta.render_seconds = result.stats.seconds, meta.medium_step_seconds = timeline.dt(), meta.png_exposure_ev = ev;
        meta.sky = sky->source, meta.sky_model = timeline.model().name(), meta.scene = o.scene.scene;
        meta.camera = scene.camera.name;
        meta.write_to(&image.metadata);
        write_image(store.frame_exr(k), image);
        write_image(store.frame_png(k), tonemap_to_display(image, ev));
        write_image(store.sky_png(k), tonemap_to_display(sky_to_image(*sky), sky_ev));

        sum_sky += sky_s, sum_build += light.last_build_seconds(), sum_render += result.stats.seconds, ++rendered;
        timings << k << ',' << t << ',' << sky_s * 1e3 << ',' << light.last_build_seconds() * 1e3 << ','
                << result.stats.seconds * 1e3 << ',' << timeline.timings().medium_steps << '\n';
        timings.flush();
        if (!o.quiet)
            std::fprintf(stderr, "frame %d/%d t=%.3f s: sky %.1f ms, distribution %.1f ms, render %.1f ms\n", k,
                         total - 1, t, sky_s * 1e3, light.last_build_seconds() * 1e3, result.stats.seconds * 1e3);
    }
    if (!o.quiet) {
        std::fprintf(stderr, "%d frame(s) rendered, %d already complete (kept)\n", rendered, skipped);
        if (rendered > 0)
            std::fprintf(
                stderr,
                "per frame (mean): sky %.1f ms (Gamma + amortised xi: %d medium step(s) this run), distribution %.1f ms, "
                "render %.1f ms; sky work %.2f%% of the frame\n",
                sum_sky / rendered * 1e3, timeline.timings().medium_steps, sum_build / rendered * 1e3,
                sum_render / rendered * 1e3, 100.0 * (sum_sky + sum_build) / (sum_sky + sum_build + sum_render));
    }

    AnimationReport report{total, first, last, rendered, skipped, store.all_complete(total)};
    if (!report.complete) {
        if (!o.quiet)
            std::fprintf(stderr, "not every frame of 0-%d exists yet: videos and contact sheet left for later\n",
                         total - 1);
        return report;
    }
    make_contact_sheet(store, total, store.file("contact_sheet.png"));
    if (!o.quiet) std::fprintf(stderr, "wrote %s\n", store.file("contact_sheet.png").c_str());
    if (!o.no_video) {
        make_video(o.out, "frame", o.fps, store.file("animation.mp4"), o.quiet);
        make_video(o.out, "sky", o.fps, store.file("sky.mp4"), o.quiet);
    }
    return report;
}

}  // namespace dynsky
