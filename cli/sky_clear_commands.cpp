// dynsky sky clear | sun | latlong: analytic clear skies (Hosek-Wilkie), the sun's position, and
// lat-long export of any sky for Blender / Unreal.
#include <algorithm>
#include <iomanip>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>
#include <vector>

#include "cli/commands.h"
#include "cli/options.h"
#include "util/exposure.h"
#include "sky/clear_sky.h"
#include "sky/default_sky.h"
#include "sky/latlong.h"
#include "sky/sky_image.h"
#include "sky/sun_position.h"
#include "util/atomic_file.h"
#include "util/error.h"
#include "util/image.h"

namespace dynsky::cli {

namespace {

// The place and time default to every other command's (sky/default_sky.h: Paris, 2026-06-21T16:00Z).
struct SunOptions {
    double lat = default_sky::kLatitudeDeg, lon = default_sky::kLongitudeDeg, elevation_m = 0;
    std::string time = default_sky::kStartTime;
    bool no_refraction = false;
    double pressure_mbar = 1010, temperature_c = 10;
};

struct ClearOptions {
    SunOptions sun;
    double turbidity = 3.0, albedo = 0.3;
    bool no_sun = false;
    int resolution = 1024;
    std::string out, preview;
};

struct LatLongOptions {
    std::string sky, out, preview;
    int width = 0;
    std::string ground = "0";
};

void add_sun_options(CLI::App* cmd, SunOptions* o) {
    cmd->add_option("--lat", o->lat, "Latitude in degrees, north positive (-90..90)")
        ->check(finite_in(-90, 90))
        ->capture_default_str();
    cmd->add_option("--lon", o->lon,
                    "Longitude in degrees, EAST positive (-180..180, or 0..360); write --lon=-105.2 or --lon -105.2")
        ->check(finite_in(-360, 360))
        ->capture_default_str();
    cmd->add_option("--time", o->time,
                    "Date and time, ISO 8601 with a zone: 2026-06-21T12:00:00Z (UTC) or 2026-06-21T14:00:00+02:00")
        ->check(utc_time())
        ->capture_default_str();
    cmd->add_option("--elevation", o->elevation_m, "Height of the place above sea level in metres (default 0)")
        ->check(finite_in(-1000, 100000));
    CLI::Option* no_refraction = cmd->add_flag("--no-refraction", o->no_refraction,
                                               "Geometric position: no atmospheric refraction");
    // The air of a refraction that is off would be ignored silently (an options audit): refused.
    cmd->add_option("--pressure", o->pressure_mbar, "Air pressure for refraction, mbar (default 1010)")
        ->check(finite_above(0, 2000))
        ->excludes(no_refraction);
    cmd->add_option("--temperature", o->temperature_c, "Air temperature for refraction, Celsius (default 10)")
        ->check(finite_in(-100, 100))
        ->excludes(no_refraction);
}

SunPosition sun_from(const SunOptions& o, UtcTime* t) {
    *t = parse_utc_time(o.time);
    GeoLocation where{o.lat, o.lon, o.elevation_m};
    try {
        validate_location(where);
    } catch (const Error& e) {
        throw Error(std::string("--lat/--lon/--elevation: ") + e.what());
    }
    return compute_sun_position(*t, where, !o.no_refraction, o.pressure_mbar, o.temperature_c);
}

void print_sun(const SunPosition& s, const UtcTime& t, const SunOptions& o) {
    Vec3d d = s.direction();
    std::printf("time       %s\n", format_utc_time(t).c_str());
    std::printf("location   latitude %.6f deg, longitude %.6f deg (east positive), %.1f m\n", o.lat, o.lon,
                o.elevation_m);
    std::printf("zenith     %.5f deg (%s)\n", s.zenith_deg,
                o.no_refraction ? "geometric, no refraction" : "with refraction");
    std::printf("elevation  %.5f deg%s\n", s.elevation_deg(), s.elevation_deg() < 0 ? " (below the horizon)" : "");
    std::printf("azimuth    %.5f deg (from north towards east)\n", s.azimuth_deg);
    std::printf("direction  %.6f %.6f %.6f (world frame: +Y up, -Z north, +X east)\n", d.x(), d.y(), d.z());
}

void run_clear(const ClearOptions& o) {
    // Check everything before computing, so a bad run writes nothing.
    check_extension("--out", o.out, ".exr");
    if (!o.preview.empty()) check_extension("--preview", o.preview, ".png");
    // Every output before any work (a folder named as --preview failed after the sky was written).
    for (const std::string& f : {o.out, o.preview})
        if (!f.empty()) check_output_file(f);
    check_sky_resolution(o.resolution);
    validate_hosek_wilkie_range(o.turbidity, o.albedo);
    UtcTime t;
    SunPosition sun = sun_from(o.sun, &t);
    print_sun(sun, t, o.sun);

    ClearSkyParams params;
    params.sun_direction = sun.direction();
    params.turbidity = o.turbidity;
    params.ground_albedo = o.albedo;
    params.sun_disc = !o.no_sun;
    SkyImage sky = make_clear_sky(params, o.resolution);
    std::ostringstream source;
    source << std::setprecision(10) << sky.source << " time=" << format_utc_time(t) << " lat=" << o.sun.lat
           << " lon=" << o.sun.lon
           << " elevation_m=" << o.sun.elevation_m;  // all that places the sun (it was left out)
    if (o.sun.no_refraction) source << " refraction=off";
    else source << " pressure_mbar=" << o.sun.pressure_mbar << " temperature_c=" << o.sun.temperature_c;
    sky.source = source.str();
    save_sky(o.out, sky);
    std::printf("wrote %s (%dx%d fisheye, linear Rec.709 radiance in W m^-2 sr^-1; luminance = 683 Y cd/m^2)\n",
                o.out.c_str(), o.resolution, o.resolution);
    if (!o.preview.empty()) write_display_preview(o.preview, sky_to_image(sky));
}

Color parse_ground(const std::string& text) {
    std::vector<float> v;
    std::stringstream ss(text);
    std::string item;
    while (std::getline(ss, item, ',')) {
        try {
            size_t used = 0;
            float x = std::stof(item, &used);
            if (used != item.size() || !std::isfinite(x) || x < 0 || x > kMaxSkyRadiance)
                throw std::invalid_argument("bad");
            v.push_back(x);
        } catch (const std::exception&) {
            v.clear();
            break;
        }
    }
    if (v.size() == 1) return Color(v[0], v[0], v[0]);
    if (v.size() == 3) return Color(v[0], v[1], v[2]);
    throw Error("--ground '" + text + "': expected one radiance or R,G,B (numbers from 0 to 1e9, W m^-2 sr^-1)");
}

void run_latlong(const LatLongOptions& o) {
    check_extension("--out", o.out, ".exr");
    if (!o.preview.empty()) check_extension("--preview", o.preview, ".png");
    check_outputs_are_not_inputs({o.out, o.preview}, {o.sky});
    for (const std::string& f : {o.out, o.preview})
        if (!f.empty()) check_output_file(f);
    Color ground = parse_ground(o.ground);
    SkyImage sky = load_sky(o.sky);
    // At most what dynsky reads back (kMaxImageSide), the default too.
    int width = o.width > 0 ? o.width : std::min<int>(2 * sky.resolution, int(kMaxImageSide));
    if (width < 4 || width % 2 != 0 || width > kMaxImageSide)
        throw Error("--width " + std::to_string(width) + ": must be even, 4.." + std::to_string(kMaxImageSide) +
                    " (the image is W x W/2)");
    Image ll = sky_to_latlong(sky, width, ground);
    write_image(o.out, ll);
    std::printf(
        "wrote %s (%dx%d equirectangular: top row zenith, centre column east, north at u = 0.25; "
        "Blender's Environment Texture convention with north = +Y)\n",
        o.out.c_str(), ll.width, ll.height);
    if (!o.preview.empty()) write_display_preview(o.preview, ll);
}

}  // namespace

void register_sky_clear_commands(CLI::App& sky) {
    auto clear_opts = std::make_shared<ClearOptions>();
    CLI::App* clear = sky.add_subcommand(
        "clear",
        "Make an analytic clear sky (Hosek-Wilkie 2012 sky + 2013 solar disc) for a place and time, as a canonical\n"
        "fisheye EXR (equidistant, upper hemisphere, north up, east left). Pixels hold linear Rec.709 radiance in\n"
        "W m^-2 sr^-1 (the CIE-weighted integral of the spectral radiance; luminance in cd/m^2 = 683 Y). The sun\n"
        "position (Meeus/VSOP87, ~0.001 deg) is printed. A sun below the horizon is outside the model: the sky\n"
        "is made with the sun at the horizon and a warning is printed.");
    add_sun_options(clear, &clear_opts->sun);
    clear
        ->add_option("--turbidity", clear_opts->turbidity,
                     "Atmospheric turbidity, 1..10 (2: very clear, 3: clear, 6+: hazy; default 3)")
        ->check(finite_in(1, 10));
    clear->add_option("--albedo", clear_opts->albedo, "Ground albedo seen by the sky model, 0..1 (default 0.3)")
        ->check(finite_in(0, 1));
    clear->add_flag("--no-sun", clear_opts->no_sun, "Leave the solar disc out (sky only)");
    clear->add_option("--sky-res", clear_opts->resolution, "Fisheye size N in pixels (N x N), 16..16384")
        ->check(CLI::Range(kMinSkyResolution, kMaxSkyResolution))
        ->capture_default_str();
    clear->add_option("--out,-o", clear_opts->out, "Output sky, .exr")->required();
    clear->add_option("--preview", clear_opts->preview, "Also write a tone-mapped .png preview (auto exposure)");
    clear->callback([clear_opts] { run_clear(*clear_opts); });

    auto sun_opts = std::make_shared<SunOptions>();
    CLI::App* sun = sky.add_subcommand(
        "sun",
        "Print the sun's position for a place and time: topocentric zenith, elevation and azimuth (degrees,\n"
        "azimuth from north towards east) and its direction in the world frame. Meeus, Astronomical Algorithms\n"
        "(VSOP87 truncated, nutation, aberration, parallax), ~0.001 deg over 1950-2050; refraction by\n"
        "Saemundsson's formula unless --no-refraction.");
    add_sun_options(sun, sun_opts.get());
    // Its output is the answer: -q (which silences every other command's report) prints it bare, for
    // scripts: `elevation azimuth` in degrees on one line (it printed nothing at all).
    auto sun_bare = std::make_shared<bool>(false);
    sun->add_flag("-q,--quiet", *sun_bare, "Print only the elevation and azimuth (degrees), on one line");
    sun->callback([sun_opts, sun_bare] {
        UtcTime t;
        SunPosition s = sun_from(*sun_opts, &t);
        if (*sun_bare) std::printf("%.6f %.6f\n", s.elevation_deg(), s.azimuth_deg);
        else print_sun(s, t, *sun_opts);
    });

    auto ll_opts = std::make_shared<LatLongOptions>();
    CLI::App* ll = sky.add_subcommand(
        "latlong",
        "Convert a fisheye sky EXR to an equirectangular (lat-long) EXR, W x W/2, for Blender, Unreal and other\n"
        "HDRI users: top row zenith, middle horizon, lower half a constant ground; azimuth increases to the right\n"
        "with north at u = 0.25, east in the centre column (u = 0.5), south at 0.75, west at the edges. That is\n"
        "Blender's Environment Texture mapping for a world with north = +Y, where Blender's glTF importer puts\n"
        "our north (-Z). Energy-preserving: a one-pixel sun is neither missed nor doubled.");
    ll->add_option("sky", ll_opts->sky, "Input fisheye sky (.exr)")->required();
    ll->add_option("--out,-o", ll_opts->out, "Output lat-long image, .exr")->required();
    ll->add_option("--width", ll_opts->width,
                   "Width W in pixels, even (height W/2); default 2N for an N x N sky, at most 16384")
        ->check(CLI::Range(4, int(kMaxImageSide)));  // what dynsky reads back (docs/input-limits.md)
    ll->add_option("--ground", ll_opts->ground,
                   "Radiance of the lower half: one value or R,G,B in W m^-2 sr^-1 (default 0, black)");
    ll->add_option("--preview", ll_opts->preview, "Also write a tone-mapped .png preview (auto exposure)");
    ll->callback([ll_opts] { run_latlong(*ll_opts); });
}

}  // namespace dynsky::cli
