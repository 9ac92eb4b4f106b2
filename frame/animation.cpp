#include "frame/animation.h"

#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <cstdlib>
#include <iterator>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <vector>

#include "frame/frame_metadata.h"
#include "frame/frame_store.h"
#include "frame/video.h"
#include "motion/network_step_model.h"
#include "renderer/accel.h"
#include "renderer/env_light.h"
#include "renderer/integrator.h"
#include "sky/clear_sky.h"
#include "util/data_path.h"
#include "util/atomic_file.h"
#include "util/error.h"
#include "util/exposure.h"
#include "util/image.h"

namespace dynsky {

namespace fs = std::filesystem;

namespace {

std::string number(double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

// "0-3, 5, 7-9"
std::string frame_list(const std::vector<int>& frames) {
    std::string s;
    for (size_t i = 0; i < frames.size();) {
        size_t j = i;
        while (j + 1 < frames.size() && frames[j + 1] == frames[j] + 1) ++j;
        s += (s.empty() ? "" : ", ") + std::to_string(frames[i]) +
             (j > i ? "-" + std::to_string(frames[j]) : std::string());
        i = j + 1;
    }
    return s;
}

// timings.csv holds a line per frame, in frame order: a frame rendered again (a resumed run
// repairing it) replaces its line (it was appended a second time). Rewritten whole each time
// (atomic, checked).
// Frame `frame`'s row (none for -1) into the table at path, keeping the other rows of frames 0 ..
// total - 1 (one per frame, in order).
void record_timing(const std::string& path, int frame, const std::string& line, bool start_over, int total) {
    const std::string header = "frame,time_s,sky_ms,distribution_ms,render_ms,medium_steps_so_far\n";
    std::map<int, std::string> rows;
    if (!start_over) {
        std::ifstream f(path, std::ios::binary);
        std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
        // A table cut short (a killed run) starts over, as before.
        if (!text.empty() && text.back() == '\n' && text.rfind(header, 0) == 0) {
            std::istringstream in(text.substr(header.size()));
            for (std::string row; std::getline(in, row);) {
                char* end = nullptr;
                const long k = std::strtol(row.c_str(), &end, 10);
                // Rows of frames past this animation's last (an earlier, longer run's) are dropped.
                if (end != row.c_str() && *end == ',' && k >= 0 && k < total) rows[int(k)] = row + "\n";
            }
        }
    }
    if (frame >= 0) rows[frame] = line;
    std::string text = header;
    for (const auto& [k, row] : rows) text += row;
    write_file_atomic(path, text);
}

}  // namespace

FrameSettings animation_frame_settings(const AnimationSettings& o, const std::string& model_name, double dt,
                                       float png_exposure_ev) {
    FrameSettings s = sky_timeline_settings(o.sky, o.model);  // as asked; the model and Delta t as resolved:
    s["model"] = model_name + cloud_model_files(o.model.model);
    s["dt"] = number(dt);
    s["scene"] = describe_scene_input(o.scene.scene);
    s["camera"] = std::to_string(o.scene.camera);
    s["ground_albedo"] = number(o.scene.ground_albedo);
    s["fps"] = number(o.fps);
    s["spp"] = std::to_string(o.spp);
    s["res"] = std::to_string(o.width) + "x" + std::to_string(o.height);
    s["max_depth"] = std::to_string(o.max_depth);
    s["seed"] = std::to_string(o.seed);
    s["seed_per_frame"] = o.seed_per_frame ? "1" : "0";
    // Only when used: frames of runs before these options keep their settings.
    if (o.scene.animation_time >= 0) s["anim_time"] = number(o.scene.animation_time);
    if (o.play_scene_animation) s["play_anim"] = "1";
    if (!o.scene.animation.empty()) s["animation"] = o.scene.animation;
    s["exposure"] = number(png_exposure_ev);
    if (o.exposure_follows_sun) s["exposure_follows_sun"] = "1";  // only when used: older frames keep theirs
    std::string look_at;
    for (double v : o.scene.look_at) look_at += (look_at.empty() ? "" : ",") + number(v);
    s["look_at"] = look_at, s["fov"] = number(o.scene.fov_deg);
    s["gamma"] = o.model.gamma;
    s["aovs"] = o.aovs, s["sampler_pattern"] = o.sampler_pattern;
    s["clamp_indirect"] = number(o.clamp_indirect), s["filter_glossy"] = number(o.filter_glossy);
    return s;
}

int animation_frame_count(const AnimationSettings& o) {
    if (!(o.duration > 0)) throw Error("--duration must be positive");
    if (!(o.fps > 0 && o.fps <= 1000)) throw Error("--fps must be in (0, 1000]");
    const double frames = std::round(o.duration * o.fps);
    if (!(frames <= kMaxAnimationFrames)) {
        char text[200];
        std::snprintf(text, sizeof text,
                      "--duration %g s at --fps %g is %.4g frames, more than the %.0f one animation may have",
                      o.duration, o.fps, frames, kMaxAnimationFrames);
        throw Error(text);
    }
    return std::max(1, int(frames));
}

void check_animation_settings(const AnimationSettings& o, bool inputs_exist) {
    if (o.width < 1 || o.height < 1) throw Error("animation: the frame size must be positive");
    if (o.spp < 1) throw Error("--spp must be at least 1");
    parse_aovs(o.aovs);
    parse_sample_pattern(o.sampler_pattern);
    if (!(o.clamp_indirect >= 0)) throw Error("--clamp-indirect must be 0 (off) or positive");
    if (!(o.filter_glossy >= 0)) throw Error("--filter-glossy must be 0 (off) or positive");
    const int total = animation_frame_count(o);
    const std::string& stage = o.stage;
    if (stage != "all" && stage != "keys" && stage != "frames" && stage != "encode")
        throw Error("--stage '" + stage + "': expected all, keys, frames or encode");
    if (stage == "keys" && o.timeline.empty()) throw Error("--stage keys needs --timeline FOLDER (where to write it)");
    int first, last;
    parse_frame_range(o.frames, total, &first, &last);
    // The frame folder must not be (or hold) an input: its frames would replace or join them. The
    // timeline may lie inside it (OUT/timeline) but not be it: found only once both exist, the keys
    // stage's work was lost to the frames stage's refusal.
    std::error_code ec;
    auto folder = [&](const std::string& p) {  // "out1/", "./out1/." and "out1" alike, made or not
        fs::path f = fs::weakly_canonical(fs::absolute(p), ec).lexically_normal();
        return f.has_filename() ? f : f.parent_path();
    };
    if (!o.timeline.empty() && folder(o.timeline) == folder(o.out))
        throw Error("--timeline " + o.timeline + " is the frames' folder --out: give it a folder of its own, e.g. " +
                    (fs::path(o.out) / "timeline").string());
    check_outputs_are_not_inputs({o.out}, {o.sky.sky, o.sky.previous, o.scene.scene, o.timeline});
    check_numbered_outputs_spare(o.out, {"frame", "sky"}, {o.sky.sky, o.sky.previous, o.scene.scene});
    if (!inputs_exist) return;
    check_sky_source(o.sky, o.model, o.duration);  // what the run refuses before any step
    // What a farm script checks before queueing anything (--count-frames): the files named exist
    // and the model is one there is (their contents are read by the stages).
    auto exists = [&](const std::string& path, const char* option) {
        if (!path.empty() && !fs::exists(resolve_user_path(path), ec))
            throw_file_error(path, missing_user_path_text(path) + " (" + option + ")");
    };
    if (o.scene.scene != "builtin") exists(o.scene.scene, "the scene");
    check_scene_camera(o.scene);
    if (!is_generated_sky(o.sky.sky)) exists(o.sky.sky, "--sky");
    exists(o.sky.previous, "--prev");
    if (stage != "keys" && stage != "all") exists(o.timeline, "--timeline");
    const std::string m = step_model_name(o.model.model);
    if (m == "paper" || m.rfind("network:", 0) == 0) {
        const std::string folder = resolve_cloud_model(m);  // "paper" not installed throws
        if (!fs::exists(fs::path(folder) / "model.json", ec))
            throw_file_error(folder, "no model.json: not a cloud model folder (--model)");
    }
}

AnimationReport render_animation(const AnimationSettings& o) {
    check_animation_settings(o, false);
    const int width = o.width, height = o.height;
    const AovSelection aovs = parse_aovs(o.aovs);
    const SamplePattern pattern = parse_sample_pattern(o.sampler_pattern);
    const int total = animation_frame_count(o);
    const std::string& stage = o.stage;
    int first, last;
    parse_frame_range(o.frames, total, &first, &last);

    std::unique_ptr<tbb::global_control> threads;
    if (o.threads > 0)
        threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, o.threads);
    if (stage == "keys") {
        write_sky_timeline(o.sky, o.model, o.duration, o.timeline, o.quiet);
        AnimationReport report;
        report.total = total, report.first = first, report.last = last;
        return report;
    }

