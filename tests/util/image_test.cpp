#include "util/image.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "tests/test_support.h"
#include "util/error.h"

namespace dynsky {
namespace {

namespace fs = std::filesystem;

TEST(ImageIo, ExrRoundTripKeepsPixelsAndMetadata) {
    std::string dir = test::temp_dir("image");
    Image image(5, 3, 3);
    for (size_t k = 0; k < image.pixels.size(); ++k) image.pixels[k] = 0.001f * k * k + 1e-4f;
    image.metadata.numbers["dynsky:time"] = 1234.5678901234;
    image.metadata.strings["dynsky:source"] = "test";
    std::string path = dir + "/a.exr";
    write_image(path, image);
    Image back = read_image(path);
    ASSERT_EQ(back.width, 5);
    ASSERT_EQ(back.height, 3);
    ASSERT_EQ(back.channels, 3);
    for (size_t k = 0; k < image.pixels.size(); ++k) EXPECT_FLOAT_EQ(back.pixels[k], image.pixels[k]);
    EXPECT_DOUBLE_EQ(back.metadata.numbers["dynsky:time"], 1234.5678901234);
    EXPECT_EQ(back.metadata.strings["dynsky:source"], "test");
    // No temporary files left behind.
    int files = 0;
    for (auto& e : fs::directory_iterator(dir)) files += e.is_regular_file();
    EXPECT_EQ(files, 1);
}

TEST(ImageIo, MissingAndBogusFilesNameTheFile) {
    std::string dir = test::temp_dir("image");
    try {
        read_image(dir + "/nope.exr");
        FAIL() << "expected an error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("nope.exr"), std::string::npos);
    }
    std::string bogus = dir + "/text.exr";
    std::ofstream(bogus) << "this is not an image";
    EXPECT_THROW(read_image(bogus), Error);
}

TEST(ImageIo, UnsupportedExtensionWritesNothing) {
    std::string dir = test::temp_dir("image");
    Image image(2, 2, 3);
    EXPECT_THROW(write_image(dir + "/x.bmpx", image), Error);
    EXPECT_TRUE(fs::is_empty(dir));
}

}  // namespace
}  // namespace dynsky
