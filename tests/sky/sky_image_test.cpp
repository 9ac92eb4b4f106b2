#include "sky/sky_image.h"

#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>

#include "sky/latlong.h"
#include "sky/noise.h"
#include "tests/test_support.h"
#include "util/error.h"

namespace dynsky {
namespace {

namespace fs = std::filesystem;

// A sky whose disc pixels hold values a half-float or 8-bit path could not keep: full-precision
// mantissas over many decades (1e-20 to a 1e6 sun).
SkyImage awkward_sky(int n) {
    SkyImage sky(n);
    uint64_t s = 99;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            if (!sky.in_disc(i, j)) continue;
            Color c;
            for (int k = 0; k < 3; ++k) c[k] = float(std::pow(10.0, -20.0 + 26.0 * noise_unit(s = noise_hash(s))));
            sky.set_pixel(i, j, c);
        }
    sky.set_pixel(n / 2, n / 2, Color(1.0000001f, 3.1415927f, 123456.79f));
    return sky;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

TEST(SkyImage, SaveAndLoadKeepPixelsBitForBitAndTheAttributes) {
    std::string dir = test::temp_dir("sky_image");
    SkyImage sky = awkward_sky(37);
    sky.time_seconds = 86399.123456789;            // needs a double: a float attribute would keep ~8 digits
    sky.sun_direction = Vec3(0.48f, 0.6f, 0.64f);  // unit
    sky.source = "procedural:seed 7";
    const std::string path = dir + "/sky.exr";
    save_sky(path, sky, dir + "/preview.png");

    SkyImage back = load_sky(path);
    EXPECT_EQ(back.resolution, 37);
    EXPECT_TRUE(same_bits(back.rgb, sky.rgb)) << "pixels changed on the way through the file";
    EXPECT_EQ(back.time_seconds, sky.time_seconds);
    ASSERT_TRUE(back.sun_direction.has_value());
    EXPECT_NEAR((*back.sun_direction - *sky.sun_direction).norm(), 0.0f, 1e-6f);
    EXPECT_EQ(back.source, "procedural:seed 7");
    EXPECT_TRUE(fs::is_regular_file(dir + "/preview.png"));
    // Written atomically: only the two outputs are left, no temporary.
    int files = 0;
    for (const auto& e : fs::directory_iterator(dir)) {
        ++files;
        EXPECT_NE(e.path().filename().string().rfind(".tmp", 0), 0u) << e.path();
    }
    EXPECT_EQ(files, 2);
    fs::remove_all(dir);
}

// A folder's skies in the order they were taken, from their headers: by name, sky_9 came after
// sky_11 and a sequence started from the wrong frame. Imported photographs (all at 0 on the clock)
// by the UTC times their imports recorded; a file without either leaves name order.
// A square file from another tool whose brightest light lies in a corner is not an upper-hemisphere
// fisheye (a lat-long's top half stored square): refused, where its corners were dropped and its
// sun put at the horizon silently. A uniform square and a fisheye with black corners are taken.
TEST(SkyImage, ASquareImageWithLightOutsideTheDiscIsNotAFisheye) {
    const std::string dir = test::temp_dir("sky_not_fisheye");
    Image full(32, 32, 3);
    for (float& v : full.pixels) v = 2.0f;
    write_image(dir + "/uniform.exr", full);  // a furnace test's sky: the same in any layout
    EXPECT_NO_THROW(load_sky(dir + "/uniform.exr"));
    for (int c = 0; c < 3; ++c) full.at(1, 1, c) = 5000.0f;  // its sun in a corner
    write_image(dir + "/square_panorama.exr", full);
    try {
        load_sky(dir + "/square_panorama.exr");
        ADD_FAILURE() << "a square image with light in its corners was taken as a fisheye";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("square_panorama.exr: is not an upper-hemisphere fisheye: its brightest"),
                  std::string::npos)
            << e.what();
    }
    SkyImage disc(32);
    for (int j = 0; j < 32; ++j)
        for (int i = 0; i < 32; ++i)
            if (disc.in_disc(i, j)) disc.set_pixel(i, j, Color(1.0f, 2.0f, 3.0f));
    Image plain(32, 32, 3);
    plain.pixels = disc.rgb;  // no dynsky:layout: as another tool writes it
    write_image(dir + "/fisheye.exr", plain);
    EXPECT_NO_THROW(load_sky(dir + "/fisheye.exr"));
    std::filesystem::remove_all(dir);
}

// A capture tool's sequence of Radiance .hdr skies is a sequence (it was refused as "a folder
// without sky EXRs", though each file worked alone).
// An ACEScg or ACES2065-1 sky (VFX renders and HDRIs) is read in dynsky's linear Rec.709: an
// AP1 grey stays grey, an AP1 red becomes the Rec.709 colour it is (1.705, -0.130, -0.024: its
// negative part, outside Rec.709's gamut, clipped to 0), not the Rec.709 red (1, 0, 0) it read as.
TEST(SkyImage, SkiesInAcesPrimariesAreReadInRec709) {
    const std::string dir = test::temp_dir("sky_aces");
    const std::vector<float> pixels = {0.5f, 0.5f, 0.5f, 1.0f, 0.0f, 0.0f, 0.2f, 0.4f, 0.1f, 0.0f, 0.0f, 1.0f};
    auto write = [&](const std::string& name, auto&& tag) {
        OIIO::ImageSpec spec(2, 2, 3, OIIO::TypeDesc::FLOAT);
        tag(spec);
        auto out = OIIO::ImageOutput::create(dir + "/" + name);
        ASSERT_TRUE(out);
        ASSERT_TRUE(out->open(dir + "/" + name, spec));
        ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()));
        out->close();
    };
    write("ap1.exr", [](OIIO::ImageSpec& spec) {
        const Chromaticities c = aces_ap1_chromaticities();
        spec.attribute("chromaticities", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, 8), c.data());
    });
    write("aces_container.exr", [](OIIO::ImageSpec& spec) { spec.attribute("acesImageContainerFlag", 1); });
    write("plain.exr", [](OIIO::ImageSpec&) {});
    const Image ap1 = read_radiance_image(dir + "/ap1.exr");
    const Eigen::Matrix3d m = rec709_from(aces_ap1_chromaticities());
    for (int q = 0; q < 4; ++q) {
        const Eigen::Vector3d in(pixels[q * 3], pixels[q * 3 + 1], pixels[q * 3 + 2]), out = m * in;
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(ap1.pixels[q * 3 + c], std::max(0.0, out[c]), 1e-5) << q << " " << c;
    }
    EXPECT_NEAR(ap1.pixels[0], 0.5, 1e-3);  // grey stays grey
    EXPECT_NEAR(ap1.pixels[2], 0.5, 1e-3);
    EXPECT_NEAR(ap1.pixels[3], 1.705, 2e-3);  // the AP1 red
    EXPECT_EQ(ap1.pixels[4], 0.0f);           // outside Rec.709: clipped
    const Image container = read_radiance_image(dir + "/aces_container.exr");
    EXPECT_NEAR(container.pixels[3], 2.5217, 2e-3);  // AP0's red
    EXPECT_EQ(container.metadata.numbers.count("acesImageContainerFlag"), 0u) << "not passed on to what is written";
    const Image plain = read_radiance_image(dir + "/plain.exr");
    EXPECT_EQ(plain.pixels, pixels);
    // With alpha (a render's RGBA) the colour is converted as well; a grey image stays as it is.
    {
        const std::vector<float> rgba = {1.0f, 0.0f, 0.0f, 0.5f};
        OIIO::ImageSpec spec(1, 1, 4, OIIO::TypeDesc::FLOAT);
        const Chromaticities c = aces_ap1_chromaticities();
        spec.attribute("chromaticities", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, 8), c.data());
        auto out = OIIO::ImageOutput::create(dir + "/rgba.exr");
        ASSERT_TRUE(out && out->open(dir + "/rgba.exr", spec) && out->write_image(OIIO::TypeDesc::FLOAT, rgba.data()));
        out->close();
        OIIO::ImageSpec grey_spec(2, 1, 1, OIIO::TypeDesc::FLOAT);
        grey_spec.attribute("chromaticities", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, 8), c.data());
        auto grey_out = OIIO::ImageOutput::create(dir + "/grey.exr");
        ASSERT_TRUE(grey_out && grey_out->open(dir + "/grey.exr", grey_spec) &&
                    grey_out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()));
        grey_out->close();
    }
    EXPECT_NEAR(read_radiance_image(dir + "/rgba.exr").pixels[0], 1.705, 2e-3);
    const Image grey = read_radiance_image(dir + "/grey.exr");
    EXPECT_EQ(grey.pixels, std::vector<float>(pixels.begin(), pixels.begin() + 2));
    std::filesystem::remove_all(dir);
}

