// Renderer benchmarks. Each reports its ratio against a baseline measured in the same run:
//  - PathTracerVsEmbree: rays/s of the path tracer at 1280x720 beside rays/s of plain Embree
//    traversal of the very same rays (recorded, then replayed), each traced as well as the path
//    tracer traces it: camera rays as coherent streams in the path tracer's batches (a tile's
//    pixels), the rest one by one. Goal: ratio >= 0.5. (The replay once traced camera rays one by
//    one too, a baseline 15-30 % slower than the path tracer's own use of Embree.)
//  - DistributionRebuild: per-frame rebuild of the sky's sampling distribution at N x N beside
//    one streaming pass over the same bytes (read RGB, write one float per pixel). Goal at 2048:
//    ratio <= 2.
// Scenes come from ../shared/scenes (DYNSKY_SHARED_DIR); missing scenes skip their benchmark.
#include <algorithm>
#include <atomic>
#include <benchmark/benchmark.h>

#include "bench/bench_main.h"
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <filesystem>

#include "renderer/gltf_loader.h"
#include "renderer/integrator.h"
#include "renderer/streaming_floor.h"
#include "sky/clear_sky.h"
#include "sky/fisheye.h"
#include "util/cpu_time.h"

namespace dynsky {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

std::shared_ptr<SkyImage> bench_sky(int n) {
    ClearSkyParams p;
    p.sun_direction = fisheye::direction_from_angles(0.8, 3.6);
    return std::make_shared<SkyImage>(make_clear_sky(p, n));
}

void BM_DistributionRebuild(benchmark::State& state) {
    const int n = int(state.range(0));
    auto sky = bench_sky(n);
    SkySamplerOptions cdf;
    cdf.method =
        SkySamplerMethod::Cdf;  // issue 2's piecewise-constant distribution (bench/sampling_bench compares all)
    EnvLight light(sky, 0.3f, cdf);
    light.set_sky(sky);  // steady state: the first two frames allocate the buffers a frame reuses
    std::vector<float> scratch;
    double rebuild = 0, floor = 0;
    int iterations = 0;
    for (auto _ : state) {
        auto t = Clock::now();
        light.set_sky(sky);
        double r = seconds_since(t);
        state.SetIterationTime(r);
        rebuild += r;
        floor += time_streaming_floor(*sky, &scratch);
        ++iterations;
    }
    state.counters["rebuild_ms"] = 1e3 * rebuild / iterations;
    state.counters["floor_ms"] = 1e3 * floor / iterations;
    state.counters["ratio_to_floor"] = rebuild / floor;
    state.counters["memory_MiB"] = light.memory_bytes() / 1048576.0;
}
BENCHMARK(BM_DistributionRebuild)
    ->Arg(512)
    ->Arg(1024)
    ->Arg(2048)
    ->Arg(4096)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

struct RecordedRay {
    Ray ray;
    RayKind kind;
};

// The recorded rays, by how the replay traces them.
struct Replay {
    std::vector<Ray> camera;             // in the order traced, batches of `batch`
    std::vector<RecordedRay> scattered;  // continuation and shadow rays
    size_t batch = 256;
    size_t size() const { return camera.size() + scattered.size(); }
};

// Plain Embree over the recorded rays; returns the hits (kept from the optimiser).
size_t replay_with_embree(const Accel& accel, const Replay& r) {
    std::atomic<size_t> hits{0};
    const size_t batches = (r.camera.size() + r.batch - 1) / r.batch;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, batches, 16), [&](const tbb::blocked_range<size_t>& range) {
        std::vector<RTCRayHit> records(r.batch);
        size_t h = 0;
        for (size_t b = range.begin(); b != range.end(); ++b) {
            const size_t first = b * r.batch, n = std::min(r.batch, r.camera.size() - first);
            for (size_t i = 0; i < n; ++i) Accel::setup_ray_hit(r.camera[first + i], &records[i]);
            accel.intersect_coherent(records.data(), unsigned(n));
            for (size_t i = 0; i < n; ++i) h += records[i].hit.geomID != RTC_INVALID_GEOMETRY_ID;
        }
        hits += h;
    });
    tbb::parallel_for(tbb::blocked_range<size_t>(0, r.scattered.size(), 4096),
                      [&](const tbb::blocked_range<size_t>& range) {
                          size_t h = 0;
                          for (size_t i = range.begin(); i != range.end(); ++i) {
                              float tt;
                              const RecordedRay& ray = r.scattered[i];
                              if (ray.kind == RayKind::Shadow) h += accel.occluded(ray.ray);
                              else h += accel.intersect_raw(ray.ray, &tt);
                          }
                          hits += h;
                      });
    return hits.load();
}

