#include "util/image.h"

#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <filesystem>
#include <functional>
#include <limits>
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

// A display image says how it was made from the radiance (its exposure and curve), not the
// radiance's units, and a PNG keeps the header's numbers as text (they were dropped: a render's PNG
// did not say its exposure, and a sky preview claimed W m^-2 sr^-1 for 8-bit display values).
TEST(ImageIo, ADisplayPngSaysItsExposureAndNoUnits) {
    const std::string dir = test::temp_dir("display_png");
    Image linear(2, 2, 3);
    linear.metadata.strings["dynsky:units"] = "W m^-2 sr^-1";
    linear.metadata.numbers["dynsky:time"] = 1781539200.5;
    const Image display = tonemap_to_display(linear, -1.25f);
    EXPECT_EQ(display.metadata.strings.count("dynsky:units"), 0u);
    write_image(dir + "/d.png", display);
    const auto got = image_header_strings(dir + "/d.png", {"dynsky:png_exposure_ev", "dynsky:time", "dynsky:units",
                                                           "dynsky:display_transform"});
    EXPECT_EQ(got[0], "-1.25");
    EXPECT_EQ(got[1], "1781539200.5");
    EXPECT_EQ(got[2], "");
    EXPECT_NE(got[3].find("ACES"), std::string::npos);
    // An EXR keeps numbers as numbers.
    write_image(dir + "/l.exr", linear);
    EXPECT_EQ(image_header_number(dir + "/l.exr", "dynsky:time"), 1781539200.5);
    fs::remove_all(dir);
}

// A render with an alpha pass has its colour premultiplied (the sky seen from the camera
// transparent): its PNG is RGBA with straight alpha, so the sky is transparent there too rather
// than black (a review), and a half-covered pixel shows its surface's own colour.
TEST(ImageIo, APremultipliedRenderTonemapsToStraightAlpha) {
    Image color(3, 1, 3), alpha(3, 1, 1);
    for (int c = 0; c < 3; ++c)
        color.at(0, 0, c) = 0.0f, color.at(1, 0, c) = 0.1f * (c + 1), color.at(2, 0, c) = 0.2f * (c + 1);
    alpha.at(0, 0, 0) = 0.0f, alpha.at(1, 0, 0) = 0.5f, alpha.at(2, 0, 0) = 1.0f;
    const Image rgba = tonemap_to_display(color, alpha, 0.5f), rgb = tonemap_to_display(color, 0.5f);
    ASSERT_EQ(rgba.channels, 4);
    for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(rgba.at(0, 0, c), 0.0f);
        EXPECT_FLOAT_EQ(rgba.at(1, 0, c), rgb.at(2, 0, c)) << "0.5 x a colour at alpha 0.5 is that colour";
        EXPECT_FLOAT_EQ(rgba.at(2, 0, c), rgb.at(2, 0, c));
    }
    EXPECT_EQ(rgba.at(0, 0, 3), 0.0f);
    EXPECT_EQ(rgba.at(1, 0, 3), 0.5f);
    EXPECT_EQ(tonemap_to_display(color, Image(), 0.5f).channels, 3);  // no alpha pass: as before
}

