// dynsky render: one image of a glTF scene (or the built-in plaza) under a fisheye sky.
#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <filesystem>
#include <memory>

#include "frame/scene_spec.h"
#include "util/parse.h"
#include "cli/commands.h"
#include "cli/options.h"
#include "renderer/builtin_scene.h"
#include "renderer/gltf_loader.h"
#include "renderer/integrator.h"
#include "sky/clear_sky.h"
#include "sky/sun_position.h"
#include "util/error.h"
#include "util/exposure.h"

namespace dynsky::cli {

namespace {

struct RenderOptions {
    std::string scene = "builtin";
    std::string sky;
    std::string out = "render.exr";
    std::string resolution = "960x540";
    int spp = 64;
    int camera = 0;
    uint64_t seed = 0;
    int threads = 0;
    float ground_albedo = 0.3f;
    int max_depth = 8;
    float exposure = std::numeric_limits<float>::quiet_NaN();  // NaN: automatic
    bool quiet = false;
    std::string sampler = sky_sampler_name(recommended_sky_sampler()) + "+mis";
};

// The default sky when --sky is not given: a clear afternoon over Paris at the summer solstice.
std::shared_ptr<SkyImage> default_sky() {
    ClearSkyParams p;
    GeoLocation where{48.8566, 2.3522, 35};
    p.sun_direction = compute_sun_position(parse_utc_time("2026-06-21T16:00:00Z"), where).direction();
    p.turbidity = 3;
    auto sky = std::make_shared<SkyImage>(make_clear_sky(p, 1024));
    sky->source = "builtin: clear sky, Paris 2026-06-21T16:00:00Z, turbidity 3";
    return sky;
}

int run_render(const RenderOptions& o) {
    // Everything that can be wrong with the input is checked before any pixel is traced, so a
    // bad run leaves no output behind.
    int width, height;
    parse_frame_size(o.resolution, &width, &height);
    std::string ext = file_extension(o.out);
    if (ext != ".exr" && ext != ".png") throw Error(o.out + ": output must end in .exr or .png");
    if (o.spp < 1) throw Error("--spp must be at least 1");
    const SkySamplerOptions sampler = parse_sky_sampler(o.sampler);

    std::unique_ptr<tbb::global_control> threads;
    if (o.threads > 0)
        threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, o.threads);

    LoadedScene loaded = load_scene(SceneSpec{o.scene, o.camera, o.ground_albedo}, float(width) / height);
    const Scene& scene = loaded.scene;
    const Camera& camera = loaded.camera;

    std::shared_ptr<SkyImage> sky;
    if (o.sky.empty()) {
        sky = default_sky();
    } else {
        sky = std::make_shared<SkyImage>(load_sky(o.sky));
    }

    Accel accel(scene);
    EnvLight light(sky, o.ground_albedo, sampler);
    if (!o.quiet)
        std::fprintf(stderr,
                     "scene: %s, %zu triangles, %zu instances; sky: %s (%dx%d), distribution built in %.2f ms\n",
                     o.scene.c_str(), scene.triangle_count(), scene.instances.size(), sky->source.c_str(),
                     sky->resolution, sky->resolution, light.last_build_seconds() * 1e3);

    RenderSettings settings;
    settings.width = width, settings.height = height, settings.spp = o.spp, settings.seed = o.seed;
    settings.max_depth = o.max_depth, settings.quiet = o.quiet;
    PathIntegrator integrator(accel, light, settings);
    RenderResult result = integrator.render(camera);

