// Speed of the clear-sky path: one Hosek-Wilkie fisheye (rows in parallel with oneTBB) and its
// lat-long export. Run: build-NAME/bench/sky_bench. "Time" is wall-clock, "CPU" the whole
// process (all threads): on a loaded machine CPU / cores is the better guide.
#include <benchmark/benchmark.h>

#include "bench/bench_main.h"

#include "sky/clear_sky.h"
#include "sky/fisheye.h"
#include "sky/latlong.h"

namespace dynsky {
namespace {

ClearSkyParams afternoon() {
    ClearSkyParams p;
    p.sun_direction = fisheye::direction_from_angles(50 * kPiD / 180, 230 * kPiD / 180);
    p.turbidity = 3;
    p.ground_albedo = 0.3;
    return p;
}

void BM_MakeClearSky(benchmark::State& state) {
    const int n = int(state.range(0));
    ClearSkyParams p = afternoon();
    make_clear_sky(p, 16);  // load the tables outside the timing
    for (auto _ : state) {
        SkyImage sky = make_clear_sky(p, n);
        benchmark::DoNotOptimize(sky.rgb.data());
    }
    state.counters["Mpixel/s"] = benchmark::Counter(double(n) * n * state.iterations() / 1e6,
                                                    benchmark::Counter::kIsRate);
}
BENCHMARK(BM_MakeClearSky)
    ->Arg(512)
    ->Arg(1024)
    ->Arg(2048)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

void BM_SkyToLatLong(benchmark::State& state) {
    const int n = int(state.range(0));
    SkyImage sky = make_clear_sky(afternoon(), n);
    for (auto _ : state) {
        Image ll = sky_to_latlong(sky, 2 * n);
        benchmark::DoNotOptimize(ll.pixels.data());
    }
}
BENCHMARK(BM_SkyToLatLong)->Arg(512)->Arg(1024)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

}  // namespace
}  // namespace dynsky

int main(int argc, char** argv) { return dynsky::bench::run_benchmarks(argc, argv); }