TEST(SkyImage, AFolderOfHdrSkiesIsASequence) {
    const std::string dir = test::temp_dir("sky_hdr_sequence");
    SkyImage disc(16);
    for (int j = 0; j < 16; ++j)
        for (int i = 0; i < 16; ++i)
            if (disc.in_disc(i, j)) disc.set_pixel(i, j, Color(1.0f, 2.0f, 3.0f));
    for (const char* name : {"sky_0002.hdr", "sky_0001.hdr"}) {  // as another tool writes them
        auto out = OIIO::ImageOutput::create(dir + "/" + name);
        ASSERT_TRUE(out);
        ASSERT_TRUE(out->open(dir + "/" + name, OIIO::ImageSpec(16, 16, 3, OIIO::TypeDesc::FLOAT)));
        ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, disc.rgb.data()));
        out->close();
    }
    const std::vector<std::string> files = sky_sequence_files(dir);
    ASSERT_EQ(files.size(), 2u);
    EXPECT_NE(files[0].find("sky_0001.hdr"), std::string::npos);
    EXPECT_NO_THROW(load_sky(files[1]));
    std::filesystem::remove_all(dir);
}

TEST(SkyImage, SkiesOfAFolderAreOrderedByTheirClocksThenTheirRecordedTimes) {
    const std::string dir = test::temp_dir("sky_order");
    SkyImage sky = awkward_sky(8);
    auto write = [&](const std::string& name, double t, const std::string& source) {
        sky.time_seconds = t, sky.source = source;
        save_sky(dir + "/" + name, sky);
        return dir + "/" + name;
    };
    const std::string a = write("sky_1.exr", 0, "procedural"), b = write("sky_11.exr", 100.25, "procedural"),
                      c = write("sky_9.exr", 80, "procedural");
    EXPECT_EQ(skies_in_time_order({b, c, a}), (std::vector<std::string>{a, c, b}));
    EXPECT_EQ(image_header_number(b, "dynsky:time").value_or(-1), 100.25);
    EXPECT_EQ(skies_in_time_order({c}), std::vector<std::string>{c});
    EXPECT_TRUE(skies_in_time_order({}).empty());
    // Imported photographs: every clock at 0, their recorded times in any zone.
    const std::string p = write("p_a.exr", 0, "photo:x.jpg time=2020-08-12T09:21:00+02:00"),
                      q = write("p_b.exr", 0, "photo:y.jpg time=2020-08-12T07:20:00Z"),
                      r = write("p_c.exr", 0, "photo:z.jpg time=2020-08-12T07:19:00Z");
    EXPECT_EQ(skies_in_time_order({p, q, r}), (std::vector<std::string>{r, q, p}));
    // One without a recorded time: name order.
    const std::string u = write("p_d.exr", 0, "photo:w.jpg");
    EXPECT_EQ(skies_in_time_order({u, r, p, q}), (std::vector<std::string>{p, q, r, u}));
    fs::remove_all(dir);
}

