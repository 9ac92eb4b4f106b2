#include "frame/sky_source.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <cstdio>

#include "motion/flow_extrapolation_model.h"
#include "motion/network_step_model.h"
#include "motion/flow.h"
#include "motion/procedural_step_model.h"
#include "motion/radiance_scale.h"
#include "motion/sun_patch.h"
#include "sky/clear_sky.h"
#include "sky/latlong.h"
#include "sky/sun_position.h"
#include "util/data_path.h"
#include "util/atomic_file.h"
#include "util/error.h"
#include "util/progress.h"
#include "util/parse.h"
#include "util/image.h"
#include "util/version.h"

namespace dynsky {

namespace fs = std::filesystem;

UtcTime start_time(const SkySourceSpec& o) {
    return parse_utc_time(o.time.empty() ? std::string(default_sky::kStartTime) : o.time);
}

std::optional<UtcTime> sky_time_at(const SkySourceSpec& o, const SkyImage& input, double t) {
    if (is_generated_sky(o.sky) || !o.time.empty()) return add_seconds(start_time(o), t);
    const std::optional<double> taken = sky_recorded_utc_seconds(input);
    if (!taken) return std::nullopt;
    const UtcTime j2000{2000, 1, 1, 12, 0, 0.0};  // Julian date 2451545.0
    return add_seconds(j2000, *taken - julian_date(j2000) * 86400.0 + t);
}

std::string exif_date_time(const SkySourceSpec& o, const SkyImage& input, double t) {
    const std::optional<UtcTime> when = sky_time_at(o, input, t);
    if (!when) return "";
    char text[32];
    std::snprintf(text, sizeof text, "%04d:%02d:%02d %02d:%02d:%02d", when->year, when->month, when->day, when->hour,
                  when->minute, int(std::floor(when->second)));
    return text;
}

namespace {

ProceduralSkyParams procedural_params(const SkySourceSpec& o, uint64_t seed, const Vec3d& sun) {
    ProceduralSkyParams p;
    p.seed = seed;
    p.coverage = o.coverage;
    p.layers = {cumulus_layer()};
    p.layers[0].wind_from_deg = o.wind_from_deg;
    p.layers[0].wind_speed_mps = o.wind_speed_mps;
    p.layers[0].altitude_m = o.cloud_height_m;
    p.layers[0].evolution_time_s = o.evolution_s;
    p.clear_sky.sun_direction = sun;
    p.clear_sky.turbidity = o.turbidity;
    validate_procedural_params(p);
    return p;
}

uint64_t procedural_seed(const std::string& sky) {
    if (sky.size() <= 10) return 0;
    if (sky[10] != ':' || sky.size() == 11 || sky.find_first_not_of("0123456789", 11) != std::string::npos)
        throw Error("--sky '" + sky + "': expected 'procedural' or 'procedural:SEED' (SEED a whole number)");
    return parse_seed(sky.substr(11), "--sky '" + sky + "' (the seed)");  // as `sky procedural --cloud-seed`
}

}  // namespace

bool is_generated_sky(const std::string& sky) { return sky == "clear" || sky.rfind("procedural", 0) == 0; }

void record_image_inputs(ImageMetadata* m, const std::string& scene_path, const SkySourceSpec& o) {
    m->strings["Software"] = dynsky_version();  // the build (util/version.h)
    auto record_file = [m](const std::string& key, const std::string& path) {
        m->strings[key] = fs::absolute(path).lexically_normal().string();
        m->strings[key + "_contents"] = describe_scene_input(path);  // sizes and hashes
    };
    if (!scene_path.empty() && scene_path != "builtin") record_file("dynsky:scene_file", scene_path);
    if (o.sky.empty() || is_generated_sky(o.sky)) return;
    std::error_code ec;
    if (fs::is_directory(o.sky, ec)) m->strings["dynsky:sky_folder"] = fs::absolute(o.sky).lexically_normal().string();
    else record_file("dynsky:sky_file", o.sky);
    if (o.sky_turn_deg != 0) m->numbers["dynsky:sky_turn_deg"] = o.sky_turn_deg;
    if (o.sky_resolution_given) m->numbers["dynsky:sky_res"] = o.sky_resolution;  // the file taken at it
}

SkyFileOptions sky_file_options(const SkySourceSpec& o, int latlong_limit) {
    if (!std::isfinite(o.sky_turn_deg)) throw Error("--sky-turn must be a finite number of degrees");
    return {o.sky_resolution_given ? o.sky_resolution : 0, latlong_limit, o.sky_turn_deg};
}

SkyImage make_generated_sky(const SkySourceSpec& o) {
    if (!is_generated_sky(o.sky))
        throw Error("--sky '" + o.sky + "': not a sky made here (expected 'clear' or 'procedural[:SEED]')");
    check_sky_resolution(o.sky_resolution);
    if (!(o.coverage >= 0 && o.coverage <= 1)) throw Error("--coverage must be in [0, 1]");
    const GeoLocation where{o.latitude, o.longitude, 0};
    validate_location(where);
    const Vec3d sun = compute_sun_position(start_time(o), where).direction();
    SkyImage input;
    // What made it, whole: a render's header names the sky it can be made again from.
    const std::string made = " at " + format_utc_time(start_time(o)) + ", " + number_text(o.latitude) + " N " +
                             number_text(o.longitude) + " E, " + std::to_string(o.sky_resolution) + " px";
    if (o.sky == "clear") {
        ClearSkyParams p;
        p.sun_direction = sun;
        p.turbidity = o.turbidity;
        validate_clear_sky_params(p);
        input = make_clear_sky(p, o.sky_resolution);
        input.source = "clear sky (Hosek-Wilkie, turbidity " + number_text(p.turbidity) + ")" + made;
    } else {
        const ProceduralSkyParams params = procedural_params(o, procedural_seed(o.sky), sun);
        input = render_procedural_sky(params, 0.0, o.sky_resolution);
        input.source = describe_procedural_sky(params) + made;
    }
    return input;
}

SkyImage make_builtin_clear_sky(int resolution) {
    SkySourceSpec clear;  // the place, time and turbidity of `--sky clear` everywhere
    clear.sky = "clear";
    clear.sky_resolution = resolution;  // --sky-res, as for 'clear'
    SkyImage sky = make_generated_sky(clear);
    sky.source = std::string("builtin: clear sky, Paris ") + default_sky::kStartTime + ", turbidity " +
                 number_text(default_sky::kTurbidity);
    return sky;
}

void check_sky_source(const SkySourceSpec& o, const StepModelSpec& m, double duration) {
    if (!(m.dt >= 0)) throw Error("--dt must be positive (or 0: automatic)");
    if (o.sky.rfind("procedural", 0) == 0) procedural_seed(o.sky);  // 'procedural:abc' named
    // As `sky procedural --evolution`: under a second the shapes would boil from frame to frame.
    if (!(o.evolution_s == 0 || (o.evolution_s >= 1 && o.evolution_s <= 1e7)))
        throw Error("--evolution: " + number_text(o.evolution_s) + " s: give 0 (frozen shapes) or 1..1e7 s");
    if (!o.previous.empty() && o.wind_given)
        throw Error("--prev and --wind-from/--wind-speed: give one source of motion, not both");
    if (step_model_name(m.model) == "procedural" && o.sky.rfind("procedural", 0) != 0)
        throw Error("--model procedural needs --sky procedural (it is the procedural sky's own motion)");
    if (m.dt > 0 && duration > 0) SkyTimeline::check_span(duration, m.dt);
}

SkyTimeline make_sky_timeline(const SkySourceSpec& o, const StepModelSpec& m) {
    check_sky_source(o, m, 0.0);
    const GammaKind gamma = parse_gamma(m.gamma);
    check_sky_resolution(o.sky_resolution);
    if (!(o.coverage >= 0 && o.coverage <= 1)) throw Error("--coverage must be in [0, 1]");
    GeoLocation where{o.latitude, o.longitude, 0};
    std::optional<SunClock> clock;
    if (is_generated_sky(o.sky) || !o.time.empty()) {
        validate_location(where);
        clock = SunClock{start_time(o), where};
    }
    // What moves the clouds for models that take a motion: the previous frame, else the wind.
    CloudMotion motion;
    // A captured sequence (a folder of sky EXRs): the last in time is the input, the one before it
    // the previous frame.
    std::string sky_file = o.sky, previous_file = o.previous;
    if (fs::is_directory(o.sky)) {
        sky_file = sequence_start(o.sky, previous_file.empty() && !o.wind_given, &previous_file, reports_silenced());
    }
    // A 2:1 lat-long HDRI's upper half, as `render` and `sky predict` take one; the moving sky has no
    // ground of its own, so below the horizon is the ground model.
    auto load_input_sky = [&o](const std::string& file) {
        std::shared_ptr<SkyImage> ground;
        SkyImage s = load_sky_or_latlong(file, &ground, sky_file_options(o, kMovingLatlongLimit));
        // Checked before anything is rendered: the flow between steps is measured on the sky itself
        // (a 4 x 4 sky failed after animate and compare had written their first outputs).
        if (s.resolution < 8)
            throw_file_error(file, "is a " + std::to_string(s.resolution) + " x " + std::to_string(s.resolution) +
                                       " sky: a moving sky needs at least 8 x 8 pixels (its clouds' motion is "
                                       "measured on it)");
        if (ground && !reports_silenced())
            std::fprintf(stderr, "%s; below the horizon is the ground model (--ground-albedo)\n",
                         moving_latlong_note(file, s.resolution, o.sky_resolution_given).c_str());
        return s;
    };
    if (!previous_file.empty()) {
        motion.previous = std::make_shared<const SkyImage>(load_input_sky(previous_file));
        motion.previous_dt = o.previous_dt;
        if (!(o.previous_dt >= 0)) throw Error("--prev-dt must be positive");
    } else {
        motion.wind = Wind{o.wind_from_deg, o.wind_speed_mps, o.cloud_height_m};
        wind_flow(8, *motion.wind, 1.0);  // validates
    }
    // A sky file is read before the model is made: the model takes the gap to the previous frame
    // (their own clocks, unless --prev-dt says) and both skies at the models' radiance scale.
    const bool generated = o.sky.rfind("procedural", 0) == 0 || o.sky == "clear";
    SkyImage input;
    RadianceScale scale;
    if (!generated) {
        // Any float radiance file, as render takes it (an EXR, a .hdr; integer images are refused by
        // the loader with a pointer to `sky import`); a name that is no file gets the choices.
        if (!fs::exists(sky_file))
            throw Error(o.sky +
                        ": no such sky file (give 'procedural[:SEED]', 'clear', a canonical fisheye .exr or a "
                        "folder of them; import photographs first with 'dynsky sky import')");
        input = load_input_sky(sky_file);
        if (motion.previous) {
            motion.previous_dt = previous_frame_gap(input, *motion.previous, motion.previous_dt, sky_file,
                                                    previous_file);
            if (motion.previous_dt == 0 && !reports_silenced())
                std::fputs(unknown_previous_gap_note(sky_file, previous_file).c_str(), stderr);
            // A warning, said under -q too (the glossary's -q silences reports, not warnings).
            std::fputs(long_previous_gap_warning(motion.previous_dt, sky_file, previous_file).c_str(), stderr);
        }
        input.time_seconds = 0;
        if (input.source.empty()) input.source = sky_file;
        std::optional<Vec3d> clock_sun;
        if (clock) clock_sun = compute_sun_position(clock->start, clock->where).direction();
        // The clock's sun replaces the one the file records (SkyTimeline): said where they are far
        // apart, a photograph's --time given without its --lat/--lon (Paris by default) lit the
        // clear sky from the west while the photograph's light came from the east.
        // So is a sky that records no sun but shows one (a downloaded HDRI): its sun moved to the
        // clock's while its glow and light stayed (65 degrees apart, said only as a note). Warnings:
        // said under -q too (farm runs use -q).
        if (clock_sun) {
            const std::optional<Vec3d> own = input.sun_direction
                                                 ? std::optional<Vec3d>(input.sun_direction->cast<double>())
                                                 : sun_from_brightest_pixels(input);
            const double apart = own ? std::acos(std::clamp(clock_sun->dot(*own), -1.0, 1.0)) * 180 / kPiD : 0;
            // Taken at the clock's own time: the place is right too, or the sky's sun is not the
            // clock's because its import put it where the photograph shows it (a camera whose north
            // is off: the import warned) - said so, not "give the time and place" again.
            const std::optional<double> taken = sky_recorded_utc_seconds(input);
            const bool own_time = taken && std::abs(*taken - julian_date(clock->start) * 86400.0) < 60;
            if (apart > 3 && input.sun_direction && own_time)
                std::fprintf(stderr,
                             "dynsky: warning: %s records its sun %.0f degrees from the sun of its own time at --lat "
                             "and --lon: the place is not the sky's, or its sun was put where its photograph shows it "
                             "(a camera whose north is off: 'sky import' warned then). The clock's sun is used, away "
                             "from the sky's glow (leave --time out to keep the sky's own sun%s)\n",
                             sky_file.c_str(), apart, o.sky_turn_deg != 0 ? ", turned by --sky-turn" : "");
            else if (apart > 3 && input.sun_direction)
                std::fprintf(stderr,
                             "dynsky: warning: %s records its sun %.0f degrees from where --time, --lat and --lon put "
                             "it: the clock's sun is used (give the place and time the sky was taken at, or leave "
                             "--time out to keep the sky's own sun%s)\n",
                             sky_file.c_str(), apart, o.sky_turn_deg != 0 ? ", turned by --sky-turn" : "");
            else if (apart > 3)
                std::fprintf(stderr,
                             "dynsky: warning: %s records no sun but shows one %.0f degrees from where --time, "
                             "--lat and --lon put it: the sun is moved there and the sky's glow stays where it is "
                             "(leave --time out to keep the sky's own sun%s, or give the place and time it was "
                             "taken at)\n",
                             sky_file.c_str(), apart, o.sky_turn_deg != 0 ? ", turned by --sky-turn" : "");
        }
        scale = bring_to_model_scale(&input, &motion.previous, clock_sun);
        if (scale.apply && !reports_silenced())
            std::fprintf(stderr,
                         "dynsky: note: %s is %s: its clouds are moved at the model's scale and its frames given "
                         "back in its own units\n",
                         sky_file.c_str(), scale.describe().c_str());
    }
    std::string model_name = step_model_name(m.model);
    std::unique_ptr<MediumStepModel> model;
    if (model_name == "auto" || model_name == "paper" || model_name == "advect") {
        const std::string folder = resolve_cloud_model(model_name);
        if (model_name == "auto" && folder == "advect")
            std::fprintf(stderr,
                         "dynsky: note: the shipped cloud model is not installed; clouds move by pure advection\n");
        model = make_network_step_model(folder, motion);
        model_name = folder == "advect" ? "advect" : "network:" + folder;
    }
    if (model_name.rfind("network:", 0) == 0 && !model)
        model = make_network_step_model(resolve_user_path(model_name.substr(8)), motion);  // fails early
    if (o.sky.rfind("procedural", 0) == 0) {
        input = make_generated_sky(o);
        if (!model && (model_name == "auto" || model_name == "procedural")) {
            model = std::make_unique<ProceduralStepModel>(
                procedural_params(o, procedural_seed(o.sky), compute_sun_position(clock->start, where).direction()));
            model_name = "procedural";
        }
    } else if (o.sky == "clear") {
        input = make_generated_sky(o);
    }
    if (!model) {
        if (model_name == "auto" || model_name == "flow") {
            model = std::make_unique<FlowExtrapolationStepModel>(o.wind_from_deg, m.drift_deg_per_s);
        } else {
            throw Error("--model '" + model_name + "': expected auto, procedural, flow or network:FOLDER");
        }
    }
    // --drift shapes the flow model's first step only: said where another model ignores it.
    if (m.drift_deg_per_s != StepModelSpec{}.drift_deg_per_s && model_name != "auto" && model_name != "flow")
        std::fprintf(stderr,
                     "dynsky: warning: --drift sets the flow model's first-step drift; the %s model moves the clouds "
                     "by its own motion (--wind-from, --wind-speed, --prev): --drift is ignored\n",
                     model_name.c_str());
    double dt = m.dt;
    if (dt == 0) dt = model->native_dt() > 0 ? model->native_dt() : 10.0;
    else if (model->dt_is_fixed() && std::abs(dt - model->native_dt()) > 1e-9)
        std::fprintf(stderr, "dynsky: warning: --dt %g s, but the network was trained for Delta t = %g s\n", dt,
                     model->native_dt());
    // A long Delta t under a wind: the frames between two steps carry each step along the motion of a
    // whole step, and beyond about half the clouds' height a step the in-betweens ghost and break
    // into speckle that snaps back at every step (a TD's audit: --dt 600 at 12 m/s, 1.5 km).
    const double per_step = o.wind_speed_mps * dt / o.cloud_height_m;
    // The longest Delta t that keeps a step under half the clouds' height, rounded down (0.017 s
    // under 300 m/s at 10 m read "--dt 0", which is the model's own 30 s).
    const double half_height_dt = 0.5 * o.cloud_height_m / o.wind_speed_mps;
    const std::string longest_dt = half_height_dt >= 10 ? number_text(std::floor(half_height_dt))
                                                        : number_text(half_height_dt, 2);
    const bool advected = model_name == "advect" || model_name.rfind("network:", 0) == 0;
    // Before the first frame: beyond a thousand heights a step (motion/flow.h wind_flow) the first
    // step failed after frame 0 was written, naming the wind that was given, not --dt.
    if (!motion.previous && (advected || model_name == "procedural") && per_step > 1e3)
        throw Error("--dt " + number_text(dt) + " s: the wind (" + number_text(o.wind_speed_mps) + " m/s, clouds at " +
                    number_text(o.cloud_height_m) + " m) moves the clouds " + number_text(per_step) +
                    " times their height a step, more than a sky can show (1000): give --dt " + longest_dt +
                    " s or less (half their height a step), a lower --wind-speed or a higher --cloud-height");
    if (!motion.previous && advected && per_step > 0.5)
        std::fprintf(stderr,
                     "dynsky: warning: --dt %g s: the wind (%g m/s, clouds at %g m) moves the clouds %.1f x their "
                     "height a step (%.0f degrees at the zenith): the frames between steps will ghost and break up; "
                     "--dt %s or less keeps it under half their height\n",
                     dt, o.wind_speed_mps, o.cloud_height_m, per_step, std::atan(per_step) * 180 / kPiD,
                     longest_dt.c_str());
    SkyTimeline timeline(std::move(input), std::move(model), dt, clock);
    timeline.set_gamma(gamma);
    if (scale.apply) timeline.set_radiance_scale(scale.factor);
    return timeline;
}


std::string step_model_name(const std::string& model) {
    if (model == "auto" || model == "flow" || model == "procedural" || model == "advect" || model == "paper" ||
        model.rfind("network:", 0) == 0)
        return model;
    // A model folder as `sky predict` takes it (network: optional). Missing, a path is a file error
    // (exit 1), as sky predict and sky evaluate say it; a word is a mistyped choice (a usage error).
    const std::string folder = resolve_user_path(model);
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) {
        if (model.find('/') != std::string::npos) throw_file_error(folder, "model folder not found");
        throw Error("--model '" + model +
                    "': expected auto, advect, paper, procedural, flow, or a model folder (network:FOLDER)");
    }
    return "network:" + model;
}