TEST(ImageIo, WorkMadeEarlierIsKeptOnlyWholeFiniteAndOfTheSameSettings) {
    std::string dir = test::temp_dir("image");
    Image sky(4, 2, 3), other(3, 3, 3);
    for (float& v : sky.pixels) v = 0.5f;
    sky.metadata.strings["dynsky:key"] = "abc";
    const std::string a = dir + "/a.exr", b = dir + "/b.exr";
    write_image(a, sky), write_image(b, other);
    EXPECT_TRUE(made_earlier_with({a, b}, "dynsky:key", "abc"));
    EXPECT_FALSE(made_earlier_with({a, b}, "dynsky:key", "abd"));    // other settings
    EXPECT_FALSE(made_earlier_with({a, b}, "dynsky:other", "abc"));  // no key
    EXPECT_FALSE(made_earlier_with({b, a}, "dynsky:key", "abc"));    // the key is the first file's
    EXPECT_FALSE(made_earlier_with({a, dir + "/missing.exr"}, "dynsky:key", "abc"));
    EXPECT_FALSE(made_earlier_with({}, "dynsky:key", "abc"));
    other.pixels[4] = std::numeric_limits<float>::quiet_NaN();
    write_image(b, other);
    EXPECT_FALSE(made_earlier_with({a, b}, "dynsky:key", "abc"));  // damaged since
    // Cut short: a file that no longer decodes to its end.
    write_image(b, Image(3, 3, 3));
    const auto size = fs::file_size(b);
    fs::resize_file(b, size / 2);
    EXPECT_FALSE(made_earlier_with({a, b}, "dynsky:key", "abc"));
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

TEST(ImageIo, SizeLimitsAreExactAndNameTheFile) {
    EXPECT_EQ(image_size_problem(16384, 16384, 2), "");  // 2^28 pixels, 2^29 values: the largest allowed
    EXPECT_EQ(image_size_problem(1, 16384, 64), "");
    EXPECT_NE(image_size_problem(16384, 16384, 3), "");  // 3 * 2^28 values
    EXPECT_NE(image_size_problem(16385, 1, 1), "");
    EXPECT_NE(image_size_problem(1, 1, 65), "");
    EXPECT_NE(image_size_problem(30000, 30000, 3), "");
    EXPECT_NE(image_size_problem(0, 5, 3), "");
    try {
        check_image_size("big.exr", 30000, 30000, 3);
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("big.exr: image is 30000 x 30000 with 3 channels"), std::string::npos)
            << e.what();
    }
}

TEST(ImageIo, ReadingRecordsTheFileFormatAndRefusesCutJpegs) {
    std::string dir = test::temp_dir("image");
    Image image(40, 30, 3);
    for (size_t k = 0; k < image.pixels.size(); ++k) image.pixels[k] = float(k % 97) / 97.0f;
    write_image(dir + "/a.jpg", image);
    write_image(dir + "/a.exr", image);
    Image jpg = read_image(dir + "/a.jpg");
    EXPECT_EQ(jpg.file_format, "jpeg");
    EXPECT_EQ(jpg.file_pixel_type, "uint8");
    Image exr = read_image(dir + "/a.exr");
    EXPECT_EQ(exr.file_format, "openexr");
    EXPECT_EQ(exr.file_pixel_type, "float");
    std::ifstream in(dir + "/a.jpg", std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (size_t keep : {bytes.size() / 10, bytes.size() / 2, bytes.size() - 2}) {
        std::ofstream(dir + "/cut.jpg", std::ios::binary) << bytes.substr(0, keep);
        try {
            read_image(dir + "/cut.jpg");
            ADD_FAILURE() << "a JPEG cut to " << keep << " of " << bytes.size() << " bytes was read";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("cut.jpg"), std::string::npos) << e.what();
        }
    }
    // Bytes after the end-of-image marker (as some cameras append) are not a truncation.
    std::ofstream(dir + "/tail.jpg", std::ios::binary) << bytes << "trailing camera data";
    EXPECT_NO_THROW(read_image(dir + "/tail.jpg"));
}

// A fuzz finding (fuzz_sky_image): a PNG cut short made libpng longjmp out of OpenImageIO's read
// callback, leaking its error string, with a message naming no file. Cut anywhere, a PNG is now
// refused before decoding, naming the file; under ASan (scripts/test_sanitizers.sh) nothing leaks.
TEST(ImageIo, PngCutAnywhereIsRefusedNamingTheFile) {
    std::string dir = test::temp_dir("image_png");
    Image image(16, 16, 3);
    for (size_t k = 0; k < image.pixels.size(); ++k) image.pixels[k] = float(k % 13) / 13.0f;
    image.metadata.strings["Description"] = "text chunks before the pixels";
    write_image(dir + "/a.png", image);
    std::ifstream in(dir + "/a.png", std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_GT(bytes.size(), 100u);
    for (size_t keep = 0; keep < bytes.size(); ++keep) {
        std::ofstream(dir + "/cut.png", std::ios::binary) << bytes.substr(0, keep);
        try {
            read_image(dir + "/cut.png");
            ADD_FAILURE() << "a PNG cut to " << keep << " of " << bytes.size() << " bytes was read";
        } catch (const Error& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("cut.png"), std::string::npos) << what;
            if (keep > 8) {
                EXPECT_NE(what.find("cut short"), std::string::npos) << keep << ": " << what;
            }
        }
    }
    std::ofstream(dir + "/tail.png", std::ios::binary) << bytes << "bytes after IEND";
    EXPECT_NO_THROW(read_image(dir + "/tail.png"));
    fs::remove_all(dir);
}

