// Sky samplers: per-frame rebuild (EnvLight::set_sky) beside the streaming floor, memory, and the
// cost of one sample() and one pdf() call. Wall and CPU time are both reported (the machine is
// shared); the ratio to the floor is measured in the same iterations.
#include <benchmark/benchmark.h>

#include "bench/bench_main.h"
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <chrono>

#include "renderer/env_light.h"
#include "renderer/streaming_floor.h"
#include "renderer/sampling.h"
#include "sky/clear_sky.h"
#include "sky/fisheye.h"

namespace dynsky {
namespace {

using Clock = std::chrono::steady_clock;

std::shared_ptr<SkyImage> bench_sky(int n) {
    static std::map<int, std::shared_ptr<SkyImage>> cache;
    auto& s = cache[n];
    if (!s) {
        ClearSkyParams p;
        p.sun_direction = fisheye::direction_from_angles(55 * kPiD / 180, 200 * kPiD / 180);
        s = std::make_shared<SkyImage>(make_clear_sky(p, n));
    }
    return s;
}

const char* kNames[] = {"cdf",     "alias",         "mip",     "sun+cdf",   "sun+alias",
                        "sun+mip", "sun+alias+mis", "mip+mis", "alias+mis", "cdf+mis"};

// Args: sampler index, N, threads (0: all).
void BM_Rebuild(benchmark::State& state) {
    const std::string name = kNames[state.range(0)];
    const int n = int(state.range(1)), threads = int(state.range(2));
    std::unique_ptr<tbb::global_control> gc;
    if (threads > 0) gc = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
    auto sky = bench_sky(n);
    EnvLight light(sky, 0.3f, parse_sky_sampler(name));
    light.set_sky(sky);  // steady state: the first two frames allocate the buffers a frame reuses
    std::vector<float> scratch;
    double rebuild = 0, floor = 0;
    for (auto _ : state) {
        auto t = Clock::now();
        light.set_sky(sky);
        double r = std::chrono::duration<double>(Clock::now() - t).count();
        state.SetIterationTime(r);
        rebuild += r;
        floor += time_streaming_floor(*sky, &scratch);
    }
    state.SetLabel(name + (threads ? " 1 thread" : " all threads"));
    state.counters["floor_ms"] = 1e3 * floor / double(state.iterations());
    state.counters["ratio_to_floor"] = rebuild / floor;
    state.counters["memory_MiB"] = light.memory_bytes() / 1048576.0;
}

void rebuild_args(benchmark::internal::Benchmark* b) {
    for (int s = 0; s < int(std::size(kNames)); ++s)
        for (int n : {256, 512, 1024, 2048, 4096})
            for (int t : {1, 0}) b->Args({s, n, t});
}
BENCHMARK(BM_Rebuild)->Apply(rebuild_args)->UseManualTime()->Unit(benchmark::kMillisecond);

// Per-call cost of sample() and pdf() (1024 px sky), random uniforms precomputed.
void BM_SampleAndPdf(benchmark::State& state) {
    const std::string name = state.range(0) < 0 ? "uniform" : kNames[state.range(0)];
    EnvLight light(bench_sky(1024), 0.0f, parse_sky_sampler(name));
    Rng rng(1, 2);
    std::vector<Vec2> us(4096);
    for (auto& u : us) u = rng.uniform2();
    const bool pdf_only = state.range(1) != 0;
    std::vector<Vec3> dirs;
    for (const Vec2& u : us) {
        EnvLightSample s;
        if (light.sample(0.5f, u, &s)) dirs.push_back(s.wi);
    }
    size_t k = 0;
    float acc = 0;
    for (auto _ : state) {
        if (pdf_only) {
            acc += light.pdf(dirs[k++ % dirs.size()]);
        } else {
            EnvLightSample s;
            light.sample(0.5f, us[k++ % us.size()], &s);
            acc += s.pdf;
        }
    }
    benchmark::DoNotOptimize(acc);
    state.SetLabel(name + (pdf_only ? " pdf" : " sample"));
}
void call_args(benchmark::internal::Benchmark* b) {
    for (int s = -1; s < int(std::size(kNames)); ++s)
        for (int p : {0, 1}) b->Args({s, p});
}
BENCHMARK(BM_SampleAndPdf)->Apply(call_args);

}  // namespace
}  // namespace dynsky

int main(int argc, char** argv) { return dynsky::bench::run_benchmarks(argc, argv); }
