// Per-frame cost of an animation, split: sky (Gamma's blend and sun insertion every frame, plus the
// medium step xi, flow estimate and key images amortised over the Delta t * fps frames of its
// interval), sky distribution rebuild (EnvLight::set_sky), and rendering. For 1024 and 2048 skies
// at `dynsky animate`'s defaults (480x270, 16 spp, 12 fps, Delta t 10 s, flow-extrapolation model,
// scenes/tower). Goal: sky work (sky + rebuild) under 5% of a frame.
// Run: build-NAME/bench/animation_bench  (counters in ms; sky_pct = (sky + rebuild) / frame).
#include <benchmark/benchmark.h>

#include "bench/bench_main.h"

#include <chrono>
#include <filesystem>

#include "renderer/builtin_scene.h"
#include "renderer/gltf_loader.h"
#include "renderer/integrator.h"
#include "sky/procedural_clouds.h"
#include "motion/sky_timeline.h"
#include "motion/flow_extrapolation_model.h"
#include "motion/network_step_model.h"
#include "motion/procedural_step_model.h"

namespace dynsky {
namespace {

double now_s() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

SkyImage cloudy_input(int n) {
    ProceduralSkyParams p;
    p.coverage = 0.5;
    p.clear_sky.sun_direction = Vec3d(0.4, 0.7, 0.3).normalized();
    return render_procedural_sky(p, 0.0, n);
}

Scene bench_scene() {
    std::string tower = std::string(DYNSKY_SOURCE_DIR) + "/scenes/tower/tower.gltf";
    return std::filesystem::exists(tower) ? load_gltf(tower) : make_builtin_scene();
}

void BM_AnimationFrameSplit(benchmark::State& state) {
    const int n = int(state.range(0));
    const double fps = 12, dt = 10;
    static Scene scene = bench_scene();
    static Accel accel(scene);
    Camera camera = scene.cameras.empty() ? frame_bounds_camera(scene.world_bounds(), 16.0f / 9) : scene.cameras[0];
    SkyTimeline timeline(cloudy_input(n), std::make_unique<FlowExtrapolationStepModel>(), dt);
    // The medium work of one interval: xi (step 1) and the flow + key images of interval 0.
    double t0 = now_s();
    timeline.step(1);
    timeline.key_third(0);
    const double medium_s = now_s() - t0;
    EnvLight light(0.3f);
    double sky_s = 0, build_s = 0, render_s = 0;
    int frames = 0;
    std::shared_ptr<SkyImage> buffers[2] = {std::make_shared<SkyImage>(), std::make_shared<SkyImage>()};
    for (auto _ : state) {
        double t = (1 + frames % 118) / fps;  // frames inside interval 0 (not on a step)
        double a = now_s();
        std::shared_ptr<SkyImage>& buffer = buffers[frames % 2];  // as dynsky animate does
        timeline.sky_at(t, buffer.get());
        double b = now_s();
        light.set_sky(buffer);
        double c = now_s();
        RenderSettings s;
        s.width = 480, s.height = 270, s.spp = 16, s.quiet = true;
        PathIntegrator integrator(accel, light, s);
        RenderResult r = integrator.render(camera);
        double d = now_s();
        benchmark::DoNotOptimize(r.color.pixels.data());
        sky_s += b - a, build_s += c - b, render_s += d - c, ++frames;
    }
    const double amortised = medium_s / (dt * fps);
    const double sky_ms = (sky_s / frames + amortised) * 1e3, build_ms = build_s / frames * 1e3,
                 render_ms = render_s / frames * 1e3;
    state.counters["gamma_ms"] = sky_s / frames * 1e3;
    state.counters["xi_flow_keys_ms_per_interval"] = medium_s * 1e3;
    state.counters["sky_ms"] = sky_ms;  // Gamma + amortised medium work
    state.counters["rebuild_ms"] = build_ms;
    state.counters["render_ms"] = render_ms;
    state.counters["sky_pct"] = 100.0 * (sky_ms + build_ms) / (sky_ms + build_ms + render_ms);
}
BENCHMARK(BM_AnimationFrameSplit)->Arg(1024)->Arg(2048)->Iterations(4)->Unit(benchmark::kMillisecond)->UseRealTime();

// Sky-only pieces, many iterations: Gamma's per-frame blend and the distribution rebuild.
void BM_GammaFrame(benchmark::State& state) {
    const int n = int(state.range(0));
    SkyTimeline timeline(cloudy_input(n), std::make_unique<FlowExtrapolationStepModel>(), 10.0);
    timeline.key_third(0);
    int k = 0;
    SkyImage s;
    for (auto _ : state) {
        timeline.sky_at(0.5 + 0.01 * (k++ % 900), &s);
        benchmark::DoNotOptimize(s.rgb.data());
    }
}
BENCHMARK(BM_GammaFrame)->Arg(1024)->Arg(2048)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_MediumInterval(benchmark::State& state) {
    const int n = int(state.range(0));
    SkyImage input = cloudy_input(n);
    for (auto _ : state) {
        SkyTimeline timeline(input, std::make_unique<FlowExtrapolationStepModel>(), 10.0);
        timeline.key_third(0);  // xi + Farneback + two great-arc advections
    }
}
BENCHMARK(BM_MediumInterval)->Arg(1024)->Arg(2048)->Iterations(3)->Unit(benchmark::kMillisecond)->UseRealTime();

// A played scene animation (animate --play-anim): each frame's scene as it was made before (the
// file loaded at the frame's time: read, buffers and textures decoded) against posing one load
// (AnimatedGltf::pose: only the nodes and what hangs on them), both with the frame's BVH. The
// CesiumMilkTruck (an animation, a 2048 px texture) from ../shared when it is there.
// Counter pose_over_load: the posed frame's time over the loaded one's.
void BM_PlayedAnimationScene(benchmark::State& state) {
    const std::string truck = std::string(DYNSKY_SOURCE_DIR) + "/../shared/scenes/CesiumMilkTruck/CesiumMilkTruck.glb";
    if (!std::filesystem::exists(truck)) {
        state.SkipWithError("../shared/scenes/CesiumMilkTruck not found");
        return;
    }
    AnimatedGltf animated(truck);
    double load_s = 0, pose_s = 0;
    int frames = 0;
    for (auto _ : state) {
        const double t = 0.1 * (frames % 40);
        double a = now_s();
        {
            Scene s = load_gltf(truck, nullptr, t);
            Accel accel(s);
            benchmark::DoNotOptimize(&accel);
        }
        double b = now_s();
        {
            Scene s = animated.pose(t);
            Accel accel(s);
            benchmark::DoNotOptimize(&accel);
        }
        double c = now_s();
        load_s += b - a, pose_s += c - b, ++frames;
    }
    state.counters["load_ms"] = load_s / frames * 1e3;
    state.counters["pose_ms"] = pose_s / frames * 1e3;
    state.counters["pose_over_load"] = pose_s / load_s;
}
BENCHMARK(BM_PlayedAnimationScene)->Iterations(10)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace dynsky

int main(int argc, char** argv) { return dynsky::bench::run_benchmarks(argc, argv); }
