// dynsky sky procedural: a sequence of procedural cloudy skies with their exact flow fields.
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "sky/clear_sky.h"
#include "sky/fisheye.h"
#include "sky/procedural_clouds.h"
#include "sky/sun_position.h"
#include "util/error.h"
#include "util/atomic_file.h"
#include "util/image.h"
#include "util/progress.h"

namespace dynsky::cli {

namespace {

namespace fs = std::filesystem;

struct ProceduralOptions {
    uint64_t seed = 0;
    double coverage = 0.4;
    double duration = 60.0;
    double dt = 10.0;
    int resolution = 512;
    std::string out;
    std::vector<std::string> layers = {"cumulus"};
    std::vector<double> wind;         // SPEED,FROM_DEG of the cumulus layer
    std::vector<double> cirrus_wind;  // SPEED,FROM_DEG of the cirrus layer
    double cumulus_altitude = 1500.0;
    double evolution = 900.0;
    std::string mask_image;
    double mask_extent = 0.0;
    double mask_detail = 0.35;
    double sun_elevation = 45.0, sun_azimuth = 180.0;
    double latitude = 0.0, longitude = 0.0;
    std::string time_iso;
    double turbidity = 3.0;
    double visibility = 40000.0;
    bool preview = false, quiet = false;
};

std::string frame_name(const char* prefix, int index, const char* ext) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s_%05d%s", prefix, index, ext);
    return buf;
}

// Flow as colour (hue: direction, saturation: speed relative to max_speed), dimmed where there
// is no cloud: for looking at, not for measuring.
Image flow_preview(const Image& flow, double max_speed) {
    cv::Mat hsv(flow.height, flow.width, CV_32FC3);
    for (int y = 0; y < flow.height; ++y)
        for (int x = 0; x < flow.width; ++x) {
            float fx = flow.at(x, y, 0), fy = flow.at(x, y, 1), opacity = flow.at(x, y, 2);
            float angle = std::atan2(fy, fx) * 180.0f / kPi;
            if (angle < 0) angle += 360.0f;
            float speed = max_speed > 0 ? float(std::hypot(fx, fy) / max_speed) : 0.0f;
            bool sky = fisheye::pixel_center_uv(x, y, flow.width).squaredNorm() <= 1.0f;
            hsv.at<cv::Vec3f>(y, x) = cv::Vec3f(angle, std::min(speed, 1.0f), sky ? 0.35f + 0.65f * opacity : 0.0f);
        }
    cv::Mat rgb;
    cv::cvtColor(hsv, rgb, cv::COLOR_HSV2RGB);
    Image out(flow.width, flow.height, 3);
    std::copy(rgb.ptr<float>(), rgb.ptr<float>() + out.pixels.size(), out.pixels.begin());
    return out;
}

CloudLayer make_layer(const std::string& name, const ProceduralOptions& o) {
    if (name == "cumulus") {
        CloudLayer l = cumulus_layer();
        l.altitude_m = o.cumulus_altitude;
        l.evolution_time_s = o.evolution;
        if (!o.wind.empty()) l.wind_speed_mps = o.wind[0], l.wind_from_deg = o.wind[1];
        return l;
    }
    if (name == "cirrus") {
        CloudLayer l = cirrus_layer();
        if (!o.cirrus_wind.empty()) l.wind_speed_mps = o.cirrus_wind[0], l.wind_from_deg = o.cirrus_wind[1];
        return l;
    }
    throw Error("--layers: unknown layer '" + name + "' (use cumulus, cirrus or both: cumulus,cirrus)");
}

void run_procedural(const ProceduralOptions& o, bool use_location) {
    // Everything is checked before the output folder is touched, so a bad argument leaves nothing.
    if (o.out.empty()) throw Error("--out: an output folder is required");
    if (!std::isfinite(o.dt) || o.dt <= 0) throw Error("--dt: must be a positive number of seconds, got " + std::to_string(o.dt));
    if (!std::isfinite(o.duration) || o.duration < 0)
        throw Error("--duration: must be >= 0 seconds, got " + std::to_string(o.duration));
    double steps = std::floor(o.duration / o.dt + 1e-9);
    if (steps + 1 > 100000) throw Error("--duration / --dt: more than 100000 frames; use a larger --dt");
    const int frames = int(steps) + 1;
    if (o.resolution < 8 || o.resolution > 16384)
        throw Error("--res: must be in [8, 16384], got " + std::to_string(o.resolution));
    if (!std::isfinite(o.sun_elevation) || o.sun_elevation < -90 || o.sun_elevation > 90)
        throw Error("--sun-elevation: must be in [-90, 90] degrees");
    if (!std::isfinite(o.sun_azimuth)) throw Error("--sun-azimuth: must be a finite angle in degrees");
    if (fs::exists(o.out) && !fs::is_directory(o.out)) throw_file_error(o.out, "exists and is not a folder");

    ProceduralSkyParams params;
    params.seed = o.seed;
    params.coverage = o.coverage;
    params.visibility_m = o.visibility;
    params.clear_sky.turbidity = o.turbidity;
    params.layers.clear();
    for (const std::string& name : o.layers) params.layers.push_back(make_layer(name, o));
    if (params.layers.empty()) throw Error("--layers: at least one layer is needed");
    if (!o.mask_image.empty()) {
        // The mask shapes the first layer named in --layers.
        params.layers[0].mask = std::make_shared<Image>(load_cloud_mask(o.mask_image));
        params.layers[0].mask_extent_m = o.mask_extent;
        params.layers[0].mask_detail = o.mask_detail;
    }

    UtcTime start;
    GeoLocation where;
    auto sun_at = [&](double t) -> Vec3d {
        if (!use_location)
            return fisheye::direction_from_angles((90.0 - o.sun_elevation) * kPiD / 180.0, o.sun_azimuth * kPiD / 180.0);
        UtcTime now = start;
        now.second += t;  // julian_date is linear in the seconds field
        return compute_sun_position(now, where).direction();
    };
    if (use_location) {
        start = parse_utc_time(o.time_iso);
        where.latitude_deg = o.latitude, where.longitude_deg = o.longitude;
        validate_location(where);
    }
    params.clear_sky.sun_direction = sun_at(0.0);
    ProceduralSky sky(params);  // validates every parameter

    // Fixed exposure for all previews (from the first clear sky), so they do not flicker.
    float preview_ev = 0.0f;
    if (o.preview) {
        SkyImage clear = make_clear_sky(params.clear_sky, 64);
        std::vector<float> lum;
        for (int j = 0; j < 64; ++j)
            for (int i = 0; i < 64; ++i)
                if (clear.in_disc(i, j)) lum.push_back(luminance(clear.pixel(i, j)));
        const float median_lum = median(std::move(lum));
        if (median_lum > 0) preview_ev = std::log2(0.2f / median_lum);
    }

    fs::create_directories(o.out);
    nlohmann::ordered_json manifest;
    manifest["generator"] = "dynsky sky procedural";
    manifest["seed"] = o.seed;
    manifest["coverage"] = o.coverage;
    manifest["resolution"] = o.resolution;
    manifest["dt_s"] = o.dt;
    manifest["duration_s"] = o.duration;
    manifest["frame_count"] = frames;
    manifest["turbidity"] = o.turbidity;
    manifest["visibility_m"] = o.visibility;
    if (use_location) {
        manifest["sun"] = {{"latitude_deg", o.latitude}, {"longitude_deg", o.longitude}, {"start_time", o.time_iso}};
    } else {
        manifest["sun"] = {{"elevation_deg", o.sun_elevation}, {"azimuth_deg", o.sun_azimuth}};
    }
    nlohmann::ordered_json layers = nlohmann::ordered_json::array();
    for (const CloudLayer& l : params.layers) {
        nlohmann::ordered_json j;
        j["type"] = l.type == CloudType::Cumulus ? "cumulus" : "cirrus";
        j["altitude_m"] = l.altitude_m;
        j["coverage"] = l.coverage.value_or(params.coverage);
        j["wind_speed_mps"] = l.wind_speed_mps;
        j["wind_from_deg"] = l.wind_from_deg;
        j["evolution_time_s"] = l.evolution_time_s;
        if (l.mask) j["mask_image"] = o.mask_image;
        layers.push_back(j);
    }
    manifest["layers"] = layers;
    manifest["flow"] = {
        {"channels", {"dx_px", "dy_px", "cloud_opacity"}},
        {"units", "pixels of the canonical fisheye at this resolution"},
        {"sign", "forward: the cloud seen at pixel (x, y) of frame k is at (x + dx, y + dy) at time t_k + dt; "
                 "+x to the right, +y down (row 0 at the top, north)"}};

    nlohmann::ordered_json frame_list = nlohmann::ordered_json::array();
    double max_speed = 0.0;
    Vec3d current_sun = params.clear_sky.sun_direction;
    ProgressBar progress(frames, "procedural sky", o.quiet);
    for (int k = 0; k < frames; ++k) {
        double t = k * o.dt;
        if (use_location) {
            Vec3d s = sun_at(t);
            if (s != current_sun) sky.set_sun_direction(s), current_sun = s;
        }
        Image flow;
        SkyImage frame = sky.render(t, o.resolution, &flow, o.dt);
        std::string image_name = frame_name("frame", k, ".exr"), flow_name = frame_name("flow", k, ".exr");
        save_sky((fs::path(o.out) / image_name).string(), frame);
        write_image((fs::path(o.out) / flow_name).string(), flow);
        nlohmann::ordered_json entry;
        entry["index"] = k;
        entry["time_s"] = t;
        entry["image"] = image_name;
        entry["flow"] = flow_name;
        entry["sun_direction"] = {current_sun.x(), current_sun.y(), current_sun.z()};
        entry["sun_transmittance"] = sky.sun_transmittance(t);
        if (o.preview) {
            std::string png = frame_name("frame", k, ".png"), flow_png = frame_name("flow", k, ".png");
            write_image((fs::path(o.out) / png).string(), tonemap_to_display(sky_to_image(frame), preview_ev));
            if (k == 0)
                for (size_t p = 0; p < flow.pixels.size(); p += 3)
                    max_speed = std::max(max_speed, std::hypot(double(flow.pixels[p]), double(flow.pixels[p + 1])));
            write_image((fs::path(o.out) / flow_png).string(), flow_preview(flow, max_speed));
            entry["preview"] = png;
            entry["flow_preview"] = flow_png;
        }
        frame_list.push_back(entry);
        progress.advance();
    }
    progress.finish();
    manifest["frames"] = frame_list;
    // Written last: a manifest means the sequence is complete.
    write_file_atomic((fs::path(o.out) / "manifest.json").string(), manifest.dump(2) + "\n");
    if (!o.quiet)
        std::printf("wrote %d frames, their flows and manifest.json to %s\n", frames, o.out.c_str());
}

}  // namespace