    SkyTimeline timeline = o.timeline.empty() ? make_sky_timeline(o.sky, o.model)
                                              : load_sky_timeline(o.timeline, o.sky, o.model);
    timeline.check_span(o.duration);
    if (timeline.stored_last_step() >= 0 && timeline.last_step_for(last / o.fps) > timeline.stored_last_step())
        throw_file_error(o.timeline,
                         "the stored sky timeline ends at t = " + number(timeline.stored_last_step() * timeline.dt()) +
                             " s, before frame " + std::to_string(last) + " (t = " + number(last / o.fps) +
                             " s): make it with this --duration");
    // The scene is read only by stages that render (encode checks the frames' files and settings).
    std::optional<LoadedScene> scene;
    // Played, the file is read and its textures decoded once; each frame poses it (AnimatedGltf),
    // and the scene here is its first pose.
    std::unique_ptr<AnimatedGltf> animated;
    if (stage != "encode") {
        SceneSpec spec = o.scene;  // played: posed from the start (and no "not played" warning)
        if (o.play_scene_animation) spec.animation_time = std::max(0.0, spec.animation_time);
        if (o.play_scene_animation && o.scene.scene != "builtin") {
            const std::string path = resolve_user_path(o.scene.scene);
            animated = std::make_unique<AnimatedGltf>(path, o.scene.animation);
            scene = pose_scene(spec, *animated, path, float(width) / height, /*print_warnings=*/true);
        } else {
            scene = load_scene(spec, float(width) / height);
        }
    }
    // A farm task writes only its own frames and timings, so it removes only their temporaries:
    // the folder's others may be another task's, live on another machine. Its tasks share the
    // folder; any other run holds it alone.
    const bool farm_task = stage == "frames";
    // Removed again if this run fails before writing anything.
    const OutputFolder folder(o.out, farm_task ? FolderUse::shared : FolderUse::exclusive);
    const FrameStore store(o.out, total);
    const std::string timings_name = farm_task
                                         ? "timings_" + std::to_string(first) + "-" + std::to_string(last) + ".csv"
                                         : "timings.csv";
    std::vector<std::string> own_stems{fs::path(timings_name).stem().string()};
    for (int k = first; k <= last; ++k)
        for (const std::string& file : {store.frame_exr(k), store.sky_png(k)})
            own_stems.push_back(fs::path(file).stem().string());
    const std::vector<std::string> stale = farm_task ? remove_stale_temporaries(o.out, own_stems)
                                           : stage == "encode"
                                               ? remove_stale_temporaries(o.out, {"animation", "sky", "contact_sheet"})
                                               : remove_stale_temporaries(o.out);
    if (!stale.empty())
        std::fprintf(stderr, "dynsky: removed %zu temporary file(s) left in %s by a killed run (%s%s)\n", stale.size(),
                     o.out.c_str(), stale[0].c_str(), stale.size() > 1 ? ", ..." : "");