std::string cloud_model_files(const std::string& name) {
    std::string folder;
    try {
        folder = resolve_cloud_model(name);
    } catch (const Error&) {
        return "";  // the model's own loading says what is wrong
    }
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) return "";
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(folder, ec)) {
        const std::string ext = file_extension(e.path().string());
        if (e.is_regular_file(ec) && (ext == ".json" || ext == ".onnx")) files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
    std::string s = " [";
    for (size_t i = 0; i < files.size(); ++i) s += (i ? "; " : "") + describe_input(files[i].string());
    return s + "]";
}

FrameSettings sky_timeline_settings(const SkySourceSpec& o, const StepModelSpec& m) {
    auto number = [](double v) {
        char buf[40];
        std::snprintf(buf, sizeof buf, "%.17g", v);
        return std::string(buf);
    };
    // A sky file's filled mask beside it changes its motion (SkyImage::filled); a folder's are in
    // its description already.
    auto with_mask = [](const std::string& file) {
        std::error_code ec;
        const std::string mask = filled_mask_path(file);
        if (file.empty() || fs::is_directory(file, ec) || !fs::exists(mask, ec)) return describe_input(file);
        return describe_input(file) + " filled " + describe_input(mask);
    };
    FrameSettings s;
    s["sky"] = with_mask(o.sky);
    // A file taken at --sky-res is said so: before, --sky-res with a file was ignored but recorded as N,
    // and the frames of such a folder, made at the file's own size, were kept.
    s["sky_res"] = is_generated_sky(o.sky)  ? std::to_string(o.sky_resolution)
                   : o.sky_resolution_given ? std::to_string(o.sky_resolution) + " (the file taken at it)"
                                            : "the file's";
    // Only when given (older folders keep their frames); a whole turn is none.
    if (const double turn = std::remainder(o.sky_turn_deg, 360.0); turn != 0) s["sky_turn"] = number(turn);
    s["time"] = o.time;
    s["lat"] = number(o.latitude), s["lon"] = number(o.longitude);
    s["coverage"] = number(o.coverage);
    // Only when given (older folders keep their frames).
    if (o.turbidity != default_sky::kTurbidity) s["turbidity"] = number(o.turbidity);
    if (o.evolution_s != default_sky::kCloudEvolutionS) s["evolution"] = number(o.evolution_s);
    s["wind_from"] = number(o.wind_from_deg), s["wind_speed"] = number(o.wind_speed_mps);
    s["cloud_height"] = number(o.cloud_height_m);
    s["prev"] = o.previous.empty() ? "" : with_mask(o.previous);
    s["prev_dt"] = number(o.previous_dt);
    s["model"] = m.model + cloud_model_files(m.model);
    s["dt"] = number(m.dt);
    s["drift"] = number(m.drift_deg_per_s);
    // What the moving sky is, when its steps or frames change meaning: frames and stored timelines of
    // another revision are made again (the 21st session's relight to the clock: resumed frames of the
    // revision before jumped 17 % in blue at the first new frame).
    s["sky_revision"] = "4 (the default model's step flows by source: in-betweens without doubled edges)";
    return s;
}