void register_sky_procedural_command(CLI::App& sky) {
    auto o = std::make_shared<ProceduralOptions>();
    CLI::App* cmd = sky.add_subcommand(
        "procedural",
        "Procedural cloudy skies with known motion: cloud layers (cumulus at 1.5 km, cirrus at 8 km)\n"
        "drifting with the wind and slowly changing shape over a Hosek-Wilkie clear sky. Writes\n"
        "DIR/frame_00000.exr ... (canonical fisheye radiance, W m^-2 sr^-1), DIR/flow_00000.exr ...\n"
        "(the exact motion of the clouds over --dt: channels dx, dy in pixels of the image, +x right,\n"
        "+y down, and the cloud opacity) and DIR/manifest.json. Frames are at t = 0, dt, 2 dt, ...\n"
        "up to --duration. See docs/procedural-sky.md.");
    cmd->add_option("--seed", o->seed, "Random seed: the same seed and options give identical frames")->capture_default_str();
    cmd->add_option("--coverage", o->coverage, "Fraction of each cloud layer holding cloud, 0 (clear) to 1 (overcast)")
        ->capture_default_str();
    cmd->add_option("--duration", o->duration, "Length of the sequence in seconds (frames at 0, dt, ..., <= duration)")
        ->capture_default_str();
    cmd->add_option("--dt", o->dt, "Time step between frames in seconds; also the span of each flow field")->capture_default_str();
    cmd->add_option("--res", o->resolution, "Resolution N of the N x N fisheye images (8..16384)")->capture_default_str();
    cmd->add_option("--out", o->out, "Output folder (created if missing; files in it are overwritten)")->required();
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
        ->capture_default_str();
    cmd->add_option("--evolution", o->evolution,
                    "Seconds for the cumulus shapes to change completely; 0 freezes them (pure advection)")
        ->capture_default_str();
    cmd->add_option("--mask-image", o->mask_image,
                    "Grey or alpha image (PNG, EXR, ...) of cloud density for the first layer, seen from below\n"
                    "(north up, east left), centred overhead at t = 0 and drifting with the wind");
    cmd->add_option("--mask-extent", o->mask_extent,
                    "Width in metres of the square the mask covers on its layer (0: out to 60 deg from the zenith)")
        ->capture_default_str();
    cmd->add_option("--mask-detail", o->mask_detail, "How much noise erodes the mask's soft edges, in [0, 1)")
        ->capture_default_str();
    auto* elevation = cmd->add_option("--sun-elevation", o->sun_elevation, "Sun elevation above the horizon, degrees")
                          ->capture_default_str();
    auto* azimuth = cmd->add_option("--sun-azimuth", o->sun_azimuth, "Sun azimuth, degrees clockwise from north")
                        ->capture_default_str();
    auto* lat = cmd->add_option("--lat", o->latitude, "Latitude in degrees (north +); with --lon and --time the sun\n"
                                                      "follows its true path over the sequence");
    auto* lon = cmd->add_option("--lon", o->longitude, "Longitude in degrees (east +)");
    auto* time = cmd->add_option("--time", o->time_iso, "Start time, ISO 8601 with a zone, e.g. 2024-06-21T14:00:00Z");
    lat->excludes(elevation)->excludes(azimuth);
    lon->excludes(elevation)->excludes(azimuth);
    time->excludes(elevation)->excludes(azimuth);
    cmd->add_option("--turbidity", o->turbidity, "Clear-sky turbidity, 1..10 (2 very clear, 3 clear, 6+ hazy)")
        ->capture_default_str();
    cmd->add_option("--visibility", o->visibility, "Distance in metres over which far clouds fade into the sky (1/e)")
        ->capture_default_str();
    cmd->add_flag("--preview", o->preview, "Also write tone-mapped PNGs: frame_NNNNN.png and flow_NNNNN.png (colour-coded)");
    cmd->add_flag("--quiet", o->quiet, "No progress bar or summary");
    cmd->callback([o, lat, lon, time]() {
        int given = int(lat->count() > 0) + int(lon->count() > 0) + int(time->count() > 0);
        if (given != 0 && given != 3) throw Error("--lat, --lon and --time go together: give all three or none");
        run_procedural(*o, given == 3);
    });
}

}  // namespace dynsky::cli
