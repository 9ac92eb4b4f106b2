#include "sky/procedural_sequence.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <memory>
#include <sstream>
#include <nlohmann/json.hpp>
#include <set>

#include "sky/clear_sky.h"
#include "sky/fisheye.h"
#include "sky/procedural_clouds.h"
#include "sky/sun_position.h"
#include "util/atomic_file.h"
#include "util/error.h"
#include "util/exposure.h"
#include "util/file_hash.h"
#include "util/frame_names.h"
#include "util/image.h"
#include "util/parse.h"
#include "util/progress.h"

namespace dynsky {

namespace {

namespace fs = std::filesystem;

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

CloudLayer make_layer(const std::string& name, const ProceduralSequenceSettings& o) {
    if (name == "cumulus") {
        CloudLayer l = cumulus_layer();
        l.altitude_m = o.cloud_height_m;
        l.evolution_time_s = o.evolution;
        l.wind_speed_mps = o.wind_speed_mps, l.wind_from_deg = o.wind_from_deg;
        return l;
    }
    if (name == "cirrus") {
        CloudLayer l = cirrus_layer();
        if (!o.cirrus_wind.empty()) l.wind_speed_mps = o.cirrus_wind[0], l.wind_from_deg = o.cirrus_wind[1];
        return l;
    }
    throw Error("--layers: unknown layer '" + name + "' (use cumulus, cirrus or both: cumulus,cirrus)");
}

// What decides frame k of a sequence (all settings but its length, --preview and -q; the mask by
// content), as a hash recorded in each frame's header: a run stopped midway keeps the frames it
// finished when run again. A setting added to ProceduralSequenceSettings belongs here.
std::string frame_settings_key(const ProceduralSequenceSettings& o) {
    std::ostringstream s;
    s << std::setprecision(17) << "seed=" << o.cloud_seed << ";coverage=" << o.coverage << ";dt=" << o.dt
      << ";resolution=" << o.resolution << ";wind=" << o.wind_from_deg << ',' << o.wind_speed_mps << ','
      << o.cloud_height_m << ";evolution=" << o.evolution << ";mask_extent=" << o.mask_extent
      << ";mask_detail=" << o.mask_detail << ";fixed_sun=" << o.fixed_sun << ";sun=" << o.sun_elevation << ','
      << o.sun_azimuth << ";place=" << o.latitude << ',' << o.longitude << ";time=" << o.time_iso
      << ";turbidity=" << o.turbidity << ";visibility=" << o.visibility << ";layers=";
    for (const std::string& l : o.layers) s << l << ',';
    s << ";cirrus_wind=";
    for (double v : o.cirrus_wind) s << v << ',';
    if (!o.mask_image.empty()) s << ";mask=" << describe_file(o.mask_image);
    return hash_text(s.str());
}

constexpr const char* kFrameSettingsKey = "dynsky:procedural_settings";

}  // namespace

void write_procedural_sequence(const ProceduralSequenceSettings& o) {
    const bool use_location = !o.fixed_sun;
    // Everything is checked before the output folder is touched, so a bad argument leaves nothing.
    if (o.out.empty()) throw Error("--out: an output folder is required");
    if (!std::isfinite(o.dt) || o.dt <= 0)
        throw Error("--dt: must be a positive number of seconds, got " + std::to_string(o.dt));
    if (!std::isfinite(o.duration) || o.duration < 0)
        throw Error("--duration: must be >= 0 seconds, got " + std::to_string(o.duration));
    double steps = std::floor(o.duration / o.dt + 1e-9);
    if (steps + 1 > 100000) throw Error("--duration / --dt: more than 100000 frames; use a larger --dt");
    const int frames = int(steps) + 1;
    check_sky_resolution(o.resolution);
    if (!std::isfinite(o.sun_elevation) || o.sun_elevation < -90 || o.sun_elevation > 90)
        throw Error("--sun-elevation: must be in [-90, 90] degrees");
    if (!std::isfinite(o.sun_azimuth)) throw Error("--sun-azimuth: must be a finite angle in degrees");
    if (fs::exists(o.out) && !fs::is_directory(o.out)) throw_file_error(o.out, "exists and is not a folder");

    ProceduralSkyParams params;
    params.seed = o.cloud_seed;
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
            return fisheye::direction_from_angles((90.0 - o.sun_elevation) * kPiD / 180.0,
                                                  o.sun_azimuth * kPiD / 180.0);
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
    if (o.preview) preview_ev = exposure_median(sky_to_image(make_clear_sky(params.clear_sky, 64)), 0.2f);

    const OutputFolder out_folder(o.out);  // removed again if this run fails before writing anything
    nlohmann::ordered_json manifest;
    manifest["generator"] = "dynsky sky procedural";
    manifest["seed"] = o.cloud_seed;
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
    // The EXR's channels are R, G, B (what every viewer opens); the manifest says what each holds.
    manifest["flow"] = {{"channels", {"dx_px", "dy_px", "cloud_opacity"}},
                        {"exr_channels", {"R", "G", "B"}},
                        {"units", "pixels of the canonical fisheye at this resolution"},
                        {"sign",
                         "forward: the cloud seen at pixel (x, y) of frame k is at (x + dx, y + dy) at time t_k + dt; "
                         "+x to the right, +y down (row 0 at the top, north)"}};

    nlohmann::ordered_json frame_list = nlohmann::ordered_json::array();
    double max_speed = 0.0;
    Vec3d current_sun = params.clear_sky.sun_direction;
    // The files of an earlier sequence in the folder, as its manifest lists them: those this run
    // does not write again are removed at the end (a longer sequence's later frames read as this
    // one's). Only a procedural sequence's own: other files named frame_NNNN (an animation's) stay.
    std::vector<std::string> earlier;
    try {
        std::ifstream in(fs::path(o.out) / "manifest.json");
        const nlohmann::json old = in ? nlohmann::json::parse(in) : nlohmann::json();
        if (old.is_object() && old.value("generator", "") == "dynsky sky procedural" && old.contains("frames"))
            for (const auto& f : old.at("frames"))
                for (const char* key : {"image", "flow", "preview", "flow_preview"})
                    if (f.contains(key) && f.at(key).is_string()) earlier.push_back(f.at(key).get<std::string>());
    } catch (const std::exception&) {
        earlier.clear();  // not a manifest of ours: nothing is removed
    }
    // An earlier sequence's manifest goes before any of its frames is replaced: a run that stops
    // midway must not leave it describing this run's frames.
    remove_stale_marker((fs::path(o.out) / "manifest.json").string());
    const std::string described = describe_procedural_sky(params),
                      sun_text = use_location ? "a clock from " + o.time_iso + " at " + number_text(o.latitude) +
                                                    " N " + number_text(o.longitude) + " E"
                                              : "a sun fixed at elevation " + number_text(o.sun_elevation) +
                                                    " deg, azimuth " + number_text(o.sun_azimuth) + " deg";
    // Frames of an earlier run of the same settings are kept (all their files there, each written
    // whole or not at all): a long sequence stopped midway goes on where it stopped.
    const std::string key = frame_settings_key(o);
    ImageMetadata recorded;
    recorded.strings[kFrameSettingsKey] = key;
    int kept = 0;
    ProgressBar progress(frames, "procedural sky", o.quiet);
    for (int k = 0; k < frames; ++k) {
        double t = k * o.dt;
        if (use_location) {
            Vec3d s = sun_at(t);
            if (s != current_sun) sky.set_sun_direction(s), current_sun = s;
        }
        std::string image_name = numbered_name("frame", k, ".exr", frames),
                    flow_name = numbered_name("flow", k, ".exr", frames);
        const std::string png = numbered_name("frame", k, ".png", frames),
                          flow_png = numbered_name("flow", k, ".png", frames);
        std::vector<std::string> files = {(fs::path(o.out) / image_name).string(),
                                          (fs::path(o.out) / flow_name).string()};
        if (o.preview)
            files.push_back((fs::path(o.out) / png).string()), files.push_back((fs::path(o.out) / flow_png).string());
        // Kept: its frame, flow and previews whole, the frame made with these settings.
        const bool keep = made_earlier_with(files, kFrameSettingsKey, key);
        Image flow;
        SkyImage frame;
        if (keep) {
            ++kept;
            if (o.preview && k == 0) flow = read_image(files[1]);  // the previews' speed scale
        } else {
            frame = sky.render(t, o.resolution, &flow, o.dt);
            frame.source = described + " at t = " + number_text(t) + " s of " + sun_text;  // what re-makes it
            write_image(files[1], flow);
        }
        nlohmann::ordered_json entry;
        entry["index"] = k;
        entry["time_s"] = t;
        entry["image"] = image_name;
        entry["flow"] = flow_name;
        entry["sun_direction"] = {current_sun.x(), current_sun.y(), current_sun.z()};
        entry["sun_transmittance"] = sky.sun_transmittance(t);
        if (o.preview) {
            if (k == 0)
                for (size_t p = 0; p + 1 < flow.pixels.size(); p += 3)
                    max_speed = std::max(max_speed, std::hypot(double(flow.pixels[p]), double(flow.pixels[p + 1])));
            if (!keep) {
                write_image(files[2], tonemap_to_display(sky_to_image(frame), preview_ev));
                write_image(files[3], flow_preview(flow, max_speed));
            }
            entry["preview"] = png;
            entry["flow_preview"] = flow_png;
        }
        // The frame last: it carries the settings key, so a run stopped after it has every file of
        // the frame made with those settings (written first, a stop left an earlier run's flow
        // beside it, kept on resume).
        if (!keep) save_sky(files[0], frame, "", recorded);
        frame_list.push_back(entry);
        progress.advance();
    }
    progress.finish();
    // Frames and flows of an earlier, longer sequence (or its previews) would read as this one's:
    // `animate --sky FOLDER` took the last of them as its input.
    std::set<std::string> written;
    for (const auto& f : frame_list)
        for (const char* key : {"image", "flow", "preview", "flow_preview"})
            if (f.contains(key)) written.insert(f.at(key).get<std::string>());
    int stale = 0;
    for (const std::string& name : earlier) {
        std::error_code ec;
        const fs::path path = fs::path(o.out) / name;
        if (fs::path(name).has_parent_path() || written.count(name) || !fs::is_regular_file(path, ec)) continue;
        if (fs::remove(path, ec)) ++stale;
    }
    if (stale && !o.quiet)
        std::fprintf(stderr, "dynsky: note: removed %d file(s) of an earlier sequence from %s\n", stale, o.out.c_str());
    manifest["frames"] = frame_list;
    // Written last: a manifest means the sequence is complete.
    write_file_atomic((fs::path(o.out) / "manifest.json").string(), manifest.dump(2) + "\n");
    if (!o.quiet)
        std::printf(
            "wrote %d frame%s, %s flow%s and manifest.json to %s%s\n", frames, frames == 1 ? "" : "s",
            frames == 1 ? "its" : "their", frames == 1 ? "" : "s", o.out.c_str(),
            kept ? (" (" + std::to_string(kept) + " of them kept from an earlier run of the same settings)").c_str()
                 : "");
}

}  // namespace dynsky