void path_tracer_vs_embree(benchmark::State& state, const std::string& relative) {
    std::string path = std::string(DYNSKY_SHARED_DIR) + "/scenes/" + relative;
    if (!std::filesystem::exists(path)) {
        state.SkipWithError(("missing " + path).c_str());
        for (auto _ : state) {}
        return;
    }
    Scene scene = load_gltf(path);
    Accel accel(scene);
    EnvLight light(bench_sky(1024), 0.3f);
    RenderSettings s;
    s.width = 1280, s.height = 720, s.spp = int(state.range(0)), s.quiet = true;
    Camera cam = scene.cameras.empty() ? frame_bounds_camera(scene.world_bounds(), 16.0f / 9) : scene.cameras[0];

    // Record the rays of one render (untimed), then time the render and the replay.
    tbb::enumerable_thread_specific<std::vector<RecordedRay>> recorded;
    {
        PathIntegrator recorder(accel, light, s);
        recorder.set_ray_observer([&](const Ray& r, RayKind kind) { recorded.local().push_back({r, kind}); });
        recorder.render(cam);
    }
    Replay rays;
    rays.batch = size_t(s.tile_size) * s.tile_size;  // a thread's camera rays of one tile, one sample
    for (auto& part : recorded)
        for (const RecordedRay& r : part)
            if (r.kind == RayKind::Camera) rays.camera.push_back(r.ray);
            else rays.scattered.push_back(r);

    double pt_rays_per_s = 0, embree_rays_per_s = 0, pt_rays_per_cpu_s = 0, embree_rays_per_cpu_s = 0;
    // One ratio per iteration (render, then replay, back to back): on a shared machine a single
    // pair swings by +-5 %; the median of seven is what the counters report.
    std::vector<double> ratios_cpu, ratios_wall;
    for (auto _ : state) {
        PathIntegrator pt(accel, light, s);
        double cpu0 = process_cpu_seconds();
        RenderResult r = pt.render(cam);
        pt_rays_per_cpu_s = r.stats.total_rays() / (process_cpu_seconds() - cpu0);
        pt_rays_per_s = r.stats.total_rays() / r.stats.seconds;
        state.SetIterationTime(r.stats.seconds);

        double cpu1 = process_cpu_seconds();
        auto t = Clock::now();
        benchmark::DoNotOptimize(replay_with_embree(accel, rays));
        embree_rays_per_s = rays.size() / seconds_since(t);
        embree_rays_per_cpu_s = rays.size() / (process_cpu_seconds() - cpu1);
        ratios_cpu.push_back(pt_rays_per_cpu_s / embree_rays_per_cpu_s);
        ratios_wall.push_back(pt_rays_per_s / embree_rays_per_s);
    }
    auto median = [](std::vector<double> v) {
        std::sort(v.begin(), v.end());
        return v[v.size() / 2];
    };
    state.counters["path_tracer_Mrays_s"] = pt_rays_per_s * 1e-6;
    state.counters["embree_Mrays_s"] = embree_rays_per_s * 1e-6;
    state.counters["ratio_wall"] = median(ratios_wall);
    state.counters["ratio_cpu"] = median(ratios_cpu);
    state.counters["ratio_cpu_min"] = *std::min_element(ratios_cpu.begin(), ratios_cpu.end());
    state.counters["ratio_cpu_max"] = *std::max_element(ratios_cpu.begin(), ratios_cpu.end());
    state.counters["rays"] = double(rays.size());
    // What the rays are: at 1 spp most are camera rays, and most of those see the sky (the ratio then
    // weighs the sky lookup of a missed camera ray as much as a path's bounce).
    state.counters["camera_share"] = double(rays.camera.size()) / double(rays.size());
}

void BM_PathTracerVsEmbree_MetalRoughSpheres(benchmark::State& state) {
    path_tracer_vs_embree(state, "MetalRoughSpheresNoTextures/MetalRoughSpheresNoTextures.glb");
}
void BM_PathTracerVsEmbree_FlightHelmet(benchmark::State& state) {
    path_tracer_vs_embree(state, "FlightHelmet/FlightHelmet.gltf");
}
BENCHMARK(BM_PathTracerVsEmbree_MetalRoughSpheres)->Arg(1)->Iterations(7)->UseManualTime()->Unit(benchmark::kSecond);
BENCHMARK(BM_PathTracerVsEmbree_FlightHelmet)->Arg(1)->Iterations(7)->UseManualTime()->Unit(benchmark::kSecond);

}  // namespace
}  // namespace dynsky

int main(int argc, char** argv) { return dynsky::bench::run_benchmarks(argc, argv); }