TEST(SkyImage, WithoutSunOrSourceTheLoadedSkyHasNoSunAndNamesItsFile) {
    std::string dir = test::temp_dir("sky_image_plain");
    SkyImage sky = awkward_sky(16);
    sky.time_seconds = -2.5;
    const std::string path = dir + "/plain.exr";
    save_sky(path, sky);
    SkyImage back = load_sky(path);
    EXPECT_TRUE(same_bits(back.rgb, sky.rgb));
    EXPECT_EQ(back.time_seconds, -2.5);
    EXPECT_FALSE(back.sun_direction.has_value());
    EXPECT_EQ(back.source, path);
    EXPECT_FALSE(fs::exists(dir + "/plain.png")) << "no preview was asked for";
    fs::remove_all(dir);
}

// The mask of the pixels an import filled (STEM.filled.png beside STEM.exr) comes with the sky,
// through either loader, and follows it to another resolution (filled wherever any pixel under a
// new one was); one of another size is refused naming it.
TEST(SkyImage, TheFilledMaskBesideASkyIsLoadedWithIt) {
    const std::string dir = test::temp_dir("sky_filled");
    const SkyImage sky = awkward_sky(16);
    save_sky(dir + "/s.exr", sky);
    EXPECT_TRUE(load_sky(dir + "/s.exr").filled.empty());
    Image mask(16, 16, 1);
    mask.pixels[size_t(5) * 16 + 7] = 1.0f;  // one filled pixel: (7, 5)
    write_image(dir + "/s.filled.png", mask);
    std::shared_ptr<SkyImage> ground;
    for (const SkyImage& back : {load_sky(dir + "/s.exr"), load_sky_or_latlong(dir + "/s.exr", &ground)}) {
        ASSERT_EQ(back.filled.size(), 256u);
        EXPECT_TRUE(back.is_filled(7, 5));
        EXPECT_FALSE(back.is_filled(8, 5));
        const SkyImage half = resampled_sky(back, 8);
        ASSERT_EQ(half.filled.size(), 64u);
        EXPECT_TRUE(half.is_filled(3, 2));
        EXPECT_EQ(std::count(half.filled.begin(), half.filled.end(), 1), 1);
    }
    // Another sky saved under the name: the mask was the earlier sky's.
    save_sky(dir + "/s.exr", sky);
    EXPECT_FALSE(fs::exists(dir + "/s.filled.png"));
    // One of another size is not this sky's: ignored.
    write_image(dir + "/s.filled.png", Image(8, 8, 1));
    EXPECT_TRUE(load_sky(dir + "/s.exr").filled.empty());
    fs::remove_all(dir);
}