    if (!o.quiet)
        std::fprintf(stderr,
                     "scene: %s%s; sky: %s, model %s, Delta t %g s, Gamma %s; %d frames at %g fps, rendering %d-%d\n",
                     scene ? scene->path.c_str() : o.scene.scene.c_str(),
                     scene ? (" (" + std::to_string(scene->scene.triangle_count()) + " triangles)").c_str()
                           : " (not read: encoding)",
                     timeline.step(0)->source.c_str(), timeline.model().name().c_str(), timeline.dt(),
                     gamma_name(timeline.gamma()), total, o.fps, first, last);

    // One exposure for the whole animation (per-frame auto exposure would flicker), from the sky
    // at t = 0 so every frame range agrees on it.
    EnvLight light(o.scene.ground_albedo, path_tracer_sky_sampler());  // as render's default (cdf+mis)
    auto sky0 = std::make_shared<const SkyImage>(timeline.sky_at(0.0));
    light.set_sky(sky0);
    const float ev = std::isnan(o.exposure) ? exposure_for_irradiance(light.sky_irradiance()) : o.exposure;
    const float sky_ev = exposure_log_average(sky_to_image(*sky0));
    const std::string settings = canonical_settings(animation_frame_settings(o, timeline.model().name(), timeline.dt(),
                                                                             ev));
    // The PNG exposure of the frame at t: ev, or with --exposure-follows-sun ev moved by the change
    // of the clear sky's horizontal illuminance at the clock's sun since t = 0 (a sunrise's frames
    // were clipped white from 20 minutes on, a sunset's black: 7-11 stops over an hour). The clear
    // sky's, not the frame's own: clouds passing do not make the exposure flicker.
    std::optional<double> clear_light_at_start;
    auto clear_light = [&](double t) {
        ClearSkyParams p;
        p.sun_direction = *timeline.sun_direction_at(t);
        return horizontal_illuminance(make_clear_sky(p, 32, false));
    };
    if (o.exposure_follows_sun) {
        if (!timeline.sun_direction_at(0.0))
            throw Error(
                "--exposure-follows-sun: the sky has no sun to follow (a sky file without one; give --time, "
                "--lat and --lon to put it on the clock)");
        clear_light_at_start = clear_light(0.0);
    }
    auto exposure_at = [&](double t) {
        if (!clear_light_at_start || !(*clear_light_at_start > 0)) return ev;
        const double now = clear_light(t);
        return now > 0 ? float(ev + std::log2(*clear_light_at_start / now)) : ev;
    };