// A WebP photograph (as a web download of an all-sky camera comes): OpenImageIO's WebP reader
// cannot go back to the first image after the multi-part check asked for a second, and the read
// failed as "could not decode pixels".
TEST(ImageIo, WebpPhotographsAreRead) {
    const std::string dir = test::temp_dir("webp");
    const std::string path = dir + "/photo.webp";
    {
        OIIO::ImageSpec spec(40, 30, 3, OIIO::TypeDesc::UINT8);
        std::vector<unsigned char> pixels(40 * 30 * 3);
        for (size_t i = 0; i < pixels.size(); ++i) pixels[i] = (unsigned char)(i % 3 == 2 ? 200 : 60);
        auto out = OIIO::ImageOutput::create(path);
        if (!out) GTEST_SKIP() << "this OpenImageIO writes no WebP";
        spec.attribute("compression", "webp:100");
        ASSERT_TRUE(out->open(path, spec));
        ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, pixels.data()));
        out->close();
    }
    const Image image = read_image(path);
    ASSERT_EQ(image.width, 40);
    ASSERT_EQ(image.height, 30);
    EXPECT_NEAR(image.at(20, 15, 2), 200.0f / 255.0f, 0.05f);
    EXPECT_NEAR(image.at(20, 15, 0), 60.0f / 255.0f, 0.05f);
    fs::remove_all(dir);
}

// Every EXIF orientation turns the stored pixels into the view a photo viewer shows: the displayed
// pixel (x, y) of a W x H stored image is the stored one the EXIF specification names.
TEST(ImageIo, ExifOrientationTurnsThePixelsAsViewersShowThem) {
    const int W = 3, H = 2;
    Image stored(W, H, 1);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) stored.at(x, y, 0) = float(10 * y + x);
    // Stored position shown at displayed (x, y), for orientations 1-8.
    const std::function<std::pair<int, int>(int, int)> source[9] = {
        nullptr,
        [](int x, int y) { return std::make_pair(x, y); },
        [](int x, int y) { return std::make_pair(W - 1 - x, y); },          // mirrored left-right
        [](int x, int y) { return std::make_pair(W - 1 - x, H - 1 - y); },  // 180 degrees
        [](int x, int y) { return std::make_pair(x, H - 1 - y); },          // mirrored top-bottom
        [](int x, int y) { return std::make_pair(y, x); },                  // transposed
        [](int x, int y) { return std::make_pair(y, H - 1 - x); },          // 90 degrees clockwise
        [](int x, int y) { return std::make_pair(W - 1 - y, H - 1 - x); },  // transversed
        [](int x, int y) { return std::make_pair(W - 1 - y, x); },          // 90 degrees anticlockwise
    };
    for (int o = 1; o <= 8; ++o) {
        Image image = stored;
        image.metadata.numbers["Orientation"] = o;
        EXPECT_EQ(apply_orientation(image), o);
        const bool swapped = o >= 5;
        ASSERT_EQ(image.width, swapped ? H : W) << o;
        ASSERT_EQ(image.height, swapped ? W : H) << o;
        EXPECT_EQ(image.metadata.numbers["Orientation"], 1);
        for (int y = 0; y < image.height; ++y)
            for (int x = 0; x < image.width; ++x) {
                const auto [sx, sy] = source[o](x, y);
                EXPECT_EQ(image.at(x, y, 0), stored.at(sx, sy, 0)) << "orientation " << o << " at " << x << "," << y;
            }
    }
    // No tag, or one outside 1-8: nothing changes.
    Image plain = stored;
    EXPECT_EQ(apply_orientation(plain), 1);
    plain.metadata.numbers["Orientation"] = 9;
    EXPECT_EQ(apply_orientation(plain), 1);
    EXPECT_EQ(plain.pixels, stored.pixels);

    // Read from a camera's JPEG: the tag arrives (EXIF's unsigned short) and turns the photograph.
    const std::string dir = test::temp_dir("orientation");
    auto out = OIIO::ImageOutput::create(dir + "/turned.jpg");
    OIIO::ImageSpec spec(40, 24, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("Orientation", 6);
    std::vector<unsigned char> bytes(size_t(40) * 24 * 3, 128);
    ASSERT_TRUE(out->open(dir + "/turned.jpg", spec) && out->write_image(OIIO::TypeDesc::UINT8, bytes.data()));
    out->close();
    Image photo = read_image(dir + "/turned.jpg");
    EXPECT_EQ(apply_orientation(photo), 6);
    EXPECT_EQ(photo.width, 24);
    EXPECT_EQ(photo.height, 40);
    fs::remove_all(dir);
}

