// dynsky render: one image of a glTF scene (or the built-in plaza) under a fisheye sky.
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>
#include <filesystem>
#include <memory>

#include "frame/scene_spec.h"
#include "frame/sky_source.h"
#include "util/atomic_file.h"
#include "util/parse.h"
#include "cli/commands.h"
#include "cli/options.h"
#include "renderer/builtin_scene.h"
#include "renderer/gltf_loader.h"
#include "renderer/integrator.h"
#include "renderer/sky_sampler.h"
#include "sky/clear_sky.h"
#include "sky/latlong.h"
#include "sky/sun_position.h"
#include "util/error.h"
#include "util/exposure.h"

namespace dynsky::cli {

namespace {

// render's default scene is the built-in one (animate and compare default to the tower).
SceneSpec builtin_scene_spec() {
    SceneSpec spec;
    spec.scene = "builtin";
    return spec;
}

struct RenderOptions {
    SceneSpec scene = builtin_scene_spec();  // the scene and camera options every command shares (cli/options.h)
    std::string sky;
    std::string out = "render.exr";
    std::string resolution = "960x540";
    int spp = 64;
    uint64_t seed = 0;
    int threads = 0;
    int max_depth = 8;
    float exposure = std::numeric_limits<float>::quiet_NaN();  // NaN: automatic
    bool quiet = false;
    std::string sampler = sky_sampler_name(path_tracer_sky_sampler());
    std::string aovs, region;
    float noise_threshold = 0, clamp_indirect = 0, filter_glossy = 0;
    double time_limit = 0;
    std::string sampler_pattern = "random";
    std::string override_material = "none";
    SkySourceSpec generated;  // --sky clear|procedural[:SEED] with --sky-res, --time, --lat, --lon
};

// CPU seconds of this process, all threads together.
double process_cpu_seconds() {
    timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

// The default sky when --sky is not given: a clear afternoon over Paris at the summer solstice.
std::shared_ptr<SkyImage> builtin_clear_sky(int resolution) {
    SkySourceSpec clear;  // the place, time and turbidity of `--sky clear` everywhere
    clear.sky = "clear";
    clear.sky_resolution = resolution;  // --sky-res, as for 'clear'
    auto sky = std::make_shared<SkyImage>(make_generated_sky(clear));
    sky->source = std::string("builtin: clear sky, Paris ") + default_sky::kStartTime + ", turbidity " +
                  number_text(default_sky::kTurbidity);
    return sky;
}

// Every surface a Lambertian of its base colour (textures and vertex colours kept), as
// tools/cycles/render_cycles.py --override-material lambert does in Cycles: the two renderers then
// share an exact BRDF, which separates geometry and lighting from material models. Emission goes
// too, as it does there.
void override_lambert(Scene* scene) {
    int white = -1;
    for (MeshGroup& group : scene->meshes)
        for (TriangleMesh& mesh : group.primitives)
            if (mesh.material < 0) {
                if (white < 0) {
                    scene->materials.push_back(Scene::default_material());
                    white = int(scene->materials.size()) - 1;
                }
                mesh.material = white;
            }
    for (Material& m : scene->materials)
        m.metallic = 0, m.specular = 0, m.transmission = 0,
        m.emissive = Color::Zero();  // glass too: as Cycles' diffuse
}

int run_render(const RenderOptions& o) {
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
    if (o.override_material == "lambert") override_lambert(&scene);

    std::shared_ptr<SkyImage> sky, ground;  // ground: a lat-long environment's lower half
    // A place given (--lat, --lon off their defaults) asks for a sky made here, as --time does:
    // the built-in Paris sky ignored them without a word.
    const SkySourceSpec defaults;
    const bool placed = o.generated.latitude != defaults.latitude || o.generated.longitude != defaults.longitude;
    if (o.sky.empty() && o.generated.time.empty() && !placed) {
        sky = builtin_clear_sky(o.generated.sky_resolution);
    } else if (o.sky.empty() || is_generated_sky(o.sky)) {
        SkySourceSpec spec = o.generated;  // made as animate and compare make it (frame/sky_source.h)
        spec.sky = o.sky.empty() ? "clear" : o.sky;
        sky = std::make_shared<SkyImage>(make_generated_sky(spec));
    } else if (!o.generated.time.empty() || placed) {
        throw Error(std::string(placed ? "--lat and --lon place" : "--time places") +
                    " the sun of a sky made here (--sky clear or procedural); " + o.sky + " keeps the sun it has");
    } else {
        sky = std::make_shared<SkyImage>(load_sky_or_latlong(o.sky, &ground));
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
    PathIntegrator integrator(accel, light, settings);
    const double cpu_before = process_cpu_seconds();
    RenderResult result = integrator.render(camera);
    const double render_cpu_seconds = process_cpu_seconds() - cpu_before;

    Image& image = result.color;
    // Nothing lit reached the camera: written (it is what the scene shows), but said.
    if (is_black_everywhere(image))
        std::fprintf(stderr, "dynsky: warning: the image %s\n",
                     o.max_depth == 0 ? "is black everywhere: --max-depth 0 shows only emitters and the sky seen "
                                        "directly, and the camera sees neither"
                                      : kBlackRenderHint);
    image.metadata.numbers["dynsky:spp"] = o.spp;  // the most asked for; what was taken (adaptive, --time-limit):
    image.metadata.numbers["dynsky:spp_mean"] = double(result.stats.camera_rays) /
                                                std::max<double>(1.0, double(image.width) * image.height);
    image.metadata.numbers["dynsky:seed"] = double(o.seed);
    image.metadata.strings["dynsky:seed_exact"] = std::to_string(o.seed);  // a double holds 53 bits of it
    image.metadata.numbers["dynsky:render_seconds"] = result.stats.seconds;
    // CPU time of all threads: comparable across runs on a shared machine (bench/cycles_equal_error.sh).
    image.metadata.numbers["dynsky:render_cpu_seconds"] = render_cpu_seconds;
    image.metadata.numbers["dynsky:sky_distribution_seconds"] = light.last_build_seconds();
    image.metadata.numbers["dynsky:ground_albedo"] = o.scene.ground_albedo;
    image.metadata.numbers["dynsky:time"] = sky->time_seconds;  // frame time (glossary)
    image.metadata.strings["dynsky:sky"] = sky->source;
    image.metadata.strings["dynsky:scene"] = o.scene.scene;
    image.metadata.strings["dynsky:camera"] = camera.name;
    if (!settings.region.empty())
        image.metadata.strings["dynsky:region"] = o.region;  // x0,y0,x1,y1 of the full --res image
    if (o.clamp_indirect > 0) image.metadata.numbers["dynsky:clamp_indirect"] = o.clamp_indirect;
    if (o.filter_glossy > 0) image.metadata.numbers["dynsky:filter_glossy"] = o.filter_glossy;
    if (o.noise_threshold > 0) image.metadata.numbers["dynsky:noise_threshold"] = o.noise_threshold;
    if (o.time_limit > 0) image.metadata.numbers["dynsky:time_limit_seconds"] = o.time_limit;
    if (o.scene.animation_time >= 0) image.metadata.numbers["dynsky:anim_time"] = o.scene.animation_time;
    if (!o.scene.animation.empty()) image.metadata.strings["dynsky:animation"] = o.scene.animation;
    image.metadata.numbers["dynsky:rounds"] = result.rounds;
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
    if (ext == ".exr") {
        write_image(o.out, settings.aovs.any() ? render_layers(result) : image);
        // A render is its two files: if the PNG cannot be written (a full disk, a folder of its
        // name), the EXR does not stay behind either.
        try {
            write_image(png_beside, tonemap_to_display(image, ev));
        } catch (const Error&) {
            std::error_code ec;
            std::filesystem::remove(o.out, ec);
            throw;
        }
        if (!o.quiet) std::fprintf(stderr, "wrote %s and %s\n", o.out.c_str(), png_beside.c_str());
    } else {
        write_image(o.out, tonemap_to_display(image, ev));
        if (!o.quiet) std::fprintf(stderr, "wrote %s\n", o.out.c_str());
    }
    if (!o.quiet)
        std::fprintf(stderr, "rendered %dx%d at %d spp in %.2f s: %.2f M rays/s\n", width, height, o.spp,
                     result.stats.seconds, result.stats.total_rays() / result.stats.seconds * 1e-6);
    if (!o.quiet && result.rounds > 1)
        std::fprintf(stderr, "adaptive sampling / time limit: %d round(s), %.1f samples per pixel on average\n",
                     result.rounds, double(result.stats.camera_rays) / (double(image.width) * image.height));
    return 0;
}

}  // namespace

void register_render_command(CLI::App& app) {
    auto o = std::make_shared<RenderOptions>();
    CLI::App* cmd = app.add_subcommand("render", "Render a glTF 2.0 scene under a fisheye sky (path traced, CPU)");
    add_scene_options(cmd, &o->scene);  // scene, --camera, --look-at, --fov, --ground-albedo
    cmd->add_option(
        "--sky", o->sky,
        "Sky: a canonical fisheye EXR (square, equidistant, north up, east left; see 'dynsky sky'); a lat-long\n"
        "(equirect, 2:1) HDRI in Blender's mapping: its upper half becomes the fisheye sky, its lower half the\n"
        "ground (instead of the ground model); or one made here as 'animate' makes it: 'clear' (Hosek-Wilkie)\n"
        "or 'procedural[:SEED]' at --time, --lat, --lon.\n"
        "Default: a built-in clear sky (Paris, 2026-06-21 16:00 UTC, turbidity 3; with --time, --lat or --lon:\n"
        "'clear' there)");
    add_generated_sky_options(cmd, &o->generated);
    cmd->add_option("--out,-o", o->out,
                    "Output image: .exr (linear, with metadata; a tone-mapped .png is written beside it) or .png")
        ->capture_default_str();
    cmd->add_option("--res", o->resolution, "Image size WIDTHxHEIGHT")->capture_default_str();
    cmd->add_option("--spp", o->spp, "Samples per pixel")->check(CLI::Range(1, kMaxSpp))->capture_default_str();
    cmd->add_option("--seed", o->seed, "Random seed: the same seed gives the same image on any thread count")
        ->check(non_negative_whole())
        ->capture_default_str();
    cmd->add_option("--threads", o->threads, "Worker threads (0: all cores)")
        ->check(CLI::Range(0, kMaxThreads))
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
        ->check(parsed_by([](const std::string& s) { parse_sky_sampler(s); }, "SAMPLER"))
        ->capture_default_str();
    cmd->add_option("--aovs", o->aovs,
                    "Extra passes in the EXR, comma-separated: albedo ('Denoising Albedo'), normal ('Normal', world),\n"
                    "depth ('Depth', camera Z, 1e10 on the sky), alpha (the 'A' channel), samples ('Sample Count')");
    cmd->add_option(
        "--region", o->region,
        "Render only pixels [x0, x1) x [y0, y1) of the --res image, 'x0,y0,x1,y1' (the output is cropped to\n"
        "them, the EXR placing them in the whole image by its data window, as compositors expect; they equal the same pixels of a full render with the same seed; with --noise-threshold only\n"
        "where the stopping rule's 9 x 9 neighbourhood lies inside the region). The PNG's automatic exposure\n"
        "is the region's own: give --exposure for tiles that match");
    cmd->add_option(
           "--noise-threshold", o->noise_threshold,
           "Adaptive sampling (0: off): a pixel stops taking samples, in rounds of 16, once the relative error\n"
           "of its mean (luminance), and that of its 9 x 9 neighbourhood, are under this (so a pixel whose first\n"
           "samples missed a small light keeps sampling while its neighbours see it); --spp is then the most a\n"
           "pixel takes")
        ->capture_default_str();
    cmd->add_option("--time-limit", o->time_limit,
                    "Seconds of rendering after which no new round of 16 samples starts (0: none); --spp still caps")
        ->capture_default_str();
    cmd->add_option(
           "--clamp-indirect", o->clamp_indirect,
           "Firefly clamp (Cycles' Clamp Indirect): light that scattered at two or more surfaces is limited to\n"
           "this sum of RGB per sample (0: off; biased, darkens bright indirect light)")
        ->capture_default_str();
    cmd->add_option(
           "--filter-glossy", o->filter_glossy,
           "Cycles' Filter Glossy: after the first bounce, sharp reflections are roughened by the path's\n"
           "smallest pdf (0: off; 1 is a typical value; biased, blurs caustics and reflections of reflections)")
        ->capture_default_str();
    cmd->add_option("--sampler-pattern", o->sampler_pattern,
                    "Sample values: 'random' (independent PCG32 streams per pixel, the reference) or 'sobol'\n"
                    "(Owen-scrambled Sobol in Z order, pbrt-v4's ZSobol: lower error per sample); both give the same\n"
                    "image on any thread count")
        ->capture_default_str();
    cmd->add_option("--override-material", o->override_material,
                    "'lambert': every surface a Lambertian of its base colour (to compare lighting and geometry\n"
                    "with tools/cycles/render_cycles.py --override-material lambert); 'none' (default)")
        ->check(CLI::IsMember({"none", "lambert"}))
        ->capture_default_str();
    cmd->add_flag("--quiet,-q", o->quiet, "No progress bar or summary");
    cmd->callback([o] { run_render(*o); });
}

}  // namespace dynsky::cli