    // Which frames of the range are kept: complete and made with these settings. The others are
    // rendered, and what was wrong with those that had files is said (grouped by reason).
    std::vector<char> keep(size_t(total), 0);
    std::map<std::string, std::vector<int>> replace_reasons;
    for (int k = first; k <= last; ++k) {
        if (o.force && stage != "encode") continue;
        FrameCheck c = store.check(k, width, height, settings);
        keep[size_t(k)] = c.state == FrameCheck::Complete;
        if (c.state == FrameCheck::Damaged) replace_reasons["damaged: " + c.reason].push_back(k);
        if (c.state == FrameCheck::OtherSettings) replace_reasons["made with other settings: " + c.reason].push_back(k);
    }
    int replaced = 0;
    for (const auto& [reason, frames] : replace_reasons) {
        if (stage == "encode") {  // renders nothing: says what is wrong with them instead
            std::fprintf(stderr, "dynsky: frame(s) %s of %s: %s\n", frame_list(frames).c_str(), o.out.c_str(),
                         reason.c_str());
            continue;
        }
        std::fprintf(stderr, "dynsky: rendering again frame(s) %s of %s (%s)\n", frame_list(frames).c_str(),
                     o.out.c_str(), reason.c_str());
        replaced += int(frames.size());
    }
    if (stage == "encode") {
        std::vector<int> missing;
        for (int k = 0; k < total; ++k)
            if ((k >= first && k <= last) ? !keep[size_t(k)]
                                          : store.check(k, width, height, settings).state != FrameCheck::Complete)
                missing.push_back(k);
        if (!missing.empty())
            throw_file_error(o.out, "--stage encode: frame(s) " + frame_list(missing) + " of 0-" +
                                        std::to_string(total - 1) +
                                        " are not complete with these settings; render them first");
        if (!o.no_video) {
            make_video(o.out, "frame", total, o.fps, store.file("animation.mp4"), o.quiet);
            make_video(o.out, "sky", total, o.fps, store.file("sky.mp4"), o.quiet);
        }
        make_contact_sheet(store, total, o.fps, store.file("contact_sheet.png"));
        if (!o.quiet) std::fprintf(stderr, "wrote %s\n", store.file("contact_sheet.png").c_str());
        return AnimationReport{total, first, last, 0, total, 0, true, settings};
    }
    if (o.force && !o.quiet) std::fprintf(stderr, "--force: rendering every frame of %d-%d\n", first, last);

