#include "cli/options.h"

#include <cmath>
#include <cstdio>

#include "sky/sky_image.h"
#include "sky/sun_position.h"
#include "util/error.h"
#include "util/parse.h"

namespace dynsky::cli {

namespace {

CLI::Validator finite_range(double min, double max, bool open_min, bool open_max = false) {
    std::string range = (open_min ? "(" : "[") + number_text(min) + ", " + number_text(max) + (open_max ? ")" : "]");
    return CLI::Validator(
        [=](std::string& text) -> std::string {
            double v = 0;
            if (!CLI::detail::lexical_cast(text, v)) return "'" + text + "' is not a number";
            if (!std::isfinite(v)) return "'" + text + "' is not a finite number in " + range;
            if (v < min || v > max || (open_min && v == min) || (open_max && v == max))
                return "'" + text + "' is outside " + range;
            return "";
        },
        "in " + range);
}

}  // namespace

CLI::Validator non_negative_whole() {
    return CLI::Validator(
        [](std::string& text) -> std::string {
            try {
                parse_seed(text, "");  // up to 2^64 - 1, as `animate --seed-per-frame` makes them
            } catch (const Error& e) {
                return std::string(e.what()).substr(2);  // without the empty name's ": "
            }
            return "";
        },
        "a whole number >= 0");
}

CLI::Validator finite_in(double min, double max) { return finite_range(min, max, false); }

CLI::Validator utc_time() {
    return CLI::Validator(
        [](std::string& text) -> std::string {
            try {
                const UtcTime t = parse_utc_time(text);
                // A year of 0201 or 9999 is a typo, not a sky: the sun's position (Meeus, ~0.001 deg
                // over 1950-2050) and the clock's Delta T are not modelled that far out.
                if (t.year < 1800 || t.year > 2200)
                    return "'" + text + "': the year " + std::to_string(t.year) +
                           " is outside 1800-2200, where the sun's position is computed";
            } catch (const Error& e) {
                return e.what();
            }
            return "";
        },
        "ISO 8601 with a zone");
}
CLI::Validator finite_above(double min, double max) { return finite_range(min, max, true); }

CLI::Validator finite_below(double min, double max) { return finite_range(min, max, false, true); }

CLI::Validator parsed_by(std::function<void(const std::string&)> parse, const std::string& what) {
    return CLI::Validator(
        [parse](std::string& text) -> std::string {
            try {
                parse(text);
            } catch (const Error& e) {
                return e.what();
            }
            return "";
        },
        what);
}

void add_scene_options(CLI::App* cmd, SceneSpec* o) {
    cmd->add_option(
           "scene", o->scene,
           "Scene: a .gltf/.glb file (scenes/tower/tower.gltf, scenes/house/house.gltf) or 'builtin' (the built-in plaza)")
        ->capture_default_str();
    cmd->add_option(
           "--camera", o->camera,
           "Index of the glTF camera, perspective or orthographic (the bounds are framed when the file has none)")
        ->check(CLI::Range(0, 1 << 20))
        ->capture_default_str();
    cmd->add_option("--look-at", o->look_at,
                    "Camera override: eye_x,eye_y,eye_z,target_x,target_y,target_z (world metres, +Y up)")
        ->delimiter(',')
        ->expected(6);
    cmd->add_option("--fov", o->fov_deg, "Vertical field of view in degrees, 0.01..179.9 (overrides the camera's)")
        ->check(finite_in(0.01, 179.9));
    cmd->add_option("--anim-time", o->animation_time,
                    "Pose the glTF's animations (nodes, skins, morph targets) at this time in seconds, held at their "
                    "ends (default: the rest pose)")
        ->check(finite_in(0, 1e9));
    cmd->add_option("--animation", o->animation,
                    "Play only this one of the glTF's animations, by name (the first of that name), else by index\n"
                    "(default: all of them, as one timeline; a file exported with several actions, Idle, Walk, Run,\n"
                    "plays them all at once)");
    cmd->add_option(
           "--ground-albedo", o->ground_albedo,
           "Albedo of the ground model below the horizon: a Lambertian plane lit by the sky, radiance albedo * E_sky / pi")
        ->check(finite_in(0, 1))
        ->capture_default_str();
}

void warn_options_of_generated_skies(const CLI::App* cmd, const std::string& sky) {
    auto given = [&](const char* name) {
        const CLI::Option* opt = cmd->get_option_no_throw(name);
        return opt && opt->count() > 0;
    };
    if (sky.empty() || is_generated_sky(sky)) {
        if (given("--sky-turn"))
            throw Error("--sky-turn turns a sky file; " +
                        std::string(sky.empty() ? "the built-in sky" : "'" + sky + "'") +
                        " is made here with its sun where --time, --lat and --lon put it");
        // Cloud cover shapes the procedural sky only: a clear sky given it was the same sky, and
        // its frames were made again on a resume for no change.
        for (const char* shape : {"--coverage", "--evolution"})
            if (sky == "clear" && given(shape))
                std::fprintf(stderr,
                             "dynsky: warning: %s shapes the procedural sky; 'clear' has no clouds: %s is ignored\n",
                             shape, shape);
        return;
    }
    for (const char* shape : {"--coverage", "--evolution"})
        if (given(shape))
            std::fprintf(stderr,
                         "dynsky: warning: %s shapes the procedural sky; %s is a file and keeps its own clouds: "
                         "%s is ignored\n",
                         shape, sky.c_str(), shape);
    if (given("--turbidity"))
        std::fprintf(stderr,
                     "dynsky: warning: --turbidity sets the haze of a sky made here; %s is a file and keeps its own: "
                     "--turbidity is ignored\n",
                     sky.c_str());
    // A sky file keeps its own sun unless --time puts it on the clock, at --lat and --lon: without
    // it they changed nothing, silently (render refuses them).
    if ((given("--lat") || given("--lon")) && !given("--time") && cmd->get_name() != "render")  // render refuses
        std::fprintf(stderr,
                     "dynsky: warning: %s keeps the sun it has: --lat and --lon place the sun only with --time "
                     "(the sun follows the clock from there); ignored\n",
                     sky.c_str());
}

void add_sky_source_options(CLI::App* cmd, SkySourceSpec* o, StepModelSpec* m) {
    cmd->parse_complete_callback([cmd, o] { warn_options_of_generated_skies(cmd, o->sky); });
    cmd->add_option(
           "--sky", o->sky,
           "Input sky at t = 0: 'procedural[:SEED]' (cumulus over a clear sky, known motion), 'clear' (Hosek-Wilkie),\n"
           "a canonical fisheye EXR (from 'dynsky sky clear|import|procedural|predict'; photographs: import first), or a\n"
           "folder of them (a captured sequence: the last is the input, the one before it gives the motion)")
        ->capture_default_str();
    cmd->add_option(
           "--model", m->model,
           "Medium-step model xi: 'auto' (the shipped advect-residual network, networks/models/advect_residual:\n"
           "clouds advected along the motion, a small network corrects; pure advection when not installed),\n"
           "'advect' (pure advection along the motion), 'paper' (the paper's FlowNet + CloudNet,\n"
           "networks/models/arm_tsi), 'procedural' (the procedural sky's own next frame; procedural input only),\n"
           "'flow' (extrapolate the Farneback flow of the last two steps; a uniform drift first), or\n"
           "a model folder ('network:FOLDER' or the folder). The motion: --prev when given, else the wind\n"
           "(--wind-from, --wind-speed, --cloud-height)")
        ->capture_default_str();
    cmd->add_option(
           "--dt", m->dt,
           "Delta t: seconds between medium steps (0: the model's own: a network's from its model.json, 30 for\n"
           "advect, 10 for procedural and flow)")
        ->check(finite_in(0, 86400))
        ->capture_default_str();
    cmd->add_option(
           "--gamma", m->gamma,
           "The in-between of two medium steps: 'constant' (both steps advected along the motion to the\n"
           "frame's moment and cross-faded by time: an even pace) or 'paper' (the paper's keys at 1/3 and 2/3:\n"
           "all change in the middle third of each interval)")
        ->check(CLI::IsMember({"constant", "paper"}))
        ->capture_default_str();
    add_generated_sky_options(cmd, o);
    cmd->add_option("--coverage", o->coverage, "Cloud cover of the procedural sky, 0..1")
        ->check(finite_in(0, 1))
        ->capture_default_str();
    cmd->add_option("--evolution", o->evolution_s,
                    "Seconds for the procedural sky's cumulus shapes to change completely (0, or 1..1e7); 0 freezes\n"
                    "them (the clouds moved by the wind alone, as a model from one frame moves them)")
        ->check(finite_in(0, 1e7))
        ->capture_default_str();
    cmd->add_option("--wind-from", o->wind_from_deg,
                    "Where the wind at the clouds blows from, degrees clockwise from north (moves the procedural\n"
                    "sky and, for any input sky, the clouds of the models that take a motion)")
        ->check(finite_in(-360, 360))
        ->each([o](const std::string&) { o->wind_given = true; })
        ->capture_default_str();
    cmd->add_option("--wind-speed", o->wind_speed_mps, "Wind speed at the clouds, m/s")
        ->check(finite_in(0, 300))
        ->each([o](const std::string&) { o->wind_given = true; })
        ->capture_default_str();
    cmd->add_option(
           "--cloud-height", o->cloud_height_m,
           "Height of the cloud layer the wind moves, metres (1500: fair-weather cumulus; only speed / height\n"
           "matters for the motion seen from the ground)")
        ->check(finite_in(10, 1e5))
        ->capture_default_str();
    cmd->add_option(
        "--prev", o->previous,
        "A previous frame of the input sky (canonical fisheye EXR): the clouds' motion is measured from it, and "
        "the share of the network's first correction the pair supports");
    cmd->add_option("--prev-dt", o->previous_dt, kPrevDtHelp)->check(finite_in(0, 86400))->capture_default_str();
    cmd->add_option("--drift", m->drift_deg_per_s,
                    "Flow model: first-step drift of a single input sky, degrees per second")
        ->check(finite_in(-360, 360))
        ->capture_default_str();
}

void add_generated_sky_options(CLI::App* cmd, SkySourceSpec* o) {
    cmd->add_option("--sky-res", o->sky_resolution, kSkyResHelp)
        ->check(CLI::Range(kMinSkyResolution, kMaxSkyResolution))
        ->each([o](const std::string&) { o->sky_resolution_given = true; });
    cmd->add_option("--sky-turn", o->sky_turn_deg, kSkyTurnHelp)->check(finite_in(-360, 360));
    cmd->add_option(
           "--time", o->time,
           "UTC time of t = 0, ISO 8601 (e.g. 2026-06-21T16:00:00Z): the sun follows the clock from there.\n"
           "Default for 'procedural' and 'clear': 2026-06-21T16:00:00Z (at --lat, --lon: Paris). For an EXR: without\n"
           "--time the sun stays where the file has it; with it, animate, compare and sky timeline start the clock\n"
           "there and move the file's sun to it (a warning when the file records another), render refuses it")
        ->check(utc_time());
    cmd->add_option("--turbidity", o->turbidity,
                    "Turbidity of the Hosek-Wilkie sky made here ('clear', and the clear sky under 'procedural'\n"
                    "clouds), 1..10 (2: very clear, 3: clear, 6+: hazy), as 'sky clear --turbidity'")
        ->check(finite_in(1, 10))
        ->capture_default_str();
    cmd->add_option("--lat", o->latitude, "Latitude of the place, degrees north (with --time)")
        ->check(finite_in(-90, 90))
        ->capture_default_str();
    cmd->add_option("--lon", o->longitude, "Longitude of the place, degrees east (with --time)")
        ->check(finite_in(-360, 360))
        ->capture_default_str();
}

void add_quiet_flag(CLI::App* cmd) {
    cmd->add_flag_callback(
        "-q,--quiet", [] { std::fflush(stdout), std::freopen("/dev/null", "w", stdout); },
        "No report or progress (warnings and errors still go to stderr)");
}

}  // namespace dynsky::cli
