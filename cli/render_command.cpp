// dynsky render: one image of a glTF scene (or the built-in plaza) under a fisheye sky. The options
// fill a RenderJob (frame/render_job.h), which does the work.
#include <memory>

#include "cli/commands.h"
#include "cli/options.h"
#include "cli/exit_codes.h"
#include "frame/render_job.h"
#include "renderer/sky_sampler.h"

namespace dynsky::cli {

void register_render_command(CLI::App& app) {
    auto o = std::make_shared<RenderJob>();
    CLI::App* cmd = app.add_subcommand("render", "Render a glTF 2.0 scene under a fisheye sky (path traced, CPU)");
    add_scene_options(cmd, &o->scene);  // scene, --camera, --look-at, --fov, --ground-albedo
    cmd->add_option(
        "--sky", o->sky,
        "Sky: a canonical fisheye EXR (square, equidistant, north up, east left; see 'dynsky sky'); a lat-long\n"
        "(equirect, 2:1) HDRI in Blender's mapping: its upper half becomes the fisheye sky, its lower half the\n"
        "ground (instead of the ground model); or one made here as 'animate' makes it: 'clear' (Hosek-Wilkie)\n"
        "or 'procedural[:SEED]' at --time, --lat, --lon.\n"
        "Default: a built-in clear sky (Paris, 2026-06-21 16:00 UTC, turbidity 3; with --time, --lat, --lon or --turbidity:\n"
        "'clear' there)");
    add_generated_sky_options(cmd, &o->generated);
    cmd->add_option("--out,-o", o->out,
                    "Output image: .exr (linear, with metadata; a tone-mapped .png is written beside it) or .png")
        ->capture_default_str();
    cmd->add_option("--res", o->resolution, "Image size WIDTHxHEIGHT")->capture_default_str();
    cmd->add_option("--spp", o->spp, "Samples per pixel")->check(CLI::Range(1, kMaxSpp))->capture_default_str();
    cmd->add_option("--seed", o->seed,
                    "Random seed: the same seed gives the same image on any thread count (not with --time-limit)")
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
    cmd->add_option(
        "--aovs", o->aovs,
        "Extra passes in the EXR, comma-separated: albedo ('Denoising Albedo'), normal ('Normal', world),\n"
        "depth ('Depth', camera Z, 1e10 on the sky), alpha (the 'A' channel: the sky seen from the camera\n"
        "becomes transparent and RGB premultiplied, as Cycles' Film > Transparent), samples ('Sample Count')");
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
    cmd->add_option(
           "--time-limit", o->time_limit,
           "Seconds of rendering after which no new round of 16 samples starts (0: none); --spp still caps.\n"
           "The only option whose image varies from run to run (the rounds done depend on the machine): the\n"
           "EXR records them (dynsky:rounds): --spp min(spp, 16 x rounds) without a time limit renders it again")
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
    cmd->footer(  // before the exit codes every command shows
        "Interrupted (Ctrl-C, SIGTERM), a render of more than 16 spp finishes its round of 16 samples and writes\n"
        "the image of the samples taken (exit 3); a second interrupt stops at once.\n\n" +
        exit_codes_help());
    cmd->callback([o, cmd] {
        warn_options_of_generated_skies(cmd, o->sky);
        run_render_job(*o);
    });
}

}  // namespace dynsky::cli
