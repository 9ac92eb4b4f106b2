// CPU time of the cloud model (motion/cloud_model.h, OpenCV dnn) per medium step, against the
// Farneback-extrapolation baseline at the same size, and the sky-level step at 512 px (resampling,
// detail advection, HDR maps and sun re-insertion included).
//
//   build-nets/bench/cloud_model_bench                    (shipped model: networks/models/arm_tsi)
//   DYNSKY_CLOUD_MODEL=DIR build-nets/bench/cloud_model_bench
#include <benchmark/benchmark.h>

#include "bench/bench_main.h"

#include <cstdio>
#include <opencv2/core.hpp>

#include <tbb/global_control.h>

#include <cstdlib>
#include <memory>

#include "motion/advect_residual.h"
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

// The default model (advect-residual, networks/models/advect_residual): one medium step of a whole
// sky as the timeline runs it (the HDR maps, warp at the sky's resolution with the background
// compensation, the network at 64 px and its correction, the sun put back), with the motion already
// measured (it is fixed after the first step). Goal: 1024 px in at most 250 ms on 2 cores.
AdvectResidualNetwork& advect_model() {
    static AdvectResidualNetwork m = [] {
        const char* env = std::getenv("DYNSKY_ADVECT_MODEL");
        return AdvectResidualNetwork::load(env && *env ? std::string(env)
                                                       : data_path("networks/models/advect_residual"));
    }();
    return m;
}

void BM_AdvectResidualSkyStep(benchmark::State& state) {
    const int n = int(state.range(0));
    cv::setNumThreads(int(state.range(1)));
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, size_t(state.range(1)));
    SkyImage sky = test_sky(n);
    CloudMotion motion;
    motion.wind = Wind{250, 10, 1500};
    AdvectResidualStepModel model(advect_model(), motion);
    std::vector<std::shared_ptr<const SkyImage>> history{std::make_shared<const SkyImage>(sky)};
    history.push_back(std::make_shared<const SkyImage>(model.step(history, 30.0)));  // measures the motion once
    for (auto _ : state) {
        SkyImage next = model.step(history, 30.0);  // the timeline's steady state: one step more each call
        benchmark::DoNotOptimize(next.rgb.data());
        history.push_back(std::make_shared<const SkyImage>(std::move(next)));
    }
    state.counters["resolution"] = n;
    state.counters["threads"] = double(state.range(1));
}
BENCHMARK(BM_AdvectResidualSkyStep)
    ->Args({256, 2})
    ->Args({512, 2})
    ->Args({1024, 1})
    ->Args({1024, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The motion from a previous frame (Farneback at 256 on the network form, smoothed), once per run.
void BM_MotionFromPreviousFrame1024(benchmark::State& state) {
    cv::setNumThreads(2);
    ProceduralSkyParams p;
    p.seed = 3;
    p.coverage = 0.5;
    p.clear_sky.sun_direction = fisheye::direction_from_angles(0.7, 2.5);
    ProceduralSky sky(p);
    SkyImage a = sky.render(0.0, 1024), b = sky.render(30.0, 1024);
    for (auto _ : state)
        benchmark::DoNotOptimize(network_form_flow(a, b, advect_model().info().form, 1024).confirmed.data);
}
BENCHMARK(BM_MotionFromPreviousFrame1024)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace dynsky

// The models are loaded before any benchmark runs: one that cannot be (a DYNSKY_*_MODEL naming no
// model folder) threw inside a benchmark, aborted the program and left --benchmark_out cut short.
int main(int argc, char** argv) {
    try {
        dynsky::model();
        dynsky::advect_model();
    } catch (const std::exception& e) {
        std::fprintf(stderr, "cloud_model_bench: %s\n", e.what());
        return 1;
    }
    return dynsky::bench::run_benchmarks(argc, argv);
}
