#include "util/image_input.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "tests/test_support.h"
#include "util/error.h"
#include "util/image.h"

namespace dynsky {
namespace {

std::string file_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// An APP13 segment as Photoshop writes one, holding one IPTC record (a caption) whose declared
// length runs 0x7F00 bytes past the segment: what OpenImageIO 2.4 copied from beyond the buffer.
std::string hostile_app13() {
    std::string payload = std::string("Photoshop 3.0") + '\0' + "8BIM" + "\x04\x04" + std::string(2, '\0') +
                          std::string("\0\0\0\x10", 4) + "\x1C\x02\x78\x7F\x00" + "caption";
    const size_t length = payload.size() + 2;
    return std::string("\xFF\xED") + char(length >> 8) + char(length & 0xFF) + payload;
}

// A JPEG written by OpenImageIO with an EXIF capture time, as cameras write them.
std::string write_jpeg_with_time(const std::string& path, const Image& image) {
    auto out = OIIO::ImageOutput::create(path);
    OIIO::ImageSpec spec(image.width, image.height, image.channels, OIIO::TypeDesc::UINT8);
    spec.attribute("Exif:DateTimeOriginal", "2017:05:24 16:45:30");
    EXPECT_TRUE(out->open(path, spec));
    EXPECT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data()));
    out->close();
    return file_bytes(path);
}

TEST(ImageFileInput, JpegsReachTheDecoderWithoutTheirApp13Segments) {
    const std::string dir = test::temp_dir("image_input");
    Image image(24, 16, 3);
    for (size_t k = 0; k < image.pixels.size(); ++k) image.pixels[k] = float(k % 31) / 31.0f;
    const std::string plain = write_jpeg_with_time(dir + "/plain.jpg", image);
    ASSERT_GT(plain.size(), 4u);
    // The hostile segment right after the start-of-image marker, and again after a stray byte.
    const std::string app13 = hostile_app13();
    const std::string hostile = plain.substr(0, 2) + app13 + "\x00" + app13 + plain.substr(2);
    std::ofstream(dir + "/hostile.jpg", std::ios::binary) << hostile;

    // Exactly the two segments go; the stray byte and everything else stay, byte for byte.
    const std::vector<unsigned char> in(hostile.begin(), hostile.end());
    const std::vector<unsigned char> kept = jpeg_without_app13(in);
    EXPECT_EQ(std::string(kept.begin(), kept.end()), plain.substr(0, 2) + "\x00" + plain.substr(2));
    // Not a JPEG: unchanged.
    const std::vector<unsigned char> other = {'G', 'I', 'F', '8', '9', 'a', 0xFF, 0xED, 0, 4, 1, 2};
    EXPECT_EQ(jpeg_without_app13(other), other);

    // Read as the camera's own file: same pixels, and the capture time still found in its EXIF.
    // (Under ASan, scripts/test_sanitizers.sh, reading it before the change overflowed the heap.)
    const Image a = read_image(dir + "/plain.jpg"), b = read_image(dir + "/hostile.jpg");
    EXPECT_EQ(a.pixels, b.pixels);
    EXPECT_EQ(image_header_strings(dir + "/hostile.jpg", {"Exif:DateTimeOriginal"}).at(0), "2017:05:24 16:45:30");
    // By content, whatever the name says.
    std::ofstream(dir + "/named.exr", std::ios::binary) << hostile;
    EXPECT_EQ(read_image(dir + "/named.exr").pixels, a.pixels);
    // The fuzzer's file: read or refused with its name, never past a buffer.
    const std::string finding = std::string(DYNSKY_SOURCE_DIR) + "/fuzz/regressions/sky_image/jpeg-exif-past-app1";
    try {
        (void)read_image(finding);
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("jpeg-exif-past-app1"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace dynsky
