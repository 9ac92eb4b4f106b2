// The sampling study behind `dynsky bench sampling`: the environment-map importance-sampling benchmark (docs/sampling/).
//
// Renders small scenes under several skies with every sky sampler, measures error against a
// converged reference (cached), per-frame rebuild cost beside a streaming floor, and the failure
// cases; writes a markdown report with tables, CSV files and log-log charts (matplotlib).
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <functional>
#include <string_view>
#include <map>
#include <memory>
#include <sstream>
#include <thread>

#include "bench/sampling_study.h"
#include "util/progress.h"
#include "util/child_process.h"
#include "renderer/builtin_scene.h"
#include "renderer/gltf_loader.h"
#include "renderer/integrator.h"
#include "renderer/sampling.h"
#include "renderer/sky_sampler.h"
#include "renderer/streaming_floor.h"
#include "sky/clear_sky.h"
#include "sky/fisheye.h"
#include "sky/photo_import.h"
#include "sky/procedural_clouds.h"
#include "util/data_path.h"
#include "util/error.h"
#include "util/atomic_file.h"


namespace dynsky {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }


bool selected(const std::vector<std::string>& list, const std::string& name) {
    return list.empty() || std::find(list.begin(), list.end(), name) != list.end();
}

struct NamedSky {
    std::string name, description;
    std::shared_ptr<SkyImage> sky;
};

struct NamedScene {
    std::string name, description;
    Scene scene;
    Camera camera;
};

// Pixel sampling is deterministic in (seed, pixel): renders are repeatable.
RenderResult render(const Accel& accel, const EnvLight& light, const Camera& cam, int w, int h, int spp, uint64_t seed,
                    int depth, bool with_alpha = false) {
    RenderSettings s;
    s.width = w, s.height = h, s.spp = spp, s.seed = seed, s.quiet = true, s.max_depth = depth;
    s.aovs.alpha = with_alpha;  // where the camera sees the scene, not the sky (compare's `scored`)
    return PathIntegrator(accel, light, s).render(cam);
}

struct ErrorStats {
    double rmse = 0, rel_mse = 0, firefly_share = 0;
    double trimmed_rmse = 0;  // without the 0.1% of pixels with the largest error (rare fireflies)
};

// RMSE and relative MSE (per channel, (x - r)^2 / (r^2 + 1e-2 mean^2)); firefly share: fraction of
// the squared error held by the brightest 0.1% of the render's pixels (at least one pixel). Over
// the pixels `scored` marks (all when empty).
ErrorStats compare(const Image& img, const Image& ref, const std::vector<char>& scored = {}) {
    std::vector<size_t> index;
    for (size_t p = 0; p < ref.pixels.size() / 3; ++p)
        if (scored.empty() || scored[p]) index.push_back(p);
    const size_t pixels = index.size();
    if (pixels == 0) return {};
    double mean = 0;
    for (size_t p : index)
        for (int c = 0; c < 3; ++c) mean += ref.pixels[3 * p + c];
    mean /= double(3 * pixels);
    const double eps = 1e-2 * mean * mean + 1e-12;
    std::vector<std::pair<float, double>> by_brightness(pixels);
    std::vector<double> pixel_se(pixels);
    double se = 0, rel = 0;
    for (size_t q = 0; q < pixels; ++q) {
        const size_t p = index[q];
        double e = 0;
        for (int c = 0; c < 3; ++c) {
            double d = double(img.pixels[3 * p + c]) - ref.pixels[3 * p + c];
            e += d * d;
            rel += d * d / (double(ref.pixels[3 * p + c]) * ref.pixels[3 * p + c] + eps);
        }
        se += e;
        pixel_se[q] = e;
        float lum = luminance(img.pixels[3 * p], img.pixels[3 * p + 1], img.pixels[3 * p + 2]);
        by_brightness[q] = {lum, e};
    }
    size_t top = std::max<size_t>(1, pixels / 1000);
    std::partial_sort(by_brightness.begin(), by_brightness.begin() + long(top), by_brightness.end(),
                      [](const auto& a, const auto& b) { return a.first > b.first; });
    double top_e = 0;
    for (size_t k = 0; k < top; ++k) top_e += by_brightness[k].second;
    ErrorStats s;
    s.rmse = std::sqrt(se / (3.0 * pixels));
    // Trimmed as in path-guiding comparisons (Mueller et al. 2017): a handful of fireflies (paths
    // that reach a tiny sun through a glossy bounce, which no sky sampler can help) otherwise
    // decide the whole error and its spp curve stops falling within any affordable run.
    const size_t keep = pixels - std::max<size_t>(1, pixels / 1000);
    std::nth_element(pixel_se.begin(), pixel_se.begin() + long(keep), pixel_se.end());
    double kept = 0;
    for (size_t k = 0; k < keep; ++k) kept += pixel_se[k];
    s.trimmed_rmse = std::sqrt(kept / (3.0 * double(keep)));
    s.rel_mse = rel / (3.0 * pixels);
    s.firefly_share = se > 0 ? top_e / se : 0;
    return s;
}

std::vector<std::string> samplers_under_mis() {
    // Under MIS (the renderer's mode) every pixel-based sampler is measured with and without the
    // compensation; uniform and cosine have nothing to compensate.
    std::vector<std::string> names;
    for (const std::string& n : sky_sampler_base_names()) {
        names.push_back(n);
        if (n != "uniform" && n != "cosine") names.push_back(n + "+mis");
    }
    return names;
}

std::shared_ptr<SkyImage> clear_sky(int n) {
    ClearSkyParams p;
    p.sun_direction = fisheye::direction_from_angles(55 * kPiD / 180, 200 * kPiD / 180);
    p.turbidity = 3;
    auto s = std::make_shared<SkyImage>(make_clear_sky(p, n));
    return s;
}