// Alpha is never radiance: OpenImageIO multiplied a PNG's or TIFF's unassociated alpha into its
// colour, so a sky or photograph with alpha 0.5 came in at half its light (0 read black).
TEST(ImageIo, AlphaDoesNotScaleTheColour) {
    const std::string dir = test::temp_dir("alpha");
    for (const char* name : {"sky.png", "sky.tif"}) {
        const std::string path = dir + "/" + name;
        auto out = OIIO::ImageOutput::create(path);
        OIIO::ImageSpec spec(4, 2, 4, OIIO::TypeDesc::UINT8);
        spec.alpha_channel = 3;
        spec.attribute("oiio:UnassociatedAlpha", 1);
        std::vector<unsigned char> bytes;
        for (int p = 0; p < 8; ++p) bytes.insert(bytes.end(), {200, 100, 50, (unsigned char)(p < 4 ? 128 : 0)});
        ASSERT_TRUE(out->open(path, spec) && out->write_image(OIIO::TypeDesc::UINT8, bytes.data())) << name;
        out->close();
        const Image image = read_image(path);
        ASSERT_EQ(image.channels, 4) << name;
        for (int y = 0; y < 2; ++y)
            for (int x = 0; x < 4; ++x) {
                EXPECT_NEAR(image.at(x, y, 0), 200 / 255.0f, 1e-6f) << name << " " << x << "," << y;
                EXPECT_NEAR(image.at(x, y, 2), 50 / 255.0f, 1e-6f) << name << " " << x << "," << y;
            }
    }
    fs::remove_all(dir);
}

// A Radiance file's EXPOSURE says what was multiplied into its pixels: radiance is pixel / EXPOSURE.
TEST(ImageIo, RadianceExposureIsDividedOut) {
    const std::string dir = test::temp_dir("hdr_exposure");
    auto write_hdr = [&](const std::string& path, const char* exposure_line) {
        std::ofstream f(path, std::ios::binary);
        f << "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n" << exposure_line << "\n-Y 2 +X 2\n";
        for (int p = 0; p < 4; ++p) f.write("\x80\x80\x80\x81", 4);  // 0.5 * 2^1 = 1.0 per channel
    };
    write_hdr(dir + "/plain.hdr", "");
    write_hdr(dir + "/exposed.hdr", "EXPOSURE=2.0\n");
    {
        // XYZE pixels (OpenImageIO reads RGBE only): said as such.
        std::ofstream f(dir + "/xyze.hdr", std::ios::binary);
        f << "#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 2 +X 2\n";
        for (int p = 0; p < 4; ++p) f.write("\x80\x80\x80\x81", 4);
    }
    try {
        read_image(dir + "/xyze.hdr");
        ADD_FAILURE() << "an XYZE file was read as RGB";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("XYZE"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("xyze.hdr"), std::string::npos) << e.what();
    }
    const Image plain = read_image(dir + "/plain.hdr"), exposed = read_image(dir + "/exposed.hdr");
    ASSERT_EQ(plain.pixels.size(), exposed.pixels.size());
    for (size_t k = 0; k < plain.pixels.size(); ++k) {
        EXPECT_NEAR(plain.pixels[k], 1.0f, 1e-6f) << k;
        EXPECT_NEAR(exposed.pixels[k], 0.5f, 1e-6f) << k;
    }
    fs::remove_all(dir);
}

}  // namespace
}  // namespace dynsky