    // Playing the scene's animation: each frame posed at its own time (frames rendered on a farm
    // pose the same as in one run), so the scene as loaded above needs no BVH of its own then.
    std::optional<Accel> accel;
    if (!o.play_scene_animation) accel.emplace(scene->scene);
    const double animation_start = std::max(0.0, o.scene.animation_time);
    const float aspect = float(width) / height;
    const std::string timings = store.file(timings_name);
    bool timings_start_over = o.force;
    double sum_sky = 0, sum_build = 0, sum_render = 0;
    int rendered = 0, skipped = 0;
    std::shared_ptr<SkyImage> sky_buffers[2];
    bool warned_black = false;
    // Time left, on terminals and in logs alike (a farm's log said nothing for minutes).
    int to_render = 0;
    for (int k = first; k <= last; ++k) to_render += keep[size_t(k)] ? 0 : 1;
    const auto loop_start = std::chrono::steady_clock::now();
    for (int k = first; k <= last; ++k) {
        if (keep[size_t(k)]) {
            ++skipped;
            continue;
        }
        const double t = k / o.fps;
        // Two sky buffers, alternated: the light keeps the last frame's while the next is written.
        std::shared_ptr<SkyImage>& buffer = sky_buffers[k % 2];
        if (!buffer || buffer.use_count() > 1) buffer = std::make_shared<SkyImage>();
        auto t0 = std::chrono::steady_clock::now();
        timeline.sky_at(t, buffer.get());
        double sky_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::shared_ptr<const SkyImage> sky = buffer;
        light.set_sky(sky);

        RenderSettings render;
        render.width = width, render.height = height, render.spp = o.spp, render.max_depth = o.max_depth;
        render.seed = o.seed_per_frame ? o.seed + uint64_t(k) * 0x9E3779B97F4A7C15ull : o.seed;
        render.quiet = true;
        render.aovs = aovs;
        render.clamp_indirect = o.clamp_indirect, render.filter_glossy = o.filter_glossy;
        render.pattern = pattern;
        std::optional<LoadedScene> posed;
        std::unique_ptr<Accel> posed_accel;
        if (o.play_scene_animation) {
            SceneSpec spec = o.scene;
            spec.animation_time = animation_start + t;
            posed = animated ? pose_scene(spec, *animated, scene->path, aspect) : load_scene(spec, aspect, false);
            // A file without cameras is framed once, on its first pose: framed on every pose, still
            // objects drifted and changed size as others moved.
            if (posed->scene.cameras.empty() && o.scene.look_at.empty()) posed->camera = scene->camera;
            posed_accel = std::make_unique<Accel>(posed->scene);
        }
        PathIntegrator integrator(posed_accel ? *posed_accel : *accel, light, render);
        RenderResult result = integrator.render(posed ? posed->camera : scene->camera);

        Image& image = result.color;
        if (!warned_black && is_black_everywhere(image)) {
            std::fprintf(stderr, "dynsky: warning: frame %d %s\n", k, kBlackRenderHint);
            warned_black = true;  // once: every frame of such a camera is black
        }
        FrameMetadata meta;
        meta.frame = k, meta.time_seconds = t, meta.fps = o.fps, meta.spp = o.spp, meta.seed = render.seed;
        const float frame_ev = exposure_at(t);
        meta.medium_step_seconds = timeline.dt(), meta.png_exposure_ev = frame_ev;
        meta.sky = sky->source, meta.units = sky->units, meta.sky_model = timeline.model().name(),
        meta.scene = o.scene.scene;
        meta.camera = scene->camera.name, meta.gamma = gamma_name(timeline.gamma());
        meta.settings = settings;
        meta.date_time = exif_date_time(o.sky, *sky0, t);  // the time the input records, + t
        meta.write_to(&image.metadata);
        // The frame's timing row first: killed before its images are all written, the frame is
        // rendered again and its row replaced; the other way round a kept frame lost its row.
        std::ostringstream line;
        line << k << ',' << t << ',' << sky_s * 1e3 << ',' << light.last_build_seconds() * 1e3 << ','
             << result.stats.seconds * 1e3 << ',' << timeline.timings().medium_steps << '\n';
        record_timing(timings, k, line.str(), timings_start_over, total);
        timings_start_over = false;
        // The EXR last: it carries the settings a resumed run keeps a frame by, so PNGs of an
        // earlier run never stay beside it (a run stopped between the files renders the frame again).
        // A frame's files go together: a write failing (a full disk) removes those of this frame
        // already written (a frame_0005.png stayed without its EXR).
        try {
            write_image(store.frame_png(k), tonemap_to_display(image, result.alpha, frame_ev));
            write_image(store.sky_png(k), tonemap_to_display(sky_to_image(*sky), sky_ev + (frame_ev - ev)));
            write_image(store.frame_exr(k), aovs.any() ? render_layers(result) : image);
        } catch (...) {
            std::error_code ec;
            for (const std::string& f : {store.frame_png(k), store.sky_png(k)}) fs::remove(f, ec);
            throw;
        }
        keep[size_t(k)] = 1;

        sum_sky += sky_s, sum_build += light.last_build_seconds(), sum_render += result.stats.seconds, ++rendered;
        if (!o.quiet) {
            const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - loop_start).count();
            std::fprintf(stderr,
                         "frame %d/%d t=%.3f s: sky %.1f ms, distribution %.1f ms, render %.1f ms; %d of %d rendered, "
                         "%.0f s elapsed, about %.0f s left\n",
                         k, total - 1, t, sky_s * 1e3, light.last_build_seconds() * 1e3, result.stats.seconds * 1e3,
                         rendered, to_render, elapsed, elapsed / rendered * (to_render - rendered));
        }
    }
    // An earlier, longer run's rows past this animation's last frame go (none rendered: no rewrite yet).
    if (!farm_task && fs::exists(timings)) record_timing(timings, -1, "", false, total);
    if (!o.quiet) {
        std::fprintf(stderr, "%d frame(s) rendered, %d already complete (kept)\n", rendered, skipped);
        if (rendered > 0)
            std::fprintf(
                stderr,
                "per frame (mean): sky %.1f ms (Gamma + amortised xi: %d medium step(s) this run), distribution %.1f ms, "
                "render %.1f ms; sky work %.2f%% of the frame\n",
                sum_sky / rendered * 1e3, timeline.timings().medium_steps, sum_build / rendered * 1e3,
                sum_render / rendered * 1e3, 100.0 * (sum_sky + sum_build) / (sum_sky + sum_build + sum_render));
    }