// The skies selected by --skies (only those are made: a 1024 px procedural sky costs seconds).
std::vector<NamedSky> make_skies(int n, const SamplingStudyOptions& o, std::string* notes) {
    std::vector<NamedSky> skies;
    if (selected(o.skies, "clear"))
        skies.push_back({"clear", "Hosek-Wilkie clear sky, turbidity 3, sun at 35 deg elevation (make_clear_sky)",
                         clear_sky(n)});
    ProceduralSkyParams cu;
    cu.clear_sky.sun_direction = fisheye::direction_from_angles(50 * kPiD / 180, 120 * kPiD / 180);
    cu.coverage = 0.5;
    cu.seed = 3;
    if (selected(o.skies, "cumulus"))
        skies.push_back({"cumulus", "procedural broken cumulus, coverage 0.5, sun at 40 deg (render_procedural_sky)",
                         std::make_shared<SkyImage>(render_procedural_sky(cu, 0.0, n))});
    ProceduralSkyParams ov = cu;
    ov.coverage = 1.0;
    ov.layers[0].optical_depth = 60;
    if (selected(o.skies, "overcast"))
        skies.push_back({"overcast", "procedural overcast, coverage 1.0, optical depth 60 (render_procedural_sky)",
                         std::make_shared<SkyImage>(render_procedural_sky(ov, 0.0, n))});
    std::string photo = o.shared + "/skies/mobotix_sophia_20200812_morning/images/2020-08-12_10_00.jpg";
    if (selected(o.skies, "photo")) try {
            PhotoImportParams pp;
            pp.resolution = n;
            ImportedPhoto imp = import_photo(photo, pp);
            skies.push_back({"photo",
                             "Mobotix all-sky photograph 2020-08-12 10:00 (import_photo, 8-bit, display-referred)",
                             std::make_shared<SkyImage>(std::move(imp.sky))});
        } catch (const std::exception& e) {
            *notes += std::string("- photo sky skipped: ") + e.what() + "\n";
            // Said where it is seen too (a warning, also under -q): the study's medians are then
            // over fewer skies than asked for.
            std::fprintf(stderr, "dynsky: warning: bench sampling: the photo sky is skipped: %s\n", e.what());
        }
    return skies;
}

// The scenes selected by --scenes (only those are loaded).
std::vector<NamedScene> make_scenes(const SamplingStudyOptions& o, float aspect, std::string* notes) {
    std::vector<NamedScene> scenes;
    auto add = [&](const std::string& name, const std::string& desc, const std::function<Scene()>& make) {
        if (!selected(o.scenes, name)) return;
        Scene s = make();
        Camera cam = s.cameras.empty() ? frame_bounds_camera(s.world_bounds(), aspect) : s.cameras[0];
        scenes.push_back({name, desc, std::move(s), cam});
    };
    auto gltf = [&](const std::string& name, const std::string& rel, const std::string& desc) {
        std::string path = o.shared + "/scenes/" + rel;
        if (!selected(o.scenes, name)) return;
        if (!fs::exists(path)) {
            *notes += "- scene " + name + " skipped: " + path + " not found\n";
            std::fprintf(stderr, "dynsky: warning: bench sampling: scene %s is skipped: %s not found (--shared)\n",
                         name.c_str(), path.c_str());
            return;
        }
        add(name, desc, [&] { return load_gltf(path); });
    };
    gltf("diffuse", "Box/Box.glb", "Khronos Box (diffuse), framed");
    gltf("glossy", "MetalRoughSpheresNoTextures/MetalRoughSpheresNoTextures.glb",
         "Khronos MetalRoughSpheresNoTextures (glossy)");
    add("plaza", "built-in plaza (renderer/builtin_scene.h)", [] { return make_builtin_scene(); });
    // The House animation scene shipped with dynsky (Kenney CC0 buildings, its own camera).
    add("house", "scenes/house/house.gltf (Kenney buildings, textured; its camera)",
        [] { return load_gltf(data_path("scenes/house/house.gltf")); });
    return scenes;
}

// Log-log interpolation of y at x over a series sorted by x; outside the measured range it goes on
// at the Monte Carlo rate, y ~ x^slope (slope -1/2 for error against time, -2 for time against error).
double loglog_at(const std::vector<double>& xs, const std::vector<double>& ys, double x, double slope) {
    if (x <= xs.front()) return ys.front() * std::pow(x / xs.front(), slope);
    if (x >= xs.back()) return ys.back() * std::pow(x / xs.back(), slope);
    size_t k = 1;
    while (k + 1 < xs.size() && xs[k] < x) ++k;
    double lx0 = std::log(xs[k - 1]), lx1 = std::log(xs[k]), ly0 = std::log(std::max(ys[k - 1], 1e-30)),
           ly1 = std::log(std::max(ys[k], 1e-30));
    double t = lx1 != lx0 ? (std::log(x) - lx0) / (lx1 - lx0) : 0;
    return std::exp(ly0 + t * (ly1 - ly0));
}

std::string fmt(const char* f, double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, f, v);
    return buf;
}

// The sampler references are rendered with: the study's own least noisy under a sun (sun+cdf+mis, the
// noisiest, made the failure table measure its reference's noise: every sampler 179-183 on a 1e6 sun).
const char* const kReferenceSampler = "cdf+mis";

// A sky's pixels as a key for the cache (the same name may hold another photograph or file).
std::string sky_content_key(const SkyImage& sky) {
    const std::string_view bytes(reinterpret_cast<const char*>(sky.rgb.data()), sky.rgb.size() * sizeof(float));
    char buf[24];
    std::snprintf(buf, sizeof buf, "%016zx", std::hash<std::string_view>{}(bytes));
    return buf;
}

// Reference image cache: EXR per (scene, sky and its pixels, size, spp, depth, sampler).
Image reference(const Accel& accel, const NamedScene& sc, const NamedSky& sky, int w, int h, int spp, int depth,
                const fs::path& cache) {
    fs::path file = cache / (sc.name + "_" + sky.name + "_" + std::to_string(w) + "x" + std::to_string(h) + "_" +
                             std::to_string(spp) + "spp_d" + std::to_string(depth) + "_n" +
                             std::to_string(sky.sky->resolution) + "_" + sky_content_key(*sky.sky) + "_" +
                             kReferenceSampler + ".exr");
    if (fs::exists(file)) return read_image(file.string());
    EnvLight light(sky.sky, 0.3f, parse_sky_sampler(kReferenceSampler));
    Image img = render(accel, light, sc.camera, w, h, spp, 12345, depth).color;
    write_image(file.string(), img);
    return img;
}

