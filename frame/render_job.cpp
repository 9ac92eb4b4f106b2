#include "frame/render_job.h"

#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

#include "frame/frame_metadata.h"
#include "renderer/integrator.h"
#include "sky/latlong.h"
#include "util/atomic_file.h"
#include "util/cpu_time.h"
#include "util/error.h"
#include "util/interrupt.h"
#include "util/exposure.h"
#include "util/image.h"
#include "util/parse.h"

namespace dynsky {

void run_render_job(const RenderJob& o) {
    // Everything that can be wrong with the input is checked before any pixel is traced, so a
    // bad run leaves no output behind.
    int width, height;
    parse_frame_size(o.resolution, &width, &height);
    std::string ext = file_extension(o.out);
    if (ext != ".exr" && ext != ".png") throw Error("--out " + o.out + ": must end in .exr or .png");
    if (o.spp < 1) throw Error("--spp must be at least 1");
    const SkySamplerOptions sampler = parse_sky_sampler(o.sampler);
    RenderSettings settings;
    settings.aovs = parse_aovs(o.aovs);
    settings.pattern = parse_sample_pattern(o.sampler_pattern);
    if (settings.aovs.any() && ext != ".exr")
        throw Error(o.out + ": --aovs needs an .exr output (a PNG holds colour only)");
    if (!o.region.empty()) settings.region = parse_region(o.region, width, height);
    if (!(o.noise_threshold >= 0)) throw Error("--noise-threshold must be 0 (off) or positive");
    if (!(o.time_limit >= 0)) throw Error("--time-limit must be 0 (none) or positive seconds");
    if (!(o.clamp_indirect >= 0)) throw Error("--clamp-indirect must be 0 (off) or positive");
    if (!(o.filter_glossy >= 0)) throw Error("--filter-glossy must be 0 (off) or positive");
    const std::string png_beside = ext == ".exr" ? std::filesystem::path(o.out).replace_extension(".png").string()
                                                 : std::string();
    check_outputs_are_not_inputs({o.out, png_beside}, {o.scene.scene, o.sky});
    for (const std::string& out : {o.out, png_beside}) check_output_file(out);  // before the render, not after

    std::unique_ptr<tbb::global_control> threads;
    if (o.threads > 0)
        threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, o.threads);

    LoadedScene loaded = load_scene(o.scene, float(width) / height);
    Scene& scene = loaded.scene;
    // Nor may it replace one of the files the scene was read from (a texture beside it).
    check_outputs_are_not_inputs({o.out, png_beside}, scene.source_files);
    const Camera& camera = loaded.camera;
    if (o.override_material == "lambert") override_materials_lambert(&scene);

    std::shared_ptr<SkyImage> sky, ground;  // ground: a lat-long environment's lower half
    // A place given (--lat, --lon off their defaults) asks for a sky made here, as --time does:
    // the built-in Paris sky ignored them without a word.
    const SkySourceSpec defaults;
    const bool placed = o.generated.latitude != defaults.latitude || o.generated.longitude != defaults.longitude;
    if (o.sky.empty() && o.generated.time.empty() && !placed && o.generated.turbidity == defaults.turbidity) {
        sky = std::make_shared<SkyImage>(make_builtin_clear_sky(o.generated.sky_resolution));
    } else if (o.sky.empty() || is_generated_sky(o.sky)) {
        SkySourceSpec spec = o.generated;  // made as animate and compare make it (frame/sky_source.h)
        spec.sky = o.sky.empty() ? "clear" : o.sky;
        sky = std::make_shared<SkyImage>(make_generated_sky(spec));
    } else if (!o.generated.time.empty() || placed) {
        throw Error(std::string(placed ? "--lat and --lon place" : "--time places") +
                    " the sun of a sky made here (--sky clear or procedural); " + o.sky + " keeps the sun it has");
    } else {
        sky = std::make_shared<SkyImage>(load_sky_or_latlong(o.sky, &ground, sky_file_options(o.generated)));
    }

    Accel accel(scene);
    EnvLight light(sky, o.scene.ground_albedo, sampler);
    if (ground) light.set_ground_image(ground);
    if (!o.quiet)
        std::fprintf(stderr,
                     "scene: %s, %zu triangles, %zu instances, %zu punctual light(s); sky: %s (%dx%d), distribution "
                     "built in %.2f ms\n",
                     o.scene.scene.c_str(), scene.triangle_count(), scene.instances.size(), scene.lights.size(),
                     sky->source.c_str(), sky->resolution, sky->resolution, light.last_build_seconds() * 1e3);