TEST(SkyImage, SavingAnotherFormatOrLoadingABadSkyFailsNamingTheFile) {
    std::string dir = test::temp_dir("sky_image_bad");
    SkyImage sky = awkward_sky(8);
    try {
        save_sky(dir + "/sky.png", sky);
        FAIL() << "saved a sky as PNG";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("sky.png"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(dir + "/sky.png"));
    // A black sky saves (it is only data) but does not load as a light source.
    save_sky(dir + "/black.exr", SkyImage(8));
    EXPECT_THROW(load_sky(dir + "/black.exr"), Error);
    EXPECT_THROW(load_sky(dir + "/missing.exr"), Error);
    fs::remove_all(dir);
}

TEST(SkyImage, RadianceAboveTheLimitOrIntegerFilesAreNotSkies) {
    std::string dir = test::temp_dir("sky_image_limits");
    SkyImage sky(8);
    for (float& v : sky.rgb) v = 1.0f;
    sky.set_pixel(3, 4, Color(1, float(kMaxSkyRadiance), 1));  // at the limit: a sky
    EXPECT_NO_THROW(validate_sky(sky, "at_limit"));
    sky.set_pixel(3, 4, Color(1, 1e35f, 1));
    try {
        validate_sky(sky, "bright.exr");
        ADD_FAILURE() << "a 1e35 pixel was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("bright.exr: sky pixel (3, 4) is 1e+35"), std::string::npos) << e.what();
    }
    // The same values in an 8-bit PNG: display-encoded, not radiance, whatever the name says.
    Image im(8, 8, 3);
    for (float& v : im.pixels) v = 0.5f;
    write_image(dir + "/sky.png", im);
    fs::rename(dir + "/sky.png", dir + "/renamed.exr");
    try {
        load_sky(dir + "/renamed.exr");
        ADD_FAILURE() << "an 8-bit PNG loaded as a sky";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("renamed.exr: is a png file of uint8 pixels"), std::string::npos)
            << e.what();
    }
    // Twice as wide as high, it would be taken as a lat-long HDRI: refused the same way, by both readers.
    Image wide(16, 8, 3);
    for (float& v : wide.pixels) v = 0.5f;
    write_image(dir + "/hdri.png", wide);
    std::shared_ptr<SkyImage> ground;
    for (int reader = 0; reader < 2; ++reader) {
        try {
            if (reader == 0) load_sky_or_latlong(dir + "/hdri.png", &ground);
            else load_latlong_environment(dir + "/hdri.png");
            ADD_FAILURE() << "an 8-bit 2:1 PNG loaded as a lat-long sky (reader " << reader << ")";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("hdri.png: is a png file of uint8 pixels"), std::string::npos)
                << e.what();
        }
    }
    fs::remove_all(dir);
}

