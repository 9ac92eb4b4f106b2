// dynsky sky procedural: a sequence of procedural cloudy skies with their exact flow fields
// (sky/procedural_sequence.h).
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "cli/options.h"
#include "sky/procedural_sequence.h"
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
    cmd->add_option("--seed", o->seed, "Random seed: the same seed and options give identical frames")
        ->check(non_negative_whole())
        ->capture_default_str();
    cmd->add_option("--coverage", o->coverage, "Fraction of each cloud layer holding cloud, 0 (clear) to 1 (overcast)")
        ->check(finite_in(0, 1))
        ->capture_default_str();
    cmd->add_option("--duration", o->duration, "Length of the sequence in seconds (frames at 0, dt, ..., <= duration)")
        ->check(finite_in(0, 1e9))
        ->capture_default_str();
    cmd->add_option("--dt", o->dt, "Time step between frames in seconds; also the span of each flow field")
        ->check(finite_above(0, 86400))
        ->capture_default_str();
    cmd->add_option("--sky-res", o->resolution, "Resolution N of the N x N fisheye images (8..16384)")
        ->check(CLI::Range(8, 16384))
        ->capture_default_str();
    add_hidden_alias(cmd, "--res", &o->resolution);
    cmd->add_option("--out,-o", o->out, "Output folder (created if missing; files in it are overwritten)")->required();
    cmd->add_option("--layers", o->layers, "Cloud layers, comma-separated: cumulus, cirrus")
        ->delimiter(',')
        ->capture_default_str();
    cmd->add_option("--wind", o->wind,
                    "Cumulus wind as SPEED,DIR: speed in m/s and the direction it blows FROM in degrees clockwise\n"
                    "from north (weather convention: 270 = from the west, clouds drift east). Default 8,270")
        ->delimiter(',')
        ->expected(2);
    cmd->add_option("--cirrus-wind", o->cirrus_wind, "Cirrus wind as SPEED,DIR (as --wind). Default 25,260")
        ->delimiter(',')
        ->expected(2);
    cmd->add_option("--cumulus-altitude", o->cumulus_altitude, "Height of the cumulus layer above the viewer, metres")
        ->check(finite_above(0, 1e5))
        ->capture_default_str();
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
    cmd->add_option("--mask-detail", o->mask_detail, "How much noise erodes the mask's soft edges, in [0, 1)")
        ->check(finite_in(0, 1))
        ->capture_default_str();
    auto* elevation = cmd->add_option("--sun-elevation", o->sun_elevation, "Sun elevation above the horizon, degrees")
                          ->check(finite_in(-90, 90))
                          ->capture_default_str();
    auto* azimuth = cmd->add_option("--sun-azimuth", o->sun_azimuth, "Sun azimuth, degrees clockwise from north")
                        ->check(finite_in(-360, 360))
                        ->capture_default_str();
    auto* lat = cmd->add_option("--lat", o->latitude,
                                "Latitude in degrees (north +); with --lon and --time the sun\n"
                                "follows its true path over the sequence")
                    ->check(finite_in(-90, 90));
    auto* lon = cmd->add_option("--lon", o->longitude, "Longitude in degrees (east +)")->check(finite_in(-360, 360));
    auto* time = cmd->add_option("--time", o->time_iso, "Start time, ISO 8601 with a zone, e.g. 2024-06-21T14:00:00Z")
                     ->check(utc_time());
    lat->excludes(elevation)->excludes(azimuth);
    lon->excludes(elevation)->excludes(azimuth);
    time->excludes(elevation)->excludes(azimuth);
    cmd->add_option("--turbidity", o->turbidity, "Clear-sky turbidity, 1..10 (2 very clear, 3 clear, 6+ hazy)")
        ->check(finite_in(1, 10))
        ->capture_default_str();
    cmd->add_option("--visibility", o->visibility, "Distance in metres over which far clouds fade into the sky (1/e)")
        ->check(finite_above(0, 1e9))
        ->capture_default_str();
    cmd->add_flag("--preview", o->preview,
                  "Also write tone-mapped PNGs: frame_NNNN.png and flow_NNNN.png (colour-coded)");
    cmd->add_flag("--quiet,-q", o->quiet, "No progress bar or summary");
    cmd->callback([o, lat, lon, time]() {
        int given = int(lat->count() > 0) + int(lon->count() > 0) + int(time->count() > 0);
        if (given != 0 && given != 3) throw Error("--lat, --lon and --time go together: give all three or none");
        // The same ranges as animate's --wind-speed and --wind-from.
        auto check_wind = [](const char* name, const std::vector<double>& w) {
            if (w.size() == 2 && w[0] >= 0 && w[0] <= 300 && std::abs(w[1]) <= 360) return;
            throw Error(std::string(name) + ": SPEED,DIR takes a speed of 0..300 m/s and a direction of -360..360 " +
                        "degrees" +
                        (w.size() == 2 ? " (got " + number_text(w[0]) + "," + number_text(w[1]) + ")" : ""));
        };
        if (!o->wind.empty()) check_wind("--wind", o->wind);
        if (!o->cirrus_wind.empty()) check_wind("--cirrus-wind", o->cirrus_wind);
        if (o->evolution > 0 && o->evolution < 1)
            throw Error("--evolution: " + number_text(o->evolution) + " s: give 0 (frozen shapes) or at least 1 s");
        check_outputs_are_not_inputs({o->out}, {o->mask_image});
        remove_stale_temporaries(o->out);  // of a killed run into the same folder
        write_procedural_sequence(*o, given == 3);
    });
}

}  // namespace dynsky::cli
