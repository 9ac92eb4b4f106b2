// libFuzzer target: the photograph import of `dynsky sky import PHOTO --preset arm-tsi`
// (sky/preset_import.h import_preset_photo: decoding, sky circle, obstruction detection, resampling,
// inpainting and the HDR calibration against the clear sky, the time taken from the file name).
// Seeds: small crops and reductions of ../shared's all-sky JPEGs.
#include "fuzz/fuzz_support.h"
#include "sky/preset_import.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    dynsky::fuzz::init_single_threaded();
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    // A TSI file name: the preset reads the photograph's time from it.
    const std::string path = dynsky::fuzz::write_input(data, size, "tsi_sgpC1_20170524164530Z.jpg");
    if (dynsky::fuzz::header_values(path) > dynsky::fuzz::kMaxFuzzImageValues) return 0;
    dynsky::fuzz::expect_clean_refusal([&] { (void)dynsky::import_preset_photo(path, "arm-tsi", 64); });
    return 0;
}