// Lossily compressed EXRs (DWAA/DWAB/B44, common among downloaded HDRIs) ring slightly below zero
// beside bright pixels: such values read as 0; a negative that is not ringing is still refused.
TEST(SkyImage, LossyCompressionRingingReadsAsZeroRealNegativesAreRefused) {
    const std::string dir = test::temp_dir("sky_image_ringing");
    SkyImage sky(16);
    for (float& v : sky.rgb) v = 0.1f;
    sky.set_pixel(8, 8, Color(50.0f, 50.0f, 50.0f));
    sky.set_pixel(9, 8, Color(-5e-6f, 0.1f, 0.1f));  // ringing beside the bright pixel
    Image image = sky_to_image(sky);
    write_image(dir + "/ringing.exr", image);
    const SkyImage loaded = load_sky(dir + "/ringing.exr");
    EXPECT_EQ(loaded.pixel(9, 8)[0], 0.0f);
    EXPECT_EQ(loaded.pixel(8, 8)[0], 50.0f);
    image.pixels[(size_t(8) * 16 + 9) * 3] = -0.2f;  // 0.4 % of the brightest: not ringing
    write_image(dir + "/negative.exr", image);
    try {
        load_sky(dir + "/negative.exr");
        ADD_FAILURE() << "a sky with a -0.2 pixel loaded";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("negative.exr: sky pixel (9, 8) is negative"), std::string::npos)
            << e.what();
    }
    // Ringing lies beside the bright pixel: a negative far from it, however small against the sun, is
    // refused (against the whole image's brightest, a -500 pixel 70 degrees from a 2e6 sun read as 0).
    SkyImage far(64);
    for (float& v : far.rgb) v = 3.0f;
    far.set_pixel(50, 50, Color(2e6f, 2e6f, 2e6f));
    far.set_pixel(12, 30, Color(-500.0f, 3.0f, 3.0f));
    write_image(dir + "/far.exr", sky_to_image(far));
    try {
        load_sky(dir + "/far.exr");
        ADD_FAILURE() << "a sky with a -500 pixel far from its sun loaded";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("sky pixel (12, 30) is negative"), std::string::npos) << e.what();
    }
    fs::remove_all(dir);
}