    // A farm task does not look at the other tasks' frames (each would decode every frame: quadratic
    // over the farm); the encode stage checks them all, once.
    if (farm_task) return AnimationReport{total, first, last, rendered, skipped, replaced, false, settings};
    // Frames outside the range count only when complete with these settings too.
    std::vector<int> not_complete;
    for (int k = 0; k < total; ++k)
        if (!keep[size_t(k)] &&
            (k >= first && k <= last ? true : store.check(k, width, height, settings).state != FrameCheck::Complete))
            not_complete.push_back(k);
    AnimationReport report{total, first, last, rendered, skipped, replaced, not_complete.empty(), settings};
    if (!report.complete) {
        if (!o.quiet)
            std::fprintf(stderr,
                         "frame(s) %s of 0-%d not complete with these settings yet: videos and contact sheet left "
                         "for later\n",
                         frame_list(not_complete).c_str(), total - 1);
        return report;
    }
    if (!o.no_video) {
        make_video(o.out, "frame", total, o.fps, store.file("animation.mp4"), o.quiet);
        make_video(o.out, "sky", total, o.fps, store.file("sky.mp4"), o.quiet);
    }
    make_contact_sheet(store, total, o.fps, store.file("contact_sheet.png"));
    if (!o.quiet) std::fprintf(stderr, "wrote %s\n", store.file("contact_sheet.png").c_str());
    return report;
}

}  // namespace dynsky