// One render of the accuracy study: a frame's rebuild and render timed apart.
struct Run {
    std::string scene, sky, sampler;
    int spp, seed;
    double render_seconds, rebuild_seconds, rmse, rel_mse, firefly, trimmed_rmse;
};

// Seconds per sample per pixel from renders (spp, seconds): the median of the slopes between every
// two renders of different spp (Theil-Sen), so that neither a render slowed by the machine's load
// nor the fixed cost of a render decides it (seconds / spp pooled over the renders let the single
// largest render set it: one slow 16 spp render moved a speed-up from 2.4 to 1.06x). Pooled
// seconds / spp when no two renders differ in spp.
double seconds_per_spp_of(const std::vector<std::vector<std::pair<double, double>>>& seeds) {
    // Pairs within a seed only, as the per-seed bracket takes them (pairs across seeds put the
    // estimate outside its own bracket).
    std::vector<double> slopes;
    double secs = 0, spp = 0;
    for (const auto& renders : seeds)
        for (size_t a = 0; a < renders.size(); ++a) {
            secs += renders[a].second, spp += renders[a].first;
            for (size_t b = 0; b < renders.size(); ++b)
                if (renders[b].first > renders[a].first)
                    slopes.push_back((renders[b].second - renders[a].second) / (renders[b].first - renders[a].first));
        }
    if (slopes.empty()) return spp > 0 ? secs / spp : 0.0;
    return std::max(median(slopes), 1e-12);
}

// A sampler's results on one scene and sky: per spp level, the RMSE of every seed, and its cost
// model: seconds per frame = rebuild + spp x seconds per spp (seconds_per_spp_of over all its
// renders; per seed over that seed's, for the bracket, so it shows the timing noise as well).
struct Curve {
    std::vector<double> spp;
    std::vector<std::vector<double>> rmse;            // [spp level][seed]: trimmed RMSE (see compare)
    std::vector<double> rel_mse, firefly, full_rmse;  // means per spp level (full_rmse: untrimmed)
    double seconds_per_spp = 0, rebuild_seconds = 0;
    std::vector<double> seed_seconds_per_spp;  // [seed]
    double seed_seconds_at(int seed, double spp_value) const {
        return rebuild_seconds + spp_value * seed_seconds_per_spp[size_t(seed)];
    }
    double mean_rmse(size_t level) const {
        double s = 0;
        for (double e : rmse[level]) s += e;
        return s / double(rmse[level].size());
    }
    double std_rmse(size_t level) const {
        double m = mean_rmse(level), s = 0;
        for (double e : rmse[level]) s += (e - m) * (e - m);
        return rmse[level].size() > 1 ? std::sqrt(s / double(rmse[level].size() - 1)) : 0.0;
    }
    double seconds_at(double spp_value) const { return rebuild_seconds + spp_value * seconds_per_spp; }
};

std::string machine_description() {
    std::string cpu = "unknown CPU";
    std::ifstream f("/proc/cpuinfo");
    std::string line;
    while (std::getline(f, line))
        if (line.rfind("model name", 0) == 0) {
            cpu = line.substr(line.find(':') + 2);
            break;
        }
    return cpu + ", " + std::to_string(std::thread::hardware_concurrency()) +
           " hardware threads (shared with other work: wall "
           "times are noisy, ratios measured in the same run)";
}

}  // namespace

