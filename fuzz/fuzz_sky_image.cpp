// libFuzzer target: the sky image loader (sky/sky_image.h load_sky): OpenImageIO's read path for
// EXR, PNG and JPEG (util/image.h read_image) and the sky checks. Seeds: small sky EXRs (half and
// float) made from ../shared photographs, and PNG/JPEG crops, which must be refused cleanly.
#include "fuzz/fuzz_support.h"
#include "sky/sky_image.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    dynsky::fuzz::init_single_threaded();
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = dynsky::fuzz::write_input(data, size, "sky.exr");
    if (dynsky::fuzz::header_values(path) > dynsky::fuzz::kMaxFuzzImageValues) return 0;
    dynsky::fuzz::expect_clean_refusal([&] { (void)dynsky::load_sky(path); });
    return 0;
}