// Resampling keeps a uniform sky uniform up to the rim, up and down (the rim neither darkened by
// the black outside the disc nor lost), and keeps the metadata.
TEST(SkyImage, ResampledUpOrDownKeepsTheRimAndTheMetadata) {
    SkyImage sky(32);
    for (int j = 0; j < 32; ++j)
        for (int i = 0; i < 32; ++i)
            if (sky.in_disc(i, j)) sky.set_pixel(i, j, Color(0.5f, 0.25f, 2.0f));
    sky.time_seconds = 12.0;
    sky.sun_direction = Vec3(0, 1, 0);
    for (int n : {64, 100, 17}) {
        const SkyImage r = resampled_sky(sky, n);
        ASSERT_EQ(r.resolution, n);
        EXPECT_EQ(r.time_seconds, 12.0);
        ASSERT_TRUE(r.sun_direction);
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const Color c = r.pixel(i, j);
                if (!r.in_disc(i, j)) {
                    EXPECT_EQ(c.sum(), 0.0f);
                    continue;
                }
                EXPECT_NEAR(c[0], 0.5f, 1e-5) << n << ": " << i << ", " << j;
                EXPECT_NEAR(c[2], 2.0f, 1e-5) << n << ": " << i << ", " << j;
            }
    }
}

// A folder of skies that say no time is taken in the order people number them: "s 11" is the last,
// "s 10" the one before it (plain string order made "s 9" the last and measured the motion backwards).
TEST(SkyImage, ASequenceWithoutTimesIsInNumberOrder) {
    const std::string dir = test::temp_dir("sky_sequence_numbers");
    for (const char* name : {"s 9.exr", "s 10.exr", "s 11.exr"}) save_sky(dir + "/" + name, SkyImage(16));
    std::string previous;
    EXPECT_EQ(std::filesystem::path(sequence_start(dir, true, &previous, true)).filename(), "s 11.exr");
    EXPECT_EQ(std::filesystem::path(previous).filename(), "s 10.exr");
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace dynsky

namespace dynsky {
namespace {

// An EXR of a uniform 8 x 8 sky written directly (channel names, attributes and windows as given).
void write_test_exr(const std::string& path, const std::vector<std::string>& channels,
                    const std::vector<std::pair<std::string, std::string>>& text_attributes,
                    const std::vector<std::pair<std::string, float>>& number_attributes, int full = 8) {
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(8, 8, int(channels.size()), OIIO::TypeDesc::FLOAT);
    spec.channelnames = channels;
    spec.full_width = spec.full_height = full;
    for (const auto& [k, v] : text_attributes) spec.attribute(k, v);
    for (const auto& [k, v] : number_attributes) spec.attribute(k, v);
    std::vector<float> px(size_t(64) * channels.size());
    for (size_t i = 0; i < px.size(); ++i) px[i] = float(1 + i % channels.size());  // channel k holds k + 1
    ASSERT_TRUE(out->open(path, spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data()));
    out->close();
}

std::string load_sky_error(const std::string& path) {
    try {
        load_sky(path);
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

// A bad-input audit's finds: a NaN sun attribute made NaN skies (exit 0), non-colour channels were
// read as R, G, B, a cropped data window was taken for the whole sky.
TEST(SkyImage, ChannelsAreFoundByNameAndBadAttributesOrWindowsAreRefused) {
    const std::string dir = test::temp_dir("sky_attrs");
    // Colour channels by name, wherever the file keeps them, also in one layer.
    write_test_exr(dir + "/bgr.exr", {"B", "G", "R"}, {}, {});
    SkyImage bgr = load_sky(dir + "/bgr.exr");
    const Color c = bgr.pixel(4, 4);
    EXPECT_FLOAT_EQ(c[0], 3.0f);  // R is the third channel
    EXPECT_FLOAT_EQ(c[2], 1.0f);
    write_test_exr(dir + "/layer.exr", {"A", "sky.B", "sky.G", "sky.R"}, {}, {});
    EXPECT_FLOAT_EQ(load_sky(dir + "/layer.exr").pixel(4, 4)[0], 4.0f);
    write_test_exr(dir + "/lower.exr", {"r", "g", "b"}, {}, {});
    EXPECT_FLOAT_EQ(load_sky(dir + "/lower.exr").pixel(4, 4)[2], 3.0f);
    // A render's AOV layers beside its RGB: the RGB.
    write_test_exr(dir + "/aovs.exr", {"diffuse.R", "diffuse.G", "diffuse.B", "R", "G", "B"}, {}, {});
    EXPECT_FLOAT_EQ(load_sky(dir + "/aovs.exr").pixel(4, 4)[0], 4.0f);
    struct Case {
        std::string name;
        std::vector<std::string> channels;
        std::vector<std::pair<std::string, std::string>> text;
        std::vector<std::pair<std::string, float>> numbers;
        int full;
        std::string expect;
    };
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const std::vector<Case> cases = {
        {"xyz", {"X", "Y", "Z"}, {}, {}, 8, "has no R channel (its channels: X, Y, Z)"},
        {"two_layers", {"a.R", "a.G", "a.B", "b.R", "b.G", "b.B"}, {}, {}, 8, "more than one layer"},
        {"sun_nan",
         {"R", "G", "B"},
         {},
         {{"dynsky:sun_x", 0.f}, {"dynsky:sun_y", nan}, {"dynsky:sun_z", 0.f}},
         8,
         "dynsky:sun_y is nan"},
        {"sun_zero",
         {"R", "G", "B"},
         {},
         {{"dynsky:sun_x", 0.f}, {"dynsky:sun_y", 0.f}, {"dynsky:sun_z", 0.f}},
         8,
         "not a direction"},
        {"sun_part", {"R", "G", "B"}, {}, {{"dynsky:sun_x", 1.f}}, 8, "only part of the sun"},
        {"sun_text",
         {"R", "G", "B"},
         {{"dynsky:sun_x", "east"}},
         {{"dynsky:sun_y", 1.f}, {"dynsky:sun_z", 0.f}},
         8,
         "dynsky:sun_x is text"},
        {"time_inf",
         {"R", "G", "B"},
         {},
         {{"dynsky:time", std::numeric_limits<float>::infinity()}},
         8,
         "dynsky:time is inf"},
        {"cropped", {"R", "G", "B"}, {}, {}, 16, "data window 8x8"},
    };
    for (const Case& k : cases) {
        const std::string path = dir + "/" + k.name + ".exr";
        write_test_exr(path, k.channels, k.text, k.numbers, k.full);
        const std::string e = load_sky_error(path);
        EXPECT_NE(e.find(path), std::string::npos) << k.name << ": " << e;
        EXPECT_NE(e.find(k.expect), std::string::npos) << k.name << ": " << e;
    }
    std::filesystem::remove_all(dir);
}

// Whole numbers written as int attributes (`oiiotool --attrib dynsky:time 10`, the natural way to fix
// a sky's metadata) were read as 0: a sun of (0, 1, 0) was refused as (0, 0, 0), and a --prev frame's
// int time gave the wrong gap between frames with exit 0. Ints and doubles are numbers as floats are.
TEST(SkyImage, IntegerAndDoubleAttributesAreReadAsTheirValues) {
    const std::string dir = test::temp_dir("sky_int_attrs");
    const std::string path = dir + "/int.exr";
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(8, 8, 3, OIIO::TypeDesc::FLOAT);
    spec.attribute("dynsky:time", 10);  // int
    spec.attribute("dynsky:sun_x", 0);
    spec.attribute("dynsky:sun_y", 1);
    spec.attribute("dynsky:sun_z", 0);
    spec.attribute("dynsky:extra", OIIO::TypeDesc::DOUBLE, &kPiD);
    std::vector<float> px(8 * 8 * 3, 1.0f);
    ASSERT_TRUE(out->open(path, spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data()));
    out->close();
    const SkyImage sky = load_sky(path);
    EXPECT_DOUBLE_EQ(sky.time_seconds, 10.0);
    ASSERT_TRUE(sky.sun_direction.has_value());
    EXPECT_FLOAT_EQ((*sky.sun_direction).y(), 1.0f);
    EXPECT_DOUBLE_EQ(read_image(path).metadata.numbers.at("dynsky:extra"), kPiD);  // exactly, not as a float
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace dynsky