    Image& image = result.color;
    image.metadata.numbers["dynsky:spp"] = o.spp;
    image.metadata.numbers["dynsky:seed"] = double(o.seed);
    image.metadata.numbers["dynsky:render_seconds"] = result.stats.seconds;
    image.metadata.numbers["dynsky:sky_distribution_seconds"] = light.last_build_seconds();
    image.metadata.numbers["dynsky:ground_albedo"] = o.ground_albedo;
    image.metadata.numbers["dynsky:time"] = sky->time_seconds;  // frame time (glossary)
    image.metadata.strings["dynsky:sky"] = sky->source;
    image.metadata.strings["dynsky:scene"] = o.scene;
    image.metadata.strings["dynsky:camera"] = camera.name;
    float ev = std::isnan(o.exposure) ? exposure_log_average(image) : o.exposure;
    image.metadata.numbers["dynsky:png_exposure_ev"] = ev;
    if (ext == ".exr") {
        write_image(o.out, image);
        std::string png = std::filesystem::path(o.out).replace_extension(".png").string();
        write_image(png, tonemap_to_display(image, ev));
        if (!o.quiet) std::fprintf(stderr, "wrote %s and %s\n", o.out.c_str(), png.c_str());
    } else {
        write_image(o.out, tonemap_to_display(image, ev));
        if (!o.quiet) std::fprintf(stderr, "wrote %s\n", o.out.c_str());
    }
    if (!o.quiet)
        std::fprintf(stderr, "rendered %dx%d at %d spp in %.2f s: %.2f M rays/s\n", width, height, o.spp,
                     result.stats.seconds, result.stats.total_rays() / result.stats.seconds * 1e-6);
    return 0;
}

}  // namespace

void register_render_command(CLI::App& app) {
    auto o = std::make_shared<RenderOptions>();
    CLI::App* cmd = app.add_subcommand("render", "Render a glTF 2.0 scene under a fisheye sky (path traced, CPU)");
    cmd->add_option("scene", o->scene, "Scene: a .gltf or .glb file, or 'builtin' for the built-in plaza")
        ->capture_default_str();
    cmd->add_option("--sky", o->sky,
                    "Sky image: canonical fisheye EXR (square, equidistant, north up, east left; see 'dynsky sky').\n"
                    "Default: a built-in clear sky (Paris, 2026-06-21 16:00 UTC, turbidity 3)");
    cmd->add_option("--out,-o", o->out,
                    "Output image: .exr (linear, with metadata; a tone-mapped .png is written beside it) or .png")
        ->capture_default_str();
    cmd->add_option("--res", o->resolution, "Image size WIDTHxHEIGHT")->capture_default_str();
    cmd->add_option("--spp", o->spp, "Samples per pixel")->check(CLI::Range(1, kMaxSpp))->capture_default_str();
    cmd->add_option("--camera", o->camera,
                    "Index of the glTF perspective camera to use (the scene's bounds are framed when it has none)")
        ->check(CLI::Range(0, 1 << 20))
        ->capture_default_str();
    cmd->add_option("--seed", o->seed, "Random seed: the same seed gives the same image on any thread count")
        ->check(non_negative_whole())
        ->capture_default_str();
    cmd->add_option("--threads", o->threads, "Worker threads (0: all cores)")
        ->check(CLI::Range(0, kMaxThreads))
        ->capture_default_str();
    cmd->add_option(
           "--ground-albedo", o->ground_albedo,
           "Albedo of the ground model below the horizon: a Lambertian plane lit by the sky, radiance albedo * E_sky / pi")
        ->check(finite_in(0, 1))
        ->capture_default_str();
    cmd->add_option("--max-depth", o->max_depth, "Maximum path length (bounces)")
        ->check(CLI::Range(0, kMaxDepth))
        ->capture_default_str();
    cmd->add_option(
           "--exposure", o->exposure,
           "Exposure of the PNG in stops (default: automatic, log-average luminance to middle grey; EXR pixels are never scaled)")
        ->check(finite_in(-64, 64));
    cmd->add_option(
           "--sampler", o->sampler,
           "Sky importance sampler: uniform, cosine, cdf, alias, mip, sun+cdf, sun+alias, sun+mip; pixel-based ones "
           "with '+mis' for MIS compensation (the renderer combines light and BSDF sampling by MIS). "
           "See docs/sampling/README.md")
        ->capture_default_str();
    cmd->add_flag("--quiet,-q", o->quiet, "No progress bar or summary");
    cmd->callback([o] { run_render(*o); });
}

}  // namespace dynsky::cli
