// libFuzzer target: the glTF loader (renderer/gltf_loader.h) on one file, GLB or JSON glTF.
// Seeds: the GLB and embedded glTF scenes of ../shared/scenes (scripts/fuzz.sh).
#include "fuzz/fuzz_support.h"
#include "renderer/gltf_loader.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    dynsky::fuzz::init_single_threaded();
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = dynsky::fuzz::write_input(data, size, "scene.glb");
    dynsky::fuzz::expect_clean_refusal([&] {
        // Posed at 0.5 s: files without animations load as at rest, animated ones run the sampling.
        dynsky::Scene scene = dynsky::load_gltf(path, nullptr, 0.5);
        (void)scene.triangle_count();
    });
    return 0;
}
