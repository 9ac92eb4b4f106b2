// CPU time of the cloud model (motion/cloud_model.h, OpenCV dnn) per medium step, against the
// Farneback-extrapolation baseline at the same size, and the sky-level step at 512 px (resampling,
// detail advection, HDR maps and sun re-insertion included).
//
//   build-nets/bench/cloud_model_bench                    (shipped model: networks/models/arm_tsi)
//   DYNSKY_CLOUD_MODEL=DIR build-nets/bench/cloud_model_bench
#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>

#include <cstdlib>

#include "motion/cloud_model.h"
#include "sky/fisheye.h"
#include "sky/procedural_clouds.h"
#include "motion/advection.h"
#include "motion/metrics.h"
#include "util/data_path.h"

namespace dynsky {
namespace {

CloudModel& model() {
    static CloudModel m = [] {
        const char* env = std::getenv("DYNSKY_CLOUD_MODEL");
        return CloudModel::load(env && *env ? std::string(env) : data_path("networks/models/arm_tsi"));
    }();
    return m;
}

SkyImage test_sky(int n) {
    ProceduralSkyParams p;
    p.seed = 3;
    p.coverage = 0.5;
    p.clear_sky.sun_direction = fisheye::direction_from_angles(0.7, 2.5);
    return render_procedural_sky(p, 0.0, n);
}

void BM_NetworkStep(benchmark::State& state) {
    cv::setNumThreads(int(state.range(0)));
    const int n = model().info().resolution;
    cv::Mat image = to_network_form(test_sky(n), model().info().form);
    for (auto _ : state) benchmark::DoNotOptimize(model().step_network(image).next.data);
    state.counters["resolution"] = n;
}
BENCHMARK(BM_NetworkStep)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_FlowNetOnly(benchmark::State& state) {
    cv::setNumThreads(1);
    const int n = model().info().resolution;
    cv::Mat image = to_network_form(test_sky(n), model().info().form);
    for (auto _ : state) benchmark::DoNotOptimize(model().run_flownet(image).data);
}
BENCHMARK(BM_FlowNetOnly)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_FarnebackExtrapolation(benchmark::State& state) {
    cv::setNumThreads(1);
    const int n = int(state.range(0));
    ProceduralSkyParams p;
    p.seed = 3;
    p.coverage = 0.5;
    p.clear_sky.sun_direction = fisheye::direction_from_angles(0.7, 2.5);
    ProceduralSky sky(p);
    cv::Mat i0 = to_network_form(sky.render(0.0, n), model().info().form);
    cv::Mat i1 = to_network_form(sky.render(30.0, n), model().info().form);
    for (auto _ : state) benchmark::DoNotOptimize(extrapolate_farneback(i0, i1, 1).data);
}
BENCHMARK(BM_FarnebackExtrapolation)->Arg(64)->Arg(128)->Arg(256)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_SkyStep512(benchmark::State& state) {
    cv::setNumThreads(1);
    SkyImage sky = test_sky(512);
    for (auto _ : state) benchmark::DoNotOptimize(model().step(sky).rgb.data());
}
BENCHMARK(BM_SkyStep512)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace dynsky

BENCHMARK_MAIN();
