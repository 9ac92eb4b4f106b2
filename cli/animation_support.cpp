#include "cli/animation_support.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <regex>

#include "motion/flow_extrapolation_model.h"
#include "motion/network_step_model.h"
#include "motion/procedural_step_model.h"
#include "renderer/builtin_scene.h"
#include "renderer/gltf_loader.h"
#include "sky/clear_sky.h"
#include "util/data_path.h"
#include "util/error.h"

namespace dynsky::cli {

void add_scene_options(CLI::App* cmd, SceneOptions* o) {
    cmd->add_option("scene", o->scene, "Scene: a .gltf/.glb file (scenes/tower/tower.gltf, scenes/house/house.gltf) or 'builtin'")
        ->capture_default_str();
    cmd->add_option("--camera", o->camera, "Index of the glTF perspective camera (the bounds are framed when the file has none)")
        ->capture_default_str();
    cmd->add_option("--ground-albedo", o->ground_albedo, "Albedo of the ground model below the horizon")->capture_default_str();
}

void add_sky_source_options(CLI::App* cmd, SkySourceOptions* o) {
    cmd->add_option("--sky", o->sky,
                    "Input sky at t = 0: 'procedural[:SEED]' (cumulus over a clear sky, known motion), 'clear' (Hosek-Wilkie),\n"
                    "or a canonical fisheye EXR (from 'dynsky sky clear|import|procedural|predict'; photographs: import first)")
        ->capture_default_str();
    cmd->add_option("--model", o->model,
                    "Medium-step model xi: 'procedural' (the procedural sky's own next frame; procedural input only),\n"
                    "'flow' (extrapolate the Farneback flow of the last two steps; a uniform drift first),\n"
                    "'network:FOLDER' (the trained FlowNet+CloudNet, motion/cloud_model.h), or 'auto': the shipped network\n"
                    "(networks/models/arm_tsi, Delta t 30 s) when it is installed, else procedural for procedural input and flow\n"
                    "for others")
        ->capture_default_str();
    cmd->add_option("--dt", o->dt,
                    "Delta t: seconds between medium steps (0: a network model's own Delta t from its model.json, else the paper's 10 s)")
        ->capture_default_str();
    cmd->add_option("--sky-res", o->sky_resolution, "Resolution N of skies made here (procedural, clear)")->capture_default_str();
    cmd->add_option("--time", o->time,
                    "UTC time of t = 0, ISO 8601 (e.g. 2026-06-21T16:00:00Z): the sun follows the clock from there.\n"
                    "Default for 'procedural' and 'clear': 2026-06-21T16:00:00Z; for an EXR: the sun stays where the file has it");
    cmd->add_option("--lat", o->latitude, "Latitude of the place, degrees north (with --time)")->capture_default_str();
    cmd->add_option("--lon", o->longitude, "Longitude of the place, degrees east (with --time)")->capture_default_str();
    cmd->add_option("--coverage", o->coverage, "Cloud cover of the procedural sky, 0..1")->capture_default_str();
    cmd->add_option("--wind-from", o->wind_from_deg, "Where the wind blows from, degrees clockwise from north")->capture_default_str();
    cmd->add_option("--wind-speed", o->wind_speed_mps, "Procedural sky's wind speed, m/s")->capture_default_str();
    cmd->add_option("--drift", o->drift_deg_per_s, "Flow model: first-step drift of a single input sky, degrees per second")
        ->capture_default_str();
}

void parse_frame_size(const std::string& text, int* w, int* h) {
    std::smatch m;
    if (!std::regex_match(text, m, std::regex("^([0-9]+)x([0-9]+)$")))
        throw Error("--res '" + text + "': expected WIDTHxHEIGHT, e.g. 1280x720");
    *w = std::stoi(m[1]), *h = std::stoi(m[2]);
    if (*w < 1 || *h < 1 || *w > 16384 || *h > 16384) throw Error("--res '" + text + "': each side must be 1..16384");
}

std::string shell_quote(const std::string& s) {
    std::string out = "'";
    for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

LoadedScene load_scene(const SceneOptions& o, float aspect_ratio) {
    if (!(o.ground_albedo >= 0 && o.ground_albedo <= 1)) throw Error("--ground-albedo must be in [0, 1]");
    LoadedScene out;
    if (o.scene == "builtin") {
        out.scene = make_builtin_scene();
    } else {
        out.scene = load_gltf(o.scene);
        for (const std::string& w : out.scene.warnings) std::fprintf(stderr, "dynsky: warning: %s\n", w.c_str());
    }
    if (out.scene.instances.empty()) throw Error(o.scene + ": the scene has no triangles to render");
    if (out.scene.cameras.empty()) {
        if (o.camera != 0) throw Error(o.scene + ": --camera " + std::to_string(o.camera) + " asked for, but the file has no cameras");
        out.camera = frame_bounds_camera(out.scene.world_bounds(), aspect_ratio);
    } else {
        if (o.camera < 0 || o.camera >= int(out.scene.cameras.size()))
            throw Error(o.scene + ": --camera " + std::to_string(o.camera) + " is out of range (the file has " +
                        std::to_string(out.scene.cameras.size()) + " perspective camera(s), numbered from 0)");
        out.camera = out.scene.cameras[size_t(o.camera)];
    }
    return out;
}

UtcTime start_time(const SkySourceOptions& o) {
    return parse_utc_time(o.time.empty() ? std::string("2026-06-21T16:00:00Z") : o.time);
}

namespace {

ProceduralSkyParams procedural_params(const SkySourceOptions& o, uint64_t seed, const Vec3d& sun) {
    ProceduralSkyParams p;
    p.seed = seed;
    p.coverage = o.coverage;
    p.layers = {cumulus_layer()};
    p.layers[0].wind_from_deg = o.wind_from_deg;
    p.layers[0].wind_speed_mps = o.wind_speed_mps;
    p.clear_sky.sun_direction = sun;
    p.clear_sky.turbidity = 3;
    validate_procedural_params(p);
    return p;
}

}  // namespace

SkyTimeline make_sky_timeline(const SkySourceOptions& o) {
    if (!(o.dt >= 0)) throw Error("--dt must be positive (or 0: automatic)");
    if (o.sky_resolution < 16 || o.sky_resolution > 8192) throw Error("--sky-res must be 16..8192");
    if (!(o.coverage >= 0 && o.coverage <= 1)) throw Error("--coverage must be in [0, 1]");
    GeoLocation where{o.latitude, o.longitude, 0};
    std::optional<SunClock> clock;
    const bool generated = o.sky == "clear" || o.sky.rfind("procedural", 0) == 0;
    if (generated || !o.time.empty()) {
        validate_location(where);
        clock = SunClock{start_time(o), where};
    }
    std::string model_name = o.model;
    if (model_name != "auto" && model_name != "flow" && model_name != "procedural" && model_name.rfind("network:", 0) != 0)
        throw Error("--model '" + model_name + "': expected auto, procedural, flow or network:FOLDER");
    std::unique_ptr<MediumStepModel> model;
    if (model_name == "auto") {
        // The paper's model: the shipped FlowNet + CloudNet, when the data files are where they belong.
        std::string folder;
        try {
            folder = data_path("networks/models/arm_tsi/model.json");
            folder = folder.substr(0, folder.size() - std::string("/model.json").size());
        } catch (const Error&) {
            std::fprintf(stderr, "dynsky: note: the shipped cloud model is not installed; clouds move by %s\n",
                         o.sky.rfind("procedural", 0) == 0 ? "the procedural sky's own motion" : "flow extrapolation");
        }
        if (!folder.empty()) {
            model = make_network_step_model(folder);
            model_name = "network:" + folder;
        }
    }
    if (model_name.rfind("network:", 0) == 0 && !model) model = make_network_step_model(model_name.substr(8));  // fails early
    SkyImage input;
    if (o.sky.rfind("procedural", 0) == 0) {
        uint64_t seed = 0;
        if (o.sky.size() > 10) {
            if (o.sky[10] != ':' || o.sky.size() == 11 || o.sky.find_first_not_of("0123456789", 11) != std::string::npos)
                throw Error("--sky '" + o.sky + "': expected 'procedural' or 'procedural:SEED' (SEED a whole number)");
            seed = std::stoull(o.sky.substr(11));
        }
        Vec3d sun = compute_sun_position(clock->start, where).direction();
        ProceduralSkyParams p = procedural_params(o, seed, sun);
        input = render_procedural_sky(p, 0.0, o.sky_resolution);
        input.source = "procedural (seed " + std::to_string(seed) + ", coverage " + std::to_string(o.coverage) + ")";
        if (!model && (model_name == "auto" || model_name == "procedural")) {
            model = std::make_unique<ProceduralStepModel>(p);
            model_name = "procedural";
        }
    } else if (o.sky == "clear") {
        ClearSkyParams p;
        p.sun_direction = compute_sun_position(clock->start, where).direction();
        p.turbidity = 3;
        input = make_clear_sky(p, o.sky_resolution);
        input.source = "clear sky (Hosek-Wilkie, turbidity 3)";
    } else {
        std::string ext = file_extension(o.sky);
        if (ext != ".exr")
            throw Error(o.sky + ": not a sky EXR ('procedural', 'clear' or a canonical fisheye .exr; import photographs first "
                                "with 'dynsky sky import')");
        input = load_sky(o.sky);
        input.time_seconds = 0;
        if (input.source.empty()) input.source = o.sky;
    }
    if (!model) {
        if (model_name == "auto" || model_name == "flow") {
            model = std::make_unique<FlowExtrapolationStepModel>(o.wind_from_deg, o.drift_deg_per_s);
        } else if (model_name == "procedural") {
            throw Error("--model procedural needs --sky procedural (it is the procedural sky's own motion)");
        } else {
            throw Error("--model '" + model_name + "': expected auto, procedural, flow or network:FOLDER");
        }
    }
    double dt = o.dt;
    if (dt == 0) dt = model->native_dt_seconds() > 0 ? model->native_dt_seconds() : 10.0;
    else if (model->native_dt_seconds() > 0 && std::abs(dt - model->native_dt_seconds()) > 1e-9)
        std::fprintf(stderr, "dynsky: warning: --dt %g s, but the network was trained for Delta t = %g s\n", dt,
                     model->native_dt_seconds());
    return SkyTimeline(std::move(input), std::move(model), dt, clock);
}

}  // namespace dynsky::cli
