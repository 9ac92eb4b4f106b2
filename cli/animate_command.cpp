// dynsky animate: a lit scene under a moving sky, frame by frame, resumable (frame/animation.h).
#include <cstdio>
#include <memory>
#include <string>

#include "cli/commands.h"
#include "cli/options.h"
#include "frame/animation.h"
#include "util/error.h"
#include "util/parse.h"

namespace dynsky::cli {

namespace {

struct AnimateOptions {
    AnimationSettings settings;
    std::string resolution = "480x270";
    bool count_frames = false;
};

}  // namespace

void register_animate_command(CLI::App& app) {
    auto o = std::make_shared<AnimateOptions>();
    AnimationSettings* a = &o->settings;
    CLI::App* cmd = app.add_subcommand(
        "animate",
        "Render a scene under a moving sky: numbered linear EXR + PNG frames, sky frames, MP4s and a contact sheet.\n"
        "Resumable: frames already complete in --out and made with the same settings are kept; damaged frames and\n"
        "frames of other settings are rendered again (it says which and why). Kill it at any moment and run it again.");
    // A repeated option takes its last value, so wrappers (scripts/demo.sh) can be overridden.
    cmd->option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
    add_scene_options(cmd, &a->scene);
    add_sky_source_options(cmd, &a->sky, &a->model);
    cmd->add_option("--duration", a->duration, "Length of the animation in seconds of sky time")
        ->check(finite_above(0, 1e9))
        ->capture_default_str();
    cmd->add_option("--fps", a->fps, "Frames per second (frame k shows the sky at t = k / fps)")
        ->check(finite_above(0, 1000))
        ->capture_default_str();
    cmd->add_option("--spp", a->spp, "Samples per pixel")->check(CLI::Range(1, kMaxSpp))->capture_default_str();
    cmd->add_option("--res", o->resolution, "Frame size WIDTHxHEIGHT")->capture_default_str();
    cmd->add_option(
           "--out,-o", a->out,
           "Output folder: frame_NNNN.exr/.png, sky_NNNN.png, timings.csv, contact_sheet.png, animation.mp4, sky.mp4")
        ->capture_default_str();
    cmd->add_option("--frames", a->frames, "Render only frames A-B (inclusive, numbered from 0), e.g. 0-11 or 5");
    cmd->add_option("--seed", a->seed, "Random seed of the path tracer")
        ->check(non_negative_whole())
        ->capture_default_str();
    cmd->add_flag(
        "--seed-per-frame", a->seed_per_frame,
        "A different seed every frame (independent noise; default: the same seed every frame, i.e. correlated\n"
        "sampling, which keeps Monte Carlo noise from flickering between frames)");
    cmd->add_flag("--play-anim", a->play_scene_animation,
                  "Play the glTF's animations along the frames: the frame at t s poses the scene at --anim-time + t "
                  "(the file is loaded once and posed per frame)");
    cmd->add_option("--threads", a->threads, "Worker threads (0: all cores)")
        ->check(CLI::Range(0, kMaxThreads))
        ->capture_default_str();
    cmd->add_option("--max-depth", a->max_depth, "Maximum path length (bounces)")
        ->check(CLI::Range(0, kMaxDepth))
        ->capture_default_str();
    cmd->add_option(
           "--exposure", a->exposure,
           "PNG exposure in stops for every frame (default: from the sky's irradiance at t = 0, the same for all frames)")
        ->check(finite_in(-64, 64));
    cmd->add_flag(
        "--exposure-follows-sun", a->exposure_follows_sun,
        "The PNGs' exposure follows the clear sky's light at each frame's sun, from that at t = 0 (for\n"
        "animations through sunrise or sunset, whose PNGs otherwise clip white or go black; passing clouds do\n"
        "not move it, so it does not flicker); the EXRs are the same either way");
    cmd->add_option("--aovs", a->aovs,
                    "Extra passes in each frame's EXR: albedo, normal, depth, alpha (as for 'dynsky render')");
    cmd->add_option("--clamp-indirect", a->clamp_indirect,
                    "Firefly clamp of indirect light, sum of RGB per sample (0: off; as for 'dynsky render')")
        ->capture_default_str();
    cmd->add_option("--filter-glossy", a->filter_glossy,
                    "Roughen reflections after the first bounce (0: off; as for 'dynsky render')")
        ->capture_default_str();
    cmd->add_option("--sampler-pattern", a->sampler_pattern, "Sample values: random or sobol (as for 'dynsky render')")
        ->capture_default_str();
    cmd->add_flag("--force", a->force, "Render every frame again, even those complete with the same settings");
    cmd->add_flag("--no-video", a->no_video, "Do not run ffmpeg (no MP4s)");
    cmd->add_flag("--quiet,-q", a->quiet, "No per-frame report");
    cmd->add_option("--timeline", a->timeline,
                    "Read the medium steps from this stored timeline folder ('dynsky sky timeline' or --stage keys)\n"
                    "instead of computing them; the frames are the same bytes either way (docs/render-farm.md)");
    cmd->add_option("--stage", a->stage,
                    "For render farms (docs/render-farm.md): all (render, then encode once complete), keys (write\n"
                    "--timeline for the whole duration), frames (render --frames only: no videos or contact sheet),\n"
                    "encode (render nothing: every frame must be complete; the MP4s and contact sheet)")
        ->check(CLI::IsMember({"all", "keys", "frames", "encode"}))
        ->capture_default_str();
    cmd->add_flag("--count-frames", o->count_frames,
                  "Print the animation's number of frames (round(duration x fps)) and exit (for farm scripts)");
    CLI::Option* look_at = cmd->get_option("--look-at");
    cmd->callback([o, look_at] {
        // Each --look-at gives 6 numbers; the last one given counts (TakeLast keeps 6 of 7 otherwise).
        if (look_at->count() && look_at->results().size() % 6 != 0)
            throw Error("--look-at takes 6 numbers, eye_x,eye_y,eye_z,target_x,target_y,target_z (got " +
                        std::to_string(look_at->results().size()) + ")");
        parse_frame_size(o->resolution, &o->settings.width, &o->settings.height);
        if (o->count_frames) {
            check_animation_settings(o->settings, /*inputs_exist=*/true);  // a typo fails before a farm queues
            std::printf("%d\n", animation_frame_count(o->settings));
            return;
        }
        render_animation(o->settings);
    });
}

}  // namespace dynsky::cli