int run_sampling_study(const SamplingStudyOptions& o) {
    auto start = Clock::now();
    for (const std::string& name : o.samplers) parse_sky_sampler(name);  // a clear error before any output
    // The report and cache folders must not be, or lie in, the shared data the study reads.
    check_outputs_are_not_inputs({o.out, o.cache}, {o.shared});
    fs::path out(o.out);
    const OutputFolder out_folder(o.out);  // removed again if the study fails before writing anything
    remove_stale_temporaries(o.out);       // of a killed run into the same folder
    fs::path cache = o.cache.empty() ? out / "cache" : fs::path(o.cache);
    std::string notes;

    const int sky_n = o.quick ? 256 : 1024;
    const int w = o.quick ? 32 : 160, h = o.quick ? 24 : 120;
    const int depth = o.quick ? 3 : 5;
    const int ref_spp = o.quick ? 384 : 4096;
    const std::vector<int> spps = o.quick ? std::vector<int>{1, 4, 16} : std::vector<int>{1, 2, 4, 8, 16, 32, 64};
    const int seeds = o.seeds > 0 ? o.seeds : (o.quick ? 2 : 4);
    std::vector<std::string> samplers;
    for (const std::string& name : samplers_under_mis())
        if (selected(o.samplers, name)) samplers.push_back(name);
    if (!o.samplers.empty() && !selected(o.samplers, "cdf"))
        notes += "- plain cdf (the baseline of every speed-up) was not selected: no speed-ups\n";
    const bool run_accuracy = selected(o.parts, "accuracy"), run_rebuild = selected(o.parts, "rebuild"),
               run_failures = selected(o.parts, "failures");

    // Skies serve the accuracy part, scenes also the failure cases: neither is made for others.
    std::vector<NamedSky> skies;
    if (run_accuracy) {
        if (!reports_silenced()) std::fprintf(stderr, "sampling bench: skies...\n");
        skies = make_skies(sky_n, o, &notes);
    }
    std::vector<NamedScene> scenes;
    if (run_accuracy || run_failures) {
        if (!reports_silenced()) std::fprintf(stderr, "sampling bench: scenes...\n");
        scenes = make_scenes(o, float(w) / h, &notes);
        // Nothing to measure is an error, not an empty report.
        if (scenes.empty())
            throw_file_error(o.shared,
                             "none of the selected scenes (--scenes) could be loaded (its scenes/ missing?):\n" +
                                 notes);
    }
    // An input missing or bad (exit 1), not a usage error; nothing written yet.
    if (run_accuracy && skies.empty())
        throw_file_error(o.shared, "none of the selected skies (--skies) could be made:\n" + notes);
    if (run_accuracy) {
        std::error_code ec;
        fs::create_directories(cache, ec);
        if (ec) throw_file_error(cache.string(), "cannot create the cache folder: " + ec.message());
    }

    // ---- Accuracy against time ----
    std::vector<Run> runs;
    std::ostringstream acc_csv, sum_csv, eq;
    acc_csv << "scene,sky,sampler,spp,seed,render_seconds,rebuild_seconds,rmse,rel_mse,firefly,trimmed_rmse\n";
    sum_csv << "scene,sky,sampler,spp,seconds,trimmed_rmse,trimmed_rmse_std,rmse,rel_mse,firefly\n";
    eq << "| scene | sky | sampler | trimmed RMSE at cdf's time | rel. MSE at max spp | time to cdf's error (ms) | speed-up vs cdf "
          "[min, max over seeds] | spp gain vs cdf | ms per spp | fireflies |\n|---|---|---|---|---|---|---|---|---|---|\n";
    std::map<std::string, std::vector<double>> speedups, sunny_speedups, spp_gains, sunny_spp_gains;
    std::map<std::string, std::vector<double>> sunny_low, sunny_high;  // per-seed extremes of the sunny speed-ups
    // Spp needed to reach `target` on a curve (log-log; the Monte Carlo rate outside the range).
    auto monotone = [](std::vector<double> err) {  // noise: keep an error curve from rising
        for (size_t k = 1; k < err.size(); ++k) err[k] = std::min(err[k], err[k - 1]);
        return err;
    };
    auto spp_to_reach = [&](const std::vector<double>& spp, std::vector<double> err, double target) {
        err = monotone(err);
        std::vector<double> er(err.rbegin(), err.rend()), sr(spp.rbegin(), spp.rend());
        for (size_t k = 1; k < er.size(); ++k) er[k] = std::max(er[k], er[k - 1]);
        return loglog_at(er, sr, target, -2.0);
    };
    if (run_accuracy)
        for (const NamedScene& sc : scenes) {
            Accel accel(sc.scene);
            for (const NamedSky& sky : skies) {
                if (!reports_silenced())
                    std::fprintf(stderr, "sampling bench: %s / %s (reference %d spp)\n", sc.name.c_str(),
                                 sky.name.c_str(), ref_spp);
                Image ref = reference(accel, sc, sky, w, h, ref_spp, depth, cache);
                // A finished case is kept in the cache (its rows, timings included), so a long run
                // that is stopped resumes at the first unfinished case: no finished work is lost.
                std::string key = sc.name + "_" + sky.name + "_" + std::to_string(w) + "x" + std::to_string(h) + "_d" +
                                  std::to_string(depth) + "_n" + std::to_string(sky_n) + "_s" + std::to_string(seeds) +
                                  "_" + sky_content_key(*sky.sky) + "_" + kReferenceSampler + "_spp";
                for (int spp : spps) key += "-" + std::to_string(spp);
                std::string sampler_list;
                for (const std::string& name : samplers) sampler_list += name + ";";
                key += "_" + std::to_string(std::hash<std::string>{}(sampler_list) % 1000000007ULL);
                // runs2_: every digit (runs_ files kept six, and a summary made from them moved).
                const fs::path case_file = cache / ("runs2_" + key + ".csv");
                std::ostringstream case_csv;
                bool resumed = false;
                if (fs::exists(case_file)) {
                    std::ifstream in(case_file);
                    std::string line;
                    std::vector<Run> loaded;
                    while (std::getline(in, line)) {
                        std::istringstream ls(line);
                        Run r;
                        std::string field;
                        std::vector<std::string> f;
                        while (std::getline(ls, field, ',')) f.push_back(field);
                        if (f.size() != 11) continue;
                        try {
                            r = {f[0],
                                 f[1],
                                 f[2],
                                 std::stoi(f[3]),
                                 std::stoi(f[4]),
                                 std::stod(f[5]),
                                 std::stod(f[6]),
                                 std::stod(f[7]),
                                 std::stod(f[8]),
                                 std::stod(f[9]),
                                 std::stod(f[10])};
                        } catch (const std::exception&) {
                            continue;
                        }
                        loaded.push_back(r);
                    }
                    if (loaded.size() == samplers.size() * spps.size() * size_t(seeds)) {
                        for (const Run& r : loaded) {
                            runs.push_back(r);
                            acc_csv << r.scene << "," << r.sky << "," << r.sampler << "," << r.spp << "," << r.seed
                                    << "," << r.render_seconds << "," << r.rebuild_seconds << "," << r.rmse << ","
                                    << r.rel_mse << "," << r.firefly << "," << r.trimmed_rmse << "\n";
                        }
                        resumed = true;
                        if (!reports_silenced())
                            std::fprintf(stderr, "sampling bench: %s / %s: finished earlier, read from %s\n",
                                         sc.name.c_str(), sky.name.c_str(), case_file.c_str());
                    }
                }
                std::map<std::string, std::unique_ptr<EnvLight>> lights;
                if (!resumed)
                    for (const std::string& name : samplers)
                        lights[name] = std::make_unique<EnvLight>(sky.sky, 0.3f, parse_sky_sampler(name));
                // Samplers interleaved inside each (seed, spp): the machine's load falls on all alike.
                for (int seed = 0; !resumed && seed < seeds; ++seed)
                    for (int spp : spps)
                        for (const std::string& name : samplers) {
                            EnvLight& light = *lights[name];
                            auto t0 = Clock::now();
                            light.set_sky(sky.sky);  // a frame: rebuild, then render
                            double rebuild = seconds_since(t0);
                            auto t1 = Clock::now();
                            RenderResult r = render(accel, light, sc.camera, w, h, spp, 7 + 7919 * uint64_t(seed),
                                                    depth);
                            double secs = seconds_since(t1);
                            ErrorStats e = compare(r.color, ref);
                            runs.push_back({sc.name, sky.name, name, spp, seed, secs, rebuild, e.rmse, e.rel_mse,
                                            e.firefly_share, e.trimmed_rmse});
                            // The cache keeps every digit (a summary made from it equals a fresh run's;
                            // six digits moved it in the sixth); accuracy.csv is for reading.
                            auto write_row = [&](std::ostream& out) {
                                out << sc.name << "," << sky.name << "," << name << "," << spp << "," << seed << ","
                                    << secs << "," << rebuild << "," << e.rmse << "," << e.rel_mse << ","
                                    << e.firefly_share << "," << e.trimmed_rmse << "\n";
                            };
                            write_row(acc_csv);
                            case_csv << std::setprecision(17);
                            write_row(case_csv);
                        }
                if (!resumed) write_file_atomic(case_file.string(), case_csv.str());
                // Curves and the cost model.
                std::map<std::string, Curve> curves;
                for (const std::string& name : samplers) {
                    Curve& c = curves[name];
                    std::vector<std::pair<double, double>> timed;
                    std::vector<std::vector<std::pair<double, double>>> seed_timed;
                    seed_timed.resize(size_t(seeds));
                    std::vector<double> rebuilds;
                    for (int spp : spps) {
                        c.spp.push_back(spp);
                        c.rmse.emplace_back();
                        double rel = 0, ff = 0, full = 0;
                        for (const Run& r : runs)
                            if (r.scene == sc.name && r.sky == sky.name && r.sampler == name && r.spp == spp) {
                                c.rmse.back().push_back(r.trimmed_rmse);
                                rel += r.rel_mse / seeds, ff += r.firefly / seeds, full += r.rmse / seeds;
                                timed.emplace_back(spp, r.render_seconds);
                                if (r.seed >= 0 && r.seed < seeds)
                                    seed_timed[size_t(r.seed)].emplace_back(spp, r.render_seconds);
                                rebuilds.push_back(r.rebuild_seconds);
                            }
                        c.rel_mse.push_back(rel), c.firefly.push_back(ff), c.full_rmse.push_back(full);
                    }
                    c.seconds_per_spp = seconds_per_spp_of(seed_timed);
                    if (!(c.seconds_per_spp > 0)) c.seconds_per_spp = seconds_per_spp_of({timed});
                    for (const auto& t : seed_timed)
                        c.seed_seconds_per_spp.push_back(t.empty() ? c.seconds_per_spp : seconds_per_spp_of({t}));
                    c.rebuild_seconds = median(rebuilds);
                    for (size_t k = 0; k < c.spp.size(); ++k)
                        sum_csv << sc.name << "," << sky.name << "," << name << "," << c.spp[k] << ","
                                << c.seconds_at(c.spp[k]) << "," << c.mean_rmse(k) << "," << c.std_rmse(k) << ","
                                << c.full_rmse[k] << "," << c.rel_mse[k] << "," << c.firefly[k] << "\n";
                }
                if (!curves.count("cdf")) continue;
                const Curve& cdf = curves["cdf"];
                const size_t top = cdf.spp.size() - 1;
                std::vector<double> cdf_mean(cdf.spp.size());
                for (size_t k = 0; k < cdf_mean.size(); ++k) cdf_mean[k] = cdf.mean_rmse(k);
                const double target = monotone(cdf_mean).back(), t_cdf = cdf.seconds_at(cdf.spp[top]);
                for (const std::string& name : samplers) {
                    const Curve& c = curves[name];
                    std::vector<double> mean(c.spp.size());
                    for (size_t k = 0; k < mean.size(); ++k) mean[k] = c.mean_rmse(k);
                    double need = spp_to_reach(c.spp, mean, target);
                    double speedup = t_cdf / c.seconds_at(need), gain = cdf.spp[top] / need;
                    // Per seed: both curves of that seed, so the spread shows the Monte Carlo noise.
                    double lo = 1e300, hi = 0;
                    for (int k = 0; k < seeds; ++k) {
                        std::vector<double> ek(c.spp.size()), ck(cdf.spp.size());
                        for (size_t l = 0; l < ek.size(); ++l)
                            ek[l] = c.rmse[l][size_t(k)], ck[l] = cdf.rmse[l][size_t(k)];
                        double sk = cdf.seed_seconds_at(k, cdf.spp[top]) /
                                    c.seed_seconds_at(k, spp_to_reach(c.spp, ek, monotone(ck).back()));
                        lo = std::min(lo, sk), hi = std::max(hi, sk);
                    }
                    double spp_at_equal_time = std::max((t_cdf - c.rebuild_seconds) / c.seconds_per_spp, 1e-3);
                    double e_at = loglog_at(c.spp, mean, spp_at_equal_time, -0.5);
                    speedups[name].push_back(speedup), spp_gains[name].push_back(gain);
                    if (sky.name == "clear") {
                        sunny_speedups[name].push_back(speedup), sunny_spp_gains[name].push_back(gain);
                        sunny_low[name].push_back(lo), sunny_high[name].push_back(hi);
                    }
                    eq << "| " << sc.name << " | " << sky.name << " | " << name << " | " << fmt("%.4g", e_at) << " | "
                       << fmt("%.3g", c.rel_mse.back()) << " | " << fmt("%.3g", 1e3 * c.seconds_at(need)) << " | "
                       << fmt("%.2f", speedup) << " [" << fmt("%.2f", lo) << ", " << fmt("%.2f", hi) << "] | "
                       << fmt("%.2f", gain) << " | " << fmt("%.3g", 1e3 * c.seconds_per_spp) << " | "
                       << fmt("%.2f", c.firefly.back()) << " |\n";
                }
            }
        }
    if (run_accuracy) {
        write_file_atomic((out / "accuracy.csv").string(), acc_csv.str());
        write_file_atomic((out / "accuracy_summary.csv").string(), sum_csv.str());
    }

    // ---- Rebuild cost ----
    if (run_rebuild && !reports_silenced()) std::fprintf(stderr, "sampling bench: rebuild timings\n");
    std::vector<int> sizes = o.quick ? std::vector<int>{256, 1024, 2048} : std::vector<int>{256, 512, 1024, 2048, 4096};
    if (!run_rebuild) sizes.clear();
    std::ostringstream rb_csv, rb;
    rb_csv << "sampler,n,threads,ms,ratio_to_floor,memory_mib\n";
    rb << "| sampler | N | threads | rebuild ms | floor ms | ratio to floor | memory MiB |\n|---|---|---|---|---|---|---|\n";
    std::map<std::string, double> ratio_2048;
    std::ostringstream per_call;  // sample() and pdf() cost at 1024, one thread
    std::vector<std::string> build_names;
    for (const char* name :
         {"cdf", "alias", "mip", "sun+cdf", "sun+alias", "sun+mip", "cdf+mis", "alias+mis", "mip+mis"})
        if (selected(o.samplers, name)) build_names.push_back(name);
    for (int n : sizes) {
        auto sky = clear_sky(n);
        for (int threads : {1, 0}) {
            std::unique_ptr<tbb::global_control> gc;
            if (threads == 1)
                gc = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, 1);
            const int reps = n >= 2048 ? 3 : 7;
            for (const std::string& name : build_names) {
                EnvLight light(sky, 0.3f, parse_sky_sampler(name));
                light.set_sky(sky);  // steady state: a frame's buffers are allocated by the first two frames
                std::vector<float> scratch;
                std::vector<double> rs, fs_;
                for (int k = 0; k < reps; ++k) {
                    auto t = Clock::now();
                    light.set_sky(sky);
                    rs.push_back(seconds_since(t));
                    fs_.push_back(time_streaming_floor(*sky, &scratch));  // interleaved: same load on the machine
                }
                double r = median(rs), f = median(fs_);
                std::string th = threads == 1 ? "1" : "all";
                rb_csv << name << "," << n << "," << th << "," << r * 1e3 << "," << r / f << ","
                       << light.memory_bytes() / 1048576.0 << "\n";
                rb << "| " << name << " | " << n << " | " << th << " | " << fmt("%.2f", r * 1e3) << " | "
                   << fmt("%.2f", f * 1e3) << " | " << fmt("%.2f", r / f) << " | "
                   << fmt("%.1f", light.memory_bytes() / 1048576.0) << " |\n";
                if (n == 2048 && threads == 0) ratio_2048[name] = r / f;
                if (n == 1024 && threads == 1) {
                    // Cost of one sample() and one pdf() call (uniforms and directions prepared first).
                    const int calls = 200000;
                    Rng rng(5, 1);
                    std::vector<Vec2> us(4096);
                    for (Vec2& u : us) u = rng.uniform2();
                    std::vector<Vec3> dirs;
                    for (const Vec2& u : us) {
                        EnvLightSample ls;
                        if (light.sample(0.5f, u, &ls)) dirs.push_back(ls.wi);
                    }
                    double acc = 0;
                    auto t0 = Clock::now();
                    for (int k = 0; k < calls; ++k) {
                        EnvLightSample ls;
                        if (light.sample(0.5f, us[size_t(k) % us.size()], &ls)) acc += ls.pdf;
                    }
                    double sample_ns = seconds_since(t0) * 1e9 / calls;
                    t0 = Clock::now();
                    for (int k = 0; dirs.size() && k < calls; ++k) acc += light.pdf(dirs[size_t(k) % dirs.size()]);
                    double pdf_ns = seconds_since(t0) * 1e9 / calls;
                    if (!std::isfinite(acc)) notes += "- non-finite pdf sum: " + name + "\n";
                    per_call << "| " << name << " | " << fmt("%.0f", sample_ns) << " | " << fmt("%.0f", pdf_ns)
                             << " |\n";
                }
            }
            std::vector<float> scratch;
            std::vector<double> fs_;
            for (int k = 0; k < reps; ++k) fs_.push_back(time_streaming_floor(*sky, &scratch));
            rb_csv << "floor," << n << "," << (threads == 1 ? "1" : "all") << "," << median(fs_) * 1e3 << ",1,0\n";
        }
    }
    if (run_rebuild) write_file_atomic((out / "rebuild.csv").string(), rb_csv.str());

    // ---- Failure cases (on the plaza, or the first scene) ----
    if (run_failures && !reports_silenced()) std::fprintf(stderr, "sampling bench: failure cases\n");
    std::ostringstream fl_csv, fl;
    fl_csv << "case,sampler,rmse,rel_mse,firefly\n";
    fl << "| case | sampler | RMSE | rel. MSE | firefly share |\n|---|---|---|---|---|\n";
    std::string failure_scene;
    if (run_failures && !scenes.empty()) {
        // The plaza (small, open: the sky is seen directly and through bounces), else the last scene.
        const NamedScene* chosen = &scenes.back();
        for (const NamedScene& candidate : scenes)
            if (candidate.name == "plaza") chosen = &candidate;
        const NamedScene& sc = *chosen;
        failure_scene = sc.name;
        Accel accel(sc.scene);
        const int n = 128, spp = o.quick ? 8 : 32;
        Vec3 sun = fisheye::direction_from_angles(0.8, 2.0).cast<float>();
        auto base = [&]() {
            auto s = std::make_shared<SkyImage>(n);
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i) {
                    Vec2 c = fisheye::pixel_center_uv(i, j, n);
                    if (c.squaredNorm() <= 1)
                        s->set_pixel(i, j, Color(0.3f, 0.5f, 1.0f) * (0.3f + fisheye::direction_from_uv(c).y()));
                }
            return s;
        };
        auto sun_pixel = [&](std::shared_ptr<SkyImage> s, const Vec3& d, float value) {
            Vec2 uv;
            fisheye::uv_from_direction(d, &uv);
            s->set_pixel(std::clamp(int((uv.x() + 1) / 2 * n), 0, n - 1),
                         std::clamp(int((uv.y() + 1) / 2 * n), 0, n - 1), Color::Constant(value));
            return s;
        };
        std::vector<NamedSky> cases;
        cases.push_back({"subtexel_sun", "", sun_pixel(base(), sun, 2e3f)});
        cases.push_back({"sun_1e6", "", sun_pixel(base(), sun, 1e6f)});
        cases.push_back({"horizon_sun", "",
                         sun_pixel(base(), fisheye::direction_from_angles(1.54, 1.0).cast<float>(), 2e3f)});
        auto single = std::make_shared<SkyImage>(n);
        single->set_pixel(40, 70, Color(50, 40, 30));
        cases.push_back({"single_pixel", "", single});
        auto bad = base();
        bad->set_pixel(60, 60, Color(std::numeric_limits<float>::quiet_NaN(), 1, 1));
        bad->set_pixel(61, 60, Color(std::numeric_limits<float>::infinity(), 1, 1));
        bad->set_pixel(62, 60, Color(-100, 1, 1));
        cases.push_back({"nan_inf_negative", "", bad});
        auto rim = std::make_shared<SkyImage>(n);
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                float r = fisheye::pixel_center_uv(i, j, n).norm();
                if (r <= 1 && r > 1 - 2.0f / n) rim->set_pixel(i, j, Color(20, 20, 20));
            }
        cases.push_back({"horizon_rim", "", rim});
        cases.push_back({"all_black", "", std::make_shared<SkyImage>(n)});
        for (const NamedSky& c : cases) {
            // Reference: the light with NaNs removed is what every sampler must converge to.
            EnvLight ref_light(c.sky, 0.3f, parse_sky_sampler(kReferenceSampler));
            const RenderResult reference = render(accel, ref_light, sc.camera, w, h, ref_spp, 4321, depth, true);
            const Image& ref = reference.color;
            // Scored where the camera sees the scene: a pixel that sees the sky directly is the same
            // for every sky sampler, and where it sees a 1e6 sun it held 96-99.5 % of each one's error.
            std::vector<char> surface(reference.alpha.pixels.size());
            for (size_t p = 0; p < surface.size(); ++p) surface[p] = reference.alpha.pixels[p] > 0.999f;
            for (const std::string& name : samplers) {
                EnvLight light(c.sky, 0.3f, parse_sky_sampler(name));
                Image img = render(accel, light, sc.camera, w, h, spp, 7, depth).color;
                bool finite = std::all_of(img.pixels.begin(), img.pixels.end(),
                                          [](float v) { return std::isfinite(v); });
                ErrorStats e = compare(img, ref, surface);
                if (!finite) notes += "- NON-FINITE pixels: " + c.name + " / " + name + "\n";
                fl_csv << c.name << "," << name << "," << e.rmse << "," << e.rel_mse << "," << e.firefly_share << "\n";
                fl << "| " << c.name << " | " << name << " | " << fmt("%.4g", e.rmse) << " | " << fmt("%.3g", e.rel_mse)
                   << " | " << fmt("%.2f", e.firefly_share) << " |\n";
            }
        }
    }
    if (run_failures) write_file_atomic((out / "failures.csv").string(), fl_csv.str());

    // ---- Charts ----
    std::string script = data_path("bench/sampling_charts.py");
    std::string chart_output;
    const ChildResult charts = run_program({"/usr/bin/python3", script, out.string()}, &chart_output);
    const bool charts_failed = !charts.exited || charts.exit_code != 0;
    if (charts_failed)
        notes += "- the charts were NOT all written (" + script + " exit " + std::to_string(charts.exit_code) +
                 "); the tables and CSV files are complete\n";

    // ---- Recommendation: fastest median time to plain cdf's error over all cases ----
    auto med = [](std::vector<double> v) { return v.empty() ? 0.0 : middle_mean(std::move(v)); };
    std::string best;
    double best_speed = 0;
    for (const auto& [name, v] : speedups)
        if (med(v) > best_speed) best_speed = med(v), best = name;
    std::string def = sky_sampler_name(recommended_sky_sampler()) + "+mis";
    std::string command = "dynsky bench sampling" + std::string(o.quick ? " --quick" : "") + " --seeds " +
                          std::to_string(seeds);
    auto list_option = [&](const char* flag, const std::vector<std::string>& v) {
        if (v.empty()) return;
        command += std::string(" ") + flag + " ";
        for (size_t k = 0; k < v.size(); ++k) command += (k ? "," : "") + v[k];
    };
    list_option("--skies", o.skies), list_option("--scenes", o.scenes), list_option("--samplers", o.samplers);
    list_option("--parts", o.parts);
    command += " --out " + o.out;

    std::ostringstream md;
    md << "# Sky importance sampling benchmark\n\n"
       << "Produced by `" << command << "` in " << fmt("%.0f", seconds_since(start)) << " s.\n\n"
       << "Machine: " << machine_description() << ".\n\n"
       << "Settings: sky " << sky_n << "x" << sky_n << ", image " << w << "x" << h << ", max depth " << depth << ", "
       << seeds << " seeds per point, reference " << ref_spp << " spp (" << kReferenceSampler << ", cached in "
       << cache.string() << "), MIS (power heuristic) throughout"
       << (run_accuracy || run_failures ? "" : " (accuracy and failures not run)") << ".\n\n";
    if (run_accuracy) {
        md << "## Recommendation\n\n";
        // Speed-ups are to plain cdf's error: without cdf (or the default) among the samplers run
        // there is nothing to state, not a speed-up of 0.
        if (best.empty())
            md << "Not measured: speed-ups are to plain cdf's error, and cdf was not among the samplers run "
                  "(--samplers).\n\n";
        else
            md << "Best median speed-up to plain cdf's error over the scenes and skies measured: **" << best << "** ("
               << fmt("%.2f", best_speed) << "x; " << fmt("%.2f", med(spp_gains[best])) << "x fewer spp). ";
        md << "The renderer's default is **" << def
           << "** (`render`'s default --sampler; a name given there is used as given: cdf renders without MIS).\n\n";
        if (!best.empty() && !sunny_speedups[def].empty())
            md << "Under the clear (sunny) sky, median over the scenes of the default's speed-up to plain cdf's error: "
               << fmt("%.2f", med(sunny_speedups[def]))
               << "x (per-seed range of the scenes' speed-ups: " << fmt("%.2f", med(sunny_low[def])) << "x to "
               << fmt("%.2f", med(sunny_high[def])) << "x, medians over the scenes; goal: >= 2x).\n\n";
        else
            md << "The default's speed-up under the clear (sunny) sky: not measured (it needs cdf and " << def
               << " among the samplers and the clear sky among the skies).\n\n";
    }
    if (run_rebuild)
        md << "Rebuild at 2048 of the default (" << def << "), all threads: " << fmt("%.2f", ratio_2048[def])
           << "x the streaming floor (goal: <= 2x); plain cdf: " << fmt("%.2f", ratio_2048["cdf"]) << "x.\n\n";
    if (run_accuracy) {
        md << "How time is measured: every render is timed apart from its frame's rebuild; a sampler's cost is modelled as "
              "rebuild + spp x (seconds per spp): the median rebuild, and the median of the slopes between every two of its "
              "renders of one seed "
              "(of that scene and sky) at different spp (Theil-Sen: neither one slow render nor a render's fixed cost "
              "decides it; samplers interleaved in the same loop, so the machine's load falls on all alike). Error = RMSE without the 0.1% of pixels with the largest error "
              "(as in path-guiding comparisons, e.g. Mueller et al. 2017: otherwise a handful of fireflies, paths that reach "
              "the tiny sun through a glossy bounce, which no sky sampler helps, decide the whole error; the untrimmed RMSE "
              "and the fireflies' share are in the tables and CSV files). Time to error = that cost at the spp where the "
              "sampler's mean error (over seeds) reaches plain cdf's mean error at its highest spp; speed-up = cdf's time / that "
              "time; the bracket is the range of the same speed-up computed from each seed's curves and timings alone, so it shows the timing noise too "
              "(it need not contain the figure before it: the mean of the seeds' error curves crosses cdf's mean error "
              "at another spp than any one seed's curve crosses its own). The spp gain is "
              "the same ratio at equal samples per pixel.\n\n"
              "| sampler | median speed-up | sunny (clear) median | sunny per-seed range | median spp gain | sunny spp gain |\n"
              "|---|---|---|---|---|---|\n";
        for (const auto& [name, v] : speedups)
            md << "| " << name << " | " << fmt("%.2f", med(v)) << " | " << fmt("%.2f", med(sunny_speedups[name]))
               << " | " << fmt("%.2f", med(sunny_low[name])) << " - " << fmt("%.2f", med(sunny_high[name])) << " | "
               << fmt("%.2f", med(spp_gains[name])) << " | " << fmt("%.2f", med(sunny_spp_gains[name])) << " |\n";
    }
    if (run_accuracy) {
        md << "\n## Skies\n\n";
        for (const NamedSky& s : skies) md << "- " << s.name << ": " << s.description << "\n";
        md << "\n## Scenes\n\n";
        for (const NamedScene& s : scenes) md << "- " << s.name << ": " << s.description << "\n";
    }
    if (run_accuracy) {
        md << "\n## Equal time and time to error\n\n"
           << "Baseline: plain cdf. Trimmed RMSE (mean over seeds) interpolated log-log at the time cdf takes for its highest spp; "
              "time for each sampler to reach cdf's error there (modelled as above); outside the measured range the "
              "curves go on at the Monte Carlo rate. Rel. MSE also shows bias: a biased sampler stalls above the others. "
              "Charts: mean trimmed RMSE with one standard deviation over seeds, against spp and against modelled frame time.\n\n"
           << eq.str() << "\n";
        for (const NamedScene& sc : scenes)
            for (const NamedSky& sky : skies)
                md << "![" << sc.name << " " << sky.name << "](rmse_" << sc.name << "_" << sky.name << ".png)\n";
    }
    if (run_rebuild)
        md << "\n## Per-frame rebuild\n\nMedian of repeated rebuilds (EnvLight::set_sky: weights + sampler tables) of a clear sky, "
              "beside the streaming floor (one parallel pass reading the RGB image and writing one float per pixel) "
              "measured interleaved in the same run.\n\n"
           << rb.str() << "\n![rebuild](rebuild.png)\n\n"
           << "Cost of one call at N = 1024, one thread (EnvLight::sample with the sky chosen, EnvLight::pdf of sampled directions; "
              "both include the fisheye mapping and the pdf lookup):\n\n| sampler | sample() ns | pdf() ns |\n|---|---|---|\n"
           << per_call.str() << "\n";
    if (run_failures)
        md << "## Failure cases\n\n"
           << failure_scene << " scene, " << w << "x" << h << ", 128x128 skies; reference " << ref_spp << " spp with "
           << kReferenceSampler
           << ". Errors over the pixels where the camera sees the scene (those that see the "
              "sky directly are the same for every sky sampler, and one that sees the 1e6 sun held 96-99.5 % of "
              "every sampler's error). Firefly share: fraction of the squared error held by the brightest 0.1% of "
              "those pixels.\n\n"
           << fl.str() << "\n![failures](failures.png)\n\n";
    if (!notes.empty()) md << "## Notes\n\n" << notes << "\n";
    write_file_atomic((out / "README.md").string(), md.str());
    if (!reports_silenced())
        std::fprintf(stderr, "wrote %s (%.0f s)\n", (out / "README.md").c_str(), seconds_since(start));
    if (charts_failed) {
        // The tables stand; the run is not done until its charts are (a full disk, no matplotlib).
        throw_file_error(out.string(), "the charts were not written: python3 " + script + " failed (exit " +
                                           std::to_string(charts.exit_code) + ": " +
                                           child_failure_reason(charts, chart_output) +
                                           "). The tables and CSV files are complete; run the command again to "
                                           "make the charts (measurements are kept in its cache)");
    }
    return 0;
}

}  // namespace dynsky
