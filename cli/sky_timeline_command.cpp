// dynsky sky timeline: the medium steps and flows of a whole duration, computed once and stored
// (frame/sky_source.h write_sky_timeline) for frames rendered elsewhere (`animate --timeline`).
#include <memory>
#include <string>

#include "cli/commands.h"
#include "cli/options.h"
#include "frame/sky_source.h"

namespace dynsky::cli {

namespace {

struct SkyTimelineOptions {
    SkySourceSpec sky;
    StepModelSpec model;
    double duration = 4.0;
    std::string out = "timeline";
    bool quiet = false;
};

}  // namespace

void register_sky_timeline_command(CLI::App& sky) {
    auto o = std::make_shared<SkyTimelineOptions>();
    CLI::App* cmd = sky.add_subcommand(
        "timeline",
        "Compute the medium steps, their flows and sun patches for a whole duration once and store them in a folder\n"
        "(step_NNNN.exr, flow_NNNN.npy, timeline.json): 'dynsky animate --timeline FOLDER' renders any frame range\n"
        "from it, anywhere, to the same bytes as one run (docs/render-farm.md). Takes the sky and model options of\n"
        "'animate'; a folder already holding a timeline of these settings that covers --duration is kept.");
    cmd->option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
    add_sky_source_options(cmd, &o->sky, &o->model);
    cmd->add_option("--duration", o->duration, "Seconds of sky time to cover (the animation's --duration)")
        ->check(finite_above(0, 1e9))
        ->capture_default_str();
    cmd->add_option("--out,-o", o->out, "Output folder")->capture_default_str();
    cmd->add_flag("--quiet,-q", o->quiet, "No report");
    cmd->callback([o] { write_sky_timeline(o->sky, o->model, o->duration, o->out, o->quiet); });
}

}  // namespace dynsky::cli