int write_sky_timeline(const SkySourceSpec& sky, const StepModelSpec& model, double duration, const std::string& folder,
                       bool quiet) {
    if (!(duration > 0)) throw Error("--duration must be positive");
    check_outputs_are_not_inputs({folder}, {sky.sky, sky.previous});
    const std::string settings = canonical_settings(sky_timeline_settings(sky, model));
    // A rerun (a requeued keys job) keeps a complete timeline of the same settings.
    std::error_code ec;
    if (fs::exists(fs::path(folder) / "timeline.json", ec)) {
        try {
            std::string stored;
            SkyTimeline old = SkyTimeline::load(folder, &stored);
            if (stored == settings && old.stored_last_step() >= old.last_step_for(duration)) {
                old.verify_stored();
                if (!quiet)
                    std::fprintf(stderr, "%s: the stored timeline (steps 0-%d) covers %g s: kept\n", folder.c_str(),
                                 old.stored_last_step(), duration);
                return old.stored_last_step();
            }
            if (stored == settings && !quiet)
                std::fprintf(stderr,
                             "%s: the stored timeline (steps 0-%d) covers %g s of the %g asked: made again from the "
                             "start (a rollout cannot resume midway)\n",
                             folder.c_str(), old.stored_last_step(), old.stored_last_step() * old.dt(), duration);
        } catch (const Error& e) {
            // Damaged or of another version: made again below.
            if (!quiet)
                std::fprintf(stderr, "%s: the stored timeline is not usable (%s): made again\n", folder.c_str(),
                             e.what());
        }
    }
    SkyTimeline timeline = make_sky_timeline(sky, model);
    timeline.check_span(duration);
    const int last = std::max(1, timeline.last_step_for(duration));
    if (!quiet)
        std::fprintf(stderr, "sky timeline: model %s, Delta t %g s, steps 0-%d (t <= %g s) into %s\n",
                     timeline.model().name().c_str(), timeline.dt(), last, last * timeline.dt(), folder.c_str());
    timeline.save(folder, last, settings, quiet);  // which removes a killed run's temporaries first
    if (!quiet)
        std::fprintf(stderr, "sky timeline: %d medium step(s) in %.1f s\n", timeline.timings().medium_steps,
                     timeline.timings().medium_seconds);
    return last;
}

SkyTimeline load_sky_timeline(const std::string& folder, const SkySourceSpec& sky, const StepModelSpec& model) {
    const GammaKind gamma = parse_gamma(model.gamma);
    std::string stored;
    SkyTimeline timeline = SkyTimeline::load(folder, &stored);
    const std::string settings = canonical_settings(sky_timeline_settings(sky, model));
    if (stored != settings)
        throw_file_error(folder, "the stored sky timeline was made with other settings (" +
                                     describe_settings_change(parse_settings(stored), parse_settings(settings)) +
                                     "): make it again with these options");
    timeline.set_gamma(gamma);
    return timeline;
}

}  // namespace dynsky