    settings.width = width, settings.height = height, settings.spp = o.spp, settings.seed = o.seed;
    settings.max_depth = o.max_depth, settings.quiet = o.quiet;
    settings.noise_threshold = o.noise_threshold, settings.time_limit_seconds = o.time_limit;
    settings.clamp_indirect = o.clamp_indirect, settings.filter_glossy = o.filter_glossy;
    // Ctrl-C (or a farm's SIGTERM) in a render of several rounds ends it after its round, and the
    // image of the samples taken is written: hours of a long render are not lost with the last
    // minute. Rounds keep every pixel's state (56 bytes each): up to 3840 x 2160 pixels.
    settings.stop_on_request = o.spp > settings.round_spp &&
                               (settings.region.empty()
                                    ? double(width) * height
                                    : double(settings.region.x1 - settings.region.x0) *
                                          (settings.region.y1 - settings.region.y0)) <= 3840.0 * 2160.0;
    PathIntegrator integrator(accel, light, settings);
    const double cpu_before = process_cpu_seconds();
    RenderResult result;
    {
        std::optional<AllowGracefulStop> graceful;
        if (settings.stop_on_request)
            graceful.emplace("finishing this round of samples, then writing the image of the samples taken");
        result = integrator.render(camera);
    }
    const double render_cpu_seconds = process_cpu_seconds() - cpu_before;

