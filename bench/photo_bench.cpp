// Importing one real all-sky photograph into the canonical fisheye at 512, 1024 and 2048 pixels:
//  - Import/<camera>/N: the whole geometric import (read the JPEG and the camera's mask, remap,
//    inpaint the masked pixels), as `dynsky sky import --hdr none` does it;
//  - ImportHdr/<camera>/N: the same plus the HDR recovery (clear-sky calibration, sun restored),
//    as `dynsky sky import --preset P` does by default.
// Photographs come from ../shared/skies (DYNSKY_SHARED_DIR); without them the benchmarks skip.
#include <benchmark/benchmark.h>

#include "bench/bench_main.h"

#include <filesystem>

#include "sky/hdr_recovery.h"
#include "sky/photo_import.h"
#include "util/cpu_time.h"

namespace dynsky {
namespace {

struct Camera {
    const char* preset;
    const char* photo;  // relative to DYNSKY_SHARED_DIR
};
const Camera kCameras[] = {
    {"arm-tsi", "skies/arm_tsi_sgp_20170524/images/tsi_sgpC1_20170524170000Z.jpg"},    // 480 x 640
    {"mobotix", "skies/mobotix_sophia_20200812_morning/images/2020-08-12_12_00.jpg"},  // 1280 x 960
};

void import_bench(benchmark::State& state, const Camera& cam, bool hdr) {
    std::string path = std::string(DYNSKY_SHARED_DIR) + "/" + cam.photo;
    if (!std::filesystem::exists(path)) {
        state.SkipWithError(("missing " + path).c_str());
        return;
    }
    CameraPreset preset = camera_preset(cam.preset);
    PhotoImportParams params = preset.params;
    params.resolution = int(state.range(0));
    params.mask_path = find_preset_mask(cam.preset, path);
    HdrCalibrationParams hp;
    hp.time = parse_utc_time(time_from_file_name(path, preset.filename_utc_offset_hours));
    hp.location = {preset.latitude_deg, preset.longitude_deg, preset.elevation_m};
    hp.sun_search_deg = preset.sun_search_deg;
    hp.camera_colour = preset.colour;
    double cpu0 = process_cpu_seconds();
    for (auto _ : state) {
        ImportedPhoto imp = import_photo(path, params);
        if (hdr) {
            SkyImage sky = recover_hdr(imp, hp);
            benchmark::DoNotOptimize(sky.rgb.data());
        }
        benchmark::DoNotOptimize(imp.sky.rgb.data());
    }
    // CPU seconds of all threads per import: what the work costs, whatever else shares the machine.
    state.counters["cpu_s_all_threads"] = (process_cpu_seconds() - cpu0) / double(state.iterations());
    state.counters["out_Mpix"] = double(params.resolution) * params.resolution / 1e6;
}

void register_all() {
    for (const Camera& cam : kCameras)
        for (bool hdr : {false, true}) {
            std::string name = std::string(hdr ? "ImportHdr/" : "Import/") + cam.preset;
            benchmark::RegisterBenchmark(name.c_str(), [cam, hdr](benchmark::State& s) { import_bench(s, cam, hdr); })
                ->Arg(512)
                ->Arg(1024)
                ->Arg(2048)
                ->Unit(benchmark::kMillisecond)
                ->UseRealTime();
        }
}

}  // namespace
}  // namespace dynsky

int main(int argc, char** argv) {
    dynsky::register_all();
    return dynsky::bench::run_benchmarks(argc, argv);
}
