// dynsky compare: clear against cloudy lighting (frame/clear_cloudy_comparison.h).
// dynsky temporal: temporal quality of an animation folder (frame/temporal_quality.h).
#include <memory>
#include <string>

#include "cli/commands.h"
#include "cli/options.h"
#include "frame/clear_cloudy_comparison.h"
#include "frame/temporal_quality.h"
#include "util/parse.h"

namespace dynsky::cli {

namespace {

struct CompareOptions {
    ComparisonSettings settings;
    std::string resolution = "640x360", chart_resolution = "160x90";
};

}  // namespace

void register_compare_command(CLI::App& app) {
    auto o = std::make_shared<CompareOptions>();
    ComparisonSettings* c = &o->settings;
    CLI::App* cmd = app.add_subcommand(
        "compare",
        "The same frame under the clear sky and the cloudy sky of the same sun position: side_by_side.png, difference.png,\n"
        "clear.exr, cloudy.exr, and illuminance.csv/.png (sky illuminance and luminance at chosen points over time)");
    add_scene_options(cmd, &c->scene);
    add_sky_source_options(cmd, &c->sky, &c->model);
    cmd->add_option("--res", o->resolution, "Size of the side-by-side frames, WIDTHxHEIGHT")->capture_default_str();
    cmd->add_option("--spp", c->spp, "Samples per pixel of the side-by-side frames")
        ->check(CLI::Range(1, kMaxSpp))
        ->capture_default_str();
    cmd->add_option("--out,-o", c->out, "Output folder")->capture_default_str();
    cmd->add_option("--points", c->points, "Chart points as fractions of the image: X,Y;X,Y;... (0,0 = top left)")
        ->capture_default_str();
    cmd->add_option("--duration", c->duration, "Chart: seconds of sky time")
        ->check(finite_above(0, 1e9))
        ->capture_default_str();
    cmd->add_option("--chart-frames", c->chart_frames, "Chart: frames rendered over --duration")
        ->check(CLI::Range(2, 100000))
        ->capture_default_str();
    cmd->add_option("--chart-res", o->chart_resolution, "Chart: frame size")->capture_default_str();
    cmd->add_option("--chart-spp", c->chart_spp, "Chart: samples per pixel (the same seed every frame)")
        ->check(CLI::Range(1, kMaxSpp))
        ->capture_default_str();
    cmd->add_option("--seed", c->seed, "Random seed of the path tracer")
        ->check(non_negative_whole())
        ->capture_default_str();
    cmd->add_option("--threads", c->threads, "Worker threads (0: all cores)")
        ->check(CLI::Range(0, kMaxThreads))
        ->capture_default_str();
    cmd->callback([o] {
        parse_frame_size(o->resolution, &o->settings.width, &o->settings.height);
        parse_frame_size(o->chart_resolution, &o->settings.chart_width, &o->settings.chart_height, "--chart-res");
        render_clear_cloudy_comparison(o->settings);
    });

    auto t = std::make_shared<std::string>();
    CLI::App* tc = app.add_subcommand(
        "temporal",
        "Temporal quality of a 'dynsky animate' folder: frame-to-frame luminance change, pairs across medium-step\n"
        "boundaries vs within intervals (popping), charted to temporal.png with temporal.csv. Run it on animations\n"
        "rendered with and without --seed-per-frame to measure Monte Carlo flicker");
    tc->add_option("folder", *t, "The animation folder (frame_NNNN.exr with their metadata)")->required();
    tc->callback([t] { analyse_temporal_quality(*t); });
}

}  // namespace dynsky::cli