    Image& image = result.color;
    // Nothing lit reached the camera: written (it is what the scene shows), but said.
    if (is_black_everywhere(image))
        std::fprintf(stderr, "dynsky: warning: the image %s\n",
                     o.max_depth == 0 ? "is black everywhere: --max-depth 0 shows only emitters and the sky seen "
                                        "directly, and the camera sees neither"
                                      : kBlackRenderHint);
    image.metadata.numbers["dynsky:spp"] = o.spp;  // the most asked for; what was taken (adaptive, --time-limit):
    // Samples per pixel taken (fewer than asked when adaptive, time-limited or interrupted).
    const double spp_taken = double(result.stats.camera_rays) /
                             std::max<double>(1.0, double(image.width) * image.height);
    image.metadata.numbers["dynsky:spp_mean"] = spp_taken;
    image.metadata.numbers["dynsky:seed"] = double(o.seed);
    image.metadata.strings["dynsky:seed_exact"] = std::to_string(o.seed);  // a double holds 53 bits of it
    image.metadata.numbers["dynsky:render_seconds"] = result.stats.seconds;
    // CPU time of all threads: comparable across runs on a shared machine (bench/cycles_equal_error.sh).
    image.metadata.numbers["dynsky:render_cpu_seconds"] = render_cpu_seconds;
    image.metadata.numbers["dynsky:sky_distribution_seconds"] = light.last_build_seconds();
    image.metadata.numbers["dynsky:ground_albedo"] = o.scene.ground_albedo;
    image.metadata.numbers["dynsky:time"] = sky->time_seconds;  // frame time (glossary)
    image.metadata.strings["dynsky:sky"] = sky->source;
    // Lit by a sky in known units (and lights in the same), the image is radiance in them; a sky in
    // relative units (an uncalibrated import, an HDRI) says nothing, and neither does the image.
    if (!sky->units.empty()) image.metadata.strings["dynsky:units"] = sky->units;
    image.metadata.strings["dynsky:scene"] = o.scene.scene;
    SkySourceSpec taken = o.generated;
    taken.sky = o.sky;
    record_image_inputs(&image.metadata, loaded.path, taken);
    image.metadata.strings["dynsky:camera"] = camera.name;
    if (!settings.region.empty())
        image.metadata.strings["dynsky:region"] = o.region;  // x0,y0,x1,y1 of the full --res image
    if (o.clamp_indirect > 0) image.metadata.numbers["dynsky:clamp_indirect"] = o.clamp_indirect;
    if (o.filter_glossy > 0) image.metadata.numbers["dynsky:filter_glossy"] = o.filter_glossy;
    if (o.noise_threshold > 0) image.metadata.numbers["dynsky:noise_threshold"] = o.noise_threshold;
    if (o.time_limit > 0) image.metadata.numbers["dynsky:time_limit_seconds"] = o.time_limit;
    if (o.scene.animation_time >= 0) image.metadata.numbers["dynsky:anim_time"] = o.scene.animation_time;
    if (!o.scene.animation.empty()) image.metadata.strings["dynsky:animation"] = o.scene.animation;
    // Rounds cut short by the error estimate, the clock or an interrupt (an interruptible render
    // runs in rounds too, all of them when it is not interrupted).
    if (o.noise_threshold > 0 || o.time_limit > 0 || result.stopped)
        image.metadata.numbers["dynsky:rounds"] = result.rounds;
    if (result.stopped) {
        note_stopped_early();                              // exit kInterrupted, after the image is written
        image.metadata.numbers["dynsky:interrupted"] = 1;  // fewer samples than dynsky:spp (dynsky:spp_mean)
        std::fprintf(stderr,
                     "dynsky: warning: interrupted after %d round(s): writing the image of the %.0f samples per "
                     "pixel taken (of %d)\n",
                     result.rounds, spp_taken, o.spp);
    }
    image.metadata.strings["dynsky:sampler_pattern"] = o.sampler_pattern;
    // Everything else that changes the image, so that it can be rendered again from its header.
    image.metadata.numbers["dynsky:max_depth"] = o.max_depth;
    image.metadata.strings["dynsky:sky_sampler"] = o.sampler;
    if (o.override_material != "none") image.metadata.strings["dynsky:override_material"] = o.override_material;
    if (!o.scene.look_at.empty()) {
        std::string eye_target;
        for (double v : o.scene.look_at) eye_target += (eye_target.empty() ? "" : ",") + number_text(v);
        image.metadata.strings["dynsky:look_at"] = eye_target;  // eye x,y,z, target x,y,z
    }
    if (camera.orthographic) image.metadata.numbers["dynsky:camera_ymag"] = camera.ymag;
    else image.metadata.numbers["dynsky:camera_yfov_deg"] = camera.yfov * 180.0 / kPiD;
    float ev = std::isnan(o.exposure) ? exposure_log_average(image) : o.exposure;
    image.metadata.numbers["dynsky:png_exposure_ev"] = ev;
    // The timings are the EXR's: the PNG depends only on its pixels and settings, so two runs of
    // one render give the same PNG (they did while PNGs dropped numbers).
    Image display = tonemap_to_display(image, result.alpha, ev);
    for (const char* timing : {"dynsky:render_seconds", "dynsky:render_cpu_seconds", "dynsky:sky_distribution_seconds"})
        display.metadata.numbers.erase(timing);
    if (ext == ".exr") {
        // A render is its two files: both are written under temporary names first and renamed only
        // when both are, so a PNG that cannot be written (a full disk) leaves neither, and an
        // earlier render's pair under these names stays as it was.
        write_files_atomic({{o.out, encode_image(o.out, settings.aovs.any() ? render_layers(result) : image)},
                            {png_beside, encode_image(png_beside, display)}});
        if (!o.quiet) std::fprintf(stderr, "wrote %s and %s\n", o.out.c_str(), png_beside.c_str());
    } else {
        write_image(o.out, display);
        if (!o.quiet) std::fprintf(stderr, "wrote %s\n", o.out.c_str());
    }
    if (!o.quiet && result.stopped)
        std::fprintf(stderr, "rendered %dx%d at %.0f of %d spp (interrupted) in %.2f s: %.2f M rays/s\n", width, height,
                     spp_taken, o.spp, result.stats.seconds, result.stats.total_rays() / result.stats.seconds * 1e-6);
    else if (!o.quiet)
        std::fprintf(stderr, "rendered %dx%d at %d spp in %.2f s: %.2f M rays/s\n", width, height, o.spp,
                     result.stats.seconds, result.stats.total_rays() / result.stats.seconds * 1e-6);
    if (!o.quiet && result.rounds > 1 && (o.noise_threshold > 0 || o.time_limit > 0))
        std::fprintf(stderr, "adaptive sampling / time limit: %d round(s), %.1f samples per pixel on average\n",
                     result.rounds, spp_taken);
}

}  // namespace dynsky
