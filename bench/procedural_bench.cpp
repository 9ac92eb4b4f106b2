// Time to render one procedural cloudy-sky frame (with and without its flow field).
#include <benchmark/benchmark.h>

#include "bench/bench_main.h"
#include <tbb/global_control.h>

#include "sky/fisheye.h"
#include "sky/procedural_clouds.h"

namespace dynsky {
namespace {

ProceduralSkyParams bench_params(bool cirrus) {
    ProceduralSkyParams p;
    p.seed = 1;
    p.coverage = 0.4;
    p.clear_sky.sun_direction = fisheye::direction_from_angles(45.0 * kPiD / 180.0, 180.0 * kPiD / 180.0);
    if (cirrus) p.layers.push_back(cirrus_layer());
    return p;
}

// One frame of a sequence: the clear sky is cached by ProceduralSky (as in `dynsky sky
// procedural`), so this is the cloud work per frame. Arg: resolution; second arg: 1 = add cirrus.
void BM_ProceduralFrame(benchmark::State& state) {
    const int n = int(state.range(0));
    ProceduralSky sky(bench_params(state.range(1) != 0));
    sky.render(0.0, n);  // builds the cached clear sky
    double t = 0.0;
    for (auto _ : state) {
        SkyImage frame = sky.render(t += 10.0, n);
        benchmark::DoNotOptimize(frame.rgb.data());
    }
    state.counters["Mpix/s"] = benchmark::Counter(double(n) * n * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_ProceduralFrame)->ArgsProduct({{512, 1024, 2048}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime();

// The same on one thread: its CPU time is the work per frame, and reads the same on a busy machine.
void BM_ProceduralFrameOneThread(benchmark::State& state) {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    const int n = int(state.range(0));
    ProceduralSky sky(bench_params(state.range(1) != 0));
    sky.render(0.0, n);
    double t = 0.0;
    for (auto _ : state) {
        SkyImage frame = sky.render(t += 10.0, n);
        benchmark::DoNotOptimize(frame.rgb.data());
    }
    state.counters["ns/pixel"] = benchmark::Counter(double(n) * n, benchmark::Counter::kIsIterationInvariantRate |
                                                                       benchmark::Counter::kInvert);
}
BENCHMARK(BM_ProceduralFrameOneThread)->ArgsProduct({{512, 1024, 2048}, {0, 1}})->Unit(benchmark::kMillisecond);

void BM_ProceduralFrameWithFlow(benchmark::State& state) {
    const int n = int(state.range(0));
    ProceduralSky sky(bench_params(false));
    sky.render(0.0, n);
    double t = 0.0;
    Image flow;
    for (auto _ : state) {
        SkyImage frame = sky.render(t += 10.0, n, &flow, 10.0);
        benchmark::DoNotOptimize(frame.rgb.data());
        benchmark::DoNotOptimize(flow.pixels.data());
    }
}
BENCHMARK(BM_ProceduralFrameWithFlow)->Arg(512)->Arg(1024)->Arg(2048)->Unit(benchmark::kMillisecond)->UseRealTime();

// A single call of the free function, clear sky included (what one-off users pay).
void BM_RenderProceduralSkyCold(benchmark::State& state) {
    const int n = int(state.range(0));
    ProceduralSkyParams p = bench_params(false);
    for (auto _ : state) {
        SkyImage frame = render_procedural_sky(p, 10.0, n);
        benchmark::DoNotOptimize(frame.rgb.data());
    }
}
BENCHMARK(BM_RenderProceduralSkyCold)->Arg(512)->Arg(1024)->Arg(2048)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace dynsky

int main(int argc, char** argv) { return dynsky::bench::run_benchmarks(argc, argv); }
