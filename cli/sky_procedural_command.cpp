// dynsky sky procedural: a sequence of procedural cloudy skies with their exact flow fields
// (sky/procedural_sequence.h).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "cli/options.h"
#include "sky/procedural_sequence.h"
#include "sky/sky_image.h"
#include "util/atomic_file.h"
#include "util/error.h"
#include "util/parse.h"

namespace dynsky::cli {

void register_sky_procedural_command(CLI::App& sky) {
    auto o = std::make_shared<ProceduralSequenceSettings>();
    CLI::App* cmd = sky.add_subcommand(
        "procedural",
        "Procedural cloudy skies with known motion: cloud layers (cumulus at 1.5 km, cirrus at 8 km)\n"
        "drifting with the wind and slowly changing shape over a Hosek-Wilkie clear sky. Writes\n"
        "DIR/frame_0000.exr ... (canonical fisheye radiance, W m^-2 sr^-1), DIR/flow_0000.exr ...\n"
        "(the exact motion of the clouds over --dt: channels R = dx, G = dy in pixels of the image, +x\n"
        "right, +y down, B = the cloud opacity) and DIR/manifest.json. Frames are at t = 0, dt, 2 dt, ...\n"
        "up to --duration. See docs/procedural-sky.md.");
    cmd->add_option("--cloud-seed", o->cloud_seed,
                    "The clouds' random seed (as SEED of --sky procedural:SEED elsewhere): the same seed and\n"
                    "options give identical frames")
        ->check(non_negative_whole())
        ->capture_default_str();
    // --seed is the path tracer's seed in render, animate and compare: here it would mean another
    // thing, so it is refused with the name to use.
    // The values of the refused and old spellings below, alive as long as the command.
    struct OtherSpellings {
        std::string seed;
        std::vector<double> wind;
    };
    auto other = std::make_shared<OtherSpellings>();
    auto* path_tracer_seed = cmd->add_option("--seed", other->seed)->group("");
    cmd->add_option("--coverage", o->coverage, "Fraction of each cloud layer holding cloud, 0 (clear) to 1 (overcast)")
        ->check(finite_in(0, 1))
        ->capture_default_str();
    cmd->add_option("--duration", o->duration, "Length of the sequence in seconds (frames at 0, dt, ..., <= duration)")
        ->check(finite_in(0, 1e9))
        ->capture_default_str();
    cmd->add_option("--dt", o->dt,
                    "Delta t: seconds between frames, each a step of the clouds' motion (as\n"
                    "animate's --dt); the span of each flow field")
        ->check(finite_above(0, 86400))
        ->capture_default_str();
    cmd->add_option("--sky-res", o->resolution, "Resolution N of the N x N fisheye images (16..16384)")
        ->check(CLI::Range(kMinSkyResolution, kMaxSkyResolution))
        ->capture_default_str();
    cmd->add_option("--out,-o", o->out, "Output folder (created if missing; files in it are overwritten)")->required();
    cmd->add_option("--layers", o->layers, "Cloud layers, comma-separated: cumulus, cirrus")
        ->delimiter(',')
        ->capture_default_str();
    auto* wind_from =
        cmd->add_option("--wind-from", o->wind_from_deg,
                        "Where the wind at the cumulus blows from, degrees clockwise from north (weather\n"
                        "convention: 270 = from the west, clouds drift east)")
            ->check(finite_in(-360, 360))
            ->capture_default_str();
    auto* wind_speed = cmd->add_option("--wind-speed", o->wind_speed_mps, "Wind speed at the cumulus, m/s")
                           ->check(finite_in(0, 300))
                           ->capture_default_str();
    // The old form SPEED,DIR of the two above.
    auto* wind_pair = cmd->add_option("--wind", other->wind)->group("")->delimiter(',')->expected(2);
    cmd->add_option("--cirrus-wind", o->cirrus_wind,
                    "Cirrus wind as SPEED,DIR: m/s and where it blows from, degrees (as --wind-speed,\n"
                    "--wind-from). Default 25,260")
        ->delimiter(',')
        ->expected(2);
    cmd->add_option("--cloud-height", o->cloud_height_m,
                    "Height of the cumulus layer above the viewer, metres (1500: fair-weather cumulus)")
        ->check(finite_in(10, 1e5))
        ->capture_default_str();
    add_hidden_alias(cmd, "--cumulus-altitude", &o->cloud_height_m)->check(finite_in(10, 1e5));  // as --cloud-height
    cmd->add_option("--evolution", o->evolution,
                    "Seconds for the cumulus shapes to change completely (0, or 1..1e7); 0 freezes them (pure\n"
                    "advection)")
        ->check(finite_in(0, 1e7))
        ->capture_default_str();
    cmd->add_option("--mask-image", o->mask_image,
                    "Grey or alpha image (PNG, EXR, ...) of cloud density for the first layer, seen from below\n"
                    "(north up, east left), centred overhead at t = 0 and drifting with the wind");
    cmd->add_option("--mask-extent", o->mask_extent,
                    "Width in metres of the square the mask covers on its layer (0: out to 60 deg from the zenith)")
        ->check(finite_in(0, 1e7))
        ->capture_default_str();
    cmd->add_option("--mask-detail", o->mask_detail,
                    "How much noise erodes the mask's soft edges (1 would erode the mask away)")
        ->check(finite_below(0, 1))
        ->capture_default_str();
    auto* elevation = cmd->add_option("--sun-elevation", o->sun_elevation,
                                      "A sun fixed at this elevation above the horizon, degrees (instead of the\n"
                                      "sun of --time at --lat, --lon)")
                          ->check(finite_in(-90, 90))
                          ->capture_default_str();
    auto* azimuth = cmd->add_option("--sun-azimuth", o->sun_azimuth,
                                    "A fixed sun's azimuth, degrees clockwise from north")
                        ->check(finite_in(-360, 360))
                        ->capture_default_str();
    // The same place and time as animate's, compare's and render's skies (sky/default_sky.h).
    auto* lat = cmd->add_option("--lat", o->latitude,
                                "Latitude of the place, degrees north (the sun follows the clock)")
                    ->check(finite_in(-90, 90))
                    ->capture_default_str();
    auto* lon = cmd->add_option("--lon", o->longitude, "Longitude of the place, degrees east")
                    ->check(finite_in(-360, 360))
                    ->capture_default_str();
    auto* time = cmd->add_option("--time", o->time_iso, "UTC time of t = 0, ISO 8601 with a zone")
                     ->check(utc_time())
                     ->capture_default_str();
    lat->excludes(elevation)->excludes(azimuth);
    lon->excludes(elevation)->excludes(azimuth);
    time->excludes(elevation)->excludes(azimuth);
    cmd->add_option("--turbidity", o->turbidity, "Clear-sky turbidity, 1..10 (2 very clear, 3 clear, 6+ hazy)")
        ->check(finite_in(1, 10))
        ->capture_default_str();
    cmd->add_option("--visibility", o->visibility, "Distance in metres over which far clouds fade into the sky (1/e)")
        ->check(finite_above(0, 1e9))
        ->capture_default_str();
    cmd->add_flag("--previews", o->preview,
                  "Also write tone-mapped PNGs: frame_NNNN.png and flow_NNNN.png (colour-coded)");
    cmd->add_flag("--quiet,-q", o->quiet, "No progress bar or summary");
    cmd->callback([cmd, o, other, elevation, azimuth, path_tracer_seed, wind_pair, wind_from, wind_speed]() {
        if (path_tracer_seed->count() > 0)
            throw Error(
                "--seed is the path tracer's seed (render, animate, compare); the clouds' seed here is "
                "--cloud-seed");
        o->fixed_sun = elevation->count() > 0 || azimuth->count() > 0;
        // The same ranges as animate's --wind-speed and --wind-from.
        auto check_wind = [](const char* name, const std::vector<double>& w) {
            if (w.size() == 2 && w[0] >= 0 && w[0] <= 300 && std::abs(w[1]) <= 360) return;
            throw Error(std::string(name) + ": SPEED,DIR takes a speed of 0..300 m/s and a direction of -360..360 " +
                        "degrees" +
                        (w.size() == 2 ? " (got " + number_text(w[0]) + "," + number_text(w[1]) + ")" : ""));
        };
        if (wind_pair->count() > 0 && (wind_from->count() > 0 || wind_speed->count() > 0))
            throw Error("--wind SPEED,DIR is the old form of --wind-speed and --wind-from: give one form");
        if (wind_pair->count() > 0) {
            check_wind("--wind", other->wind);
            o->wind_speed_mps = other->wind[0], o->wind_from_deg = other->wind[1];
        }
        if (!o->cirrus_wind.empty()) check_wind("--cirrus-wind", o->cirrus_wind);
        if (o->evolution > 0 && o->evolution < 1)
            throw Error("--evolution: " + number_text(o->evolution) + " s: give 0 (frozen shapes) or at least 1 s");
        // Options that shape what was not asked for are said, as --coverage with a clear sky is.
        auto given = [&](const char* name) { return cmd->get_option(name)->count() > 0; };
        if (!o->cirrus_wind.empty() && std::find(o->layers.begin(), o->layers.end(), "cirrus") == o->layers.end())
            std::fprintf(stderr,
                         "dynsky: warning: --cirrus-wind moves the cirrus layer, which --layers does not ask for: "
                         "--cirrus-wind is ignored\n");
        if (o->mask_image.empty())
            for (const char* mask_option : {"--mask-extent", "--mask-detail"})
                if (given(mask_option))
                    std::fprintf(stderr,
                                 "dynsky: warning: %s shapes the --mask-image clouds; none is given: %s is ignored\n",
                                 mask_option, mask_option);
        check_outputs_are_not_inputs({o->out}, {o->mask_image});
        check_numbered_outputs_spare(o->out, {"frame", "flow"}, {o->mask_image});
        remove_stale_temporaries(o->out);  // of a killed run into the same folder
        write_procedural_sequence(*o);
    });
}

}  // namespace dynsky::cli
