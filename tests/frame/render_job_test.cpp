#include "frame/render_job.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "tests/test_support.h"
#include "util/error.h"
#include "util/image.h"

namespace dynsky {
namespace {

namespace fs = std::filesystem;

// The job `dynsky render` runs, without the program: the EXR and its PNG, with the settings that
// made them in the header; a sky made here at a place; a bad job writes nothing.
TEST(RenderJob, WritesTheImagePairWithItsSettings) {
    const std::string dir = test::temp_dir("render_job");
    RenderJob job;
    job.out = dir + "/plaza.exr", job.resolution = "24x16", job.spp = 2, job.quiet = true;
    job.generated.sky_resolution = 32;
    run_render_job(job);
    ASSERT_TRUE(fs::exists(dir + "/plaza.png"));
    const Image image = read_image(dir + "/plaza.exr");
    EXPECT_EQ(image.width, 24);
    EXPECT_EQ(image.metadata.numbers.at("dynsky:spp"), 2);
    EXPECT_NE(image.metadata.strings.at("dynsky:sky").find("builtin: clear sky"), std::string::npos);
    float sum = 0;
    for (float v : image.pixels) sum += v;
    EXPECT_GT(sum, 0.0f);

    // A sky made here at another place and time, every surface Lambertian: said in the header.
    job.out = dir + "/placed.exr", job.sky = "clear", job.generated.time = "2026-03-20T12:00:00Z";
    job.generated.latitude = 0, job.override_material = "lambert";
    run_render_job(job);
    const Image placed = read_image(dir + "/placed.exr");
    EXPECT_EQ(placed.metadata.strings.at("dynsky:override_material"), "lambert");
    EXPECT_EQ(placed.metadata.strings.at("dynsky:sky").find("builtin"), std::string::npos);

    // Refused before a pixel is traced: nothing written.
    job.out = dir + "/bad.tiff";
    EXPECT_THROW(run_render_job(job), Error);
    job.out = dir + "/bad.png", job.aovs = "albedo";
    EXPECT_THROW(run_render_job(job), Error);
    EXPECT_FALSE(fs::exists(dir + "/bad.tiff"));
    EXPECT_FALSE(fs::exists(dir + "/bad.png"));
    fs::remove_all(dir);
}

}  // namespace
}  // namespace dynsky
