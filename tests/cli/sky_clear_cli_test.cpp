// End-to-end tests of `dynsky sky clear | sun | latlong`.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <future>
#include <vector>

#include "sky/sky_image.h"
#include "sky/sun_position.h"
#include "tests/test_support.h"
#include "util/image.h"

namespace dynsky {
namespace {

namespace fs = std::filesystem;

test::CommandResult dynsky(const std::string& args) { return test::run_command(std::string(DYNSKY_EXE) + " " + args); }

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

TEST(SkyClearCli, SunPrintsTheNrelSpaCase) {
    auto r = dynsky(
        "sky sun --lat 39.742476 --lon -105.1786 --elevation 1830.14 --time 2003-10-17T12:30:30-07:00 "
        "--pressure 820 --temperature 11");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(contains(r.output, "zenith     50.1116")) << r.output;  // SPA: 50.11162
    EXPECT_TRUE(contains(r.output, "azimuth    194.340")) << r.output;  // SPA: 194.34024
    EXPECT_TRUE(contains(r.output, "2003-10-17T19:30:30Z")) << r.output;
    // -q: the answer bare, for scripts (it printed nothing).
    r = dynsky(
        "sky sun -q --lat 39.742476 --lon -105.1786 --elevation 1830.14 --time 2003-10-17T12:30:30-07:00 "
        "--pressure 820 --temperature 11");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(contains(r.output, "39.888") && contains(r.output, " 194.340")) << r.output;
}

TEST(SkyClearCli, ClearWritesASkyAndPreview) {
    std::string dir = test::temp_dir("skyclear");
    std::string out = dir + "/sky.exr", png = dir + "/sky.png";
    auto r = dynsky(
        "sky clear --lat 48.8566 --lon 2.3522 --time 2026-06-21T12:00:00Z --turbidity 2.5 --albedo 0.2 --sky-res 64 --out " +
        out + " --preview " + png);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(contains(r.output, "azimuth")) << r.output;
    EXPECT_TRUE(contains(r.output, "W m^-2 sr^-1")) << r.output;
    ASSERT_TRUE(fs::exists(out));
    EXPECT_TRUE(fs::exists(png));
    SkyImage sky = load_sky(out);
    EXPECT_EQ(sky.resolution, 64);
    ASSERT_TRUE(sky.sun_direction.has_value());
    Vec3d expected =
        compute_sun_position(parse_utc_time("2026-06-21T12:00:00Z"), GeoLocation{48.8566, 2.3522, 0}).direction();
    EXPECT_NEAR((sky.sun_direction->cast<double>() - expected).norm(), 0.0, 1e-5);
    EXPECT_TRUE(contains(sky.source, "hosek-wilkie")) << sky.source;
    EXPECT_TRUE(contains(sky.source, "2026-06-21T12:00:00Z")) << sky.source;
    // --no-sun: same sky without the disc: the brightest pixel is far dimmer.
    std::string out2 = dir + "/nosun.exr";
    r = dynsky(
        "sky clear --lat 48.8566 --lon 2.3522 --time 2026-06-21T12:00:00Z --turbidity 2.5 --albedo 0.2 --no-sun --sky-res 64 --out " +
        out2);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    SkyImage nosun = load_sky(out2);
    float a = *std::max_element(sky.rgb.begin(), sky.rgb.end()),
          b = *std::max_element(nosun.rgb.begin(), nosun.rgb.end());
    EXPECT_GT(a, 100 * b);
    fs::remove_all(dir);
}

TEST(SkyClearCli, NightSunWarnsAndStillWrites) {
    std::string dir = test::temp_dir("skyclear");
    auto r = dynsky("sky clear --lat 48.8566 --lon 2.3522 --time 2026-06-21T23:00:00Z --sky-res 32 --out " + dir +
                    "/night.exr");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(contains(r.output, "below the horizon")) << r.output;
    EXPECT_TRUE(fs::exists(dir + "/night.exr"));
    fs::remove_all(dir);
}

TEST(SkyClearCli, BadInputFailsAndWritesNothing) {
    std::string dir = test::temp_dir("skyclear");
    std::string out = dir + "/sky.exr";
    const std::string base = "sky clear --lat 10 --lon 20 --sky-res 32 ";
    struct Case {
        std::string args, message;
    };
    const std::vector<Case> cases = {
        {base + "--time 2026-06-21T12:00:00 --out " + out, "time zone"},
        {base + "--time 2026-02-30T12:00:00Z --out " + out, "does not exist"},
        {base + "--time 2026-06-21T12:00:00Z --turbidity 12 --out " + out, "turbidity"},
        {base + "--time 2026-06-21T12:00:00Z --albedo -1 --out " + out, "albedo"},
        {base + "--time 2026-06-21T12:00:00Z --out " + dir + "/sky.png", "sky.png"},
        {"sky clear --lat 95 --lon 20 --sky-res 32 --time 2026-06-21T12:00:00Z --out " + out, "--lat"},
        {"sky clear --lat 10 --lon 20 --sky-res 0 --time 2026-06-21T12:00:00Z --out " + out, "--sky-res"},
    };
    // The program starts in ~0.5 s of CPU (shared libraries): run the cases side by side.
    std::vector<std::future<test::CommandResult>> runs;
    for (const Case& c : cases)
        runs.push_back(std::async(std::launch::async, [args = c.args] { return dynsky(args); }));
    for (size_t k = 0; k < cases.size(); ++k) {
        auto r = runs[k].get();
        EXPECT_NE(r.exit_code, 0) << cases[k].args << "\n" << r.output;
        EXPECT_TRUE(contains(r.output, cases[k].message)) << cases[k].args << "\n" << r.output;
    }
    EXPECT_FALSE(fs::exists(out));
    EXPECT_TRUE(fs::is_empty(dir));
    fs::remove_all(dir);
}

TEST(SkyClearCli, LatLongConvertsASky) {
    std::string dir = test::temp_dir("skyclear");
    std::string sky = dir + "/sky.exr", ll = dir + "/ll.exr";
    ASSERT_EQ(dynsky("sky clear --lat 0 --lon 0 --time 2026-03-20T09:00:00Z --sky-res 48 --out " + sky).exit_code, 0);
    auto r = dynsky("sky latlong " + sky + " --out " + ll + " --preview " + dir + "/ll.png --ground 0.1,0.2,0.3");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    Image image = read_image(ll);
    EXPECT_EQ(image.width, 96);  // default 2N
    EXPECT_EQ(image.height, 48);
    EXPECT_NEAR(image.at(5, 47, 2), 0.3f, 1e-6);  // ground
    EXPECT_TRUE(fs::exists(dir + "/ll.png"));
    EXPECT_TRUE(image.metadata.numbers.count("dynsky:sun_y"));
    r = dynsky("sky latlong " + sky + " --out " + dir + "/ll2.exr --width 40");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(read_image(dir + "/ll2.exr").width, 40);

    // Bad input: a missing sky, an odd width, a bad ground, a non-EXR output.
    const std::vector<std::pair<std::string, std::string>> bad = {
        {"sky latlong " + dir + "/missing.exr --out " + dir + "/bad.exr", "missing.exr"},
        {"sky latlong " + sky + " --out " + dir + "/bad.exr --width 33", "--width"},
        {"sky latlong " + sky + " --out " + dir + "/bad.exr --ground red", "--ground"},
        {"sky latlong " + sky + " --out " + dir + "/bad.exr --ground 1e30", "--ground"},  // render refused it
        {"sky latlong " + sky + " --out " + dir + "/bad.png", "bad.png"}};
    std::vector<std::future<test::CommandResult>> runs;
    for (const auto& b : bad) runs.push_back(std::async(std::launch::async, [args = b.first] { return dynsky(args); }));
    for (size_t k = 0; k < bad.size(); ++k) {
        auto r = runs[k].get();
        EXPECT_NE(r.exit_code, 0) << bad[k].first << "\n" << r.output;
        EXPECT_TRUE(contains(r.output, bad[k].second)) << bad[k].first << "\n" << r.output;
    }
    EXPECT_FALSE(fs::exists(dir + "/bad.exr"));
    EXPECT_FALSE(fs::exists(dir + "/bad.png"));
    fs::remove_all(dir);
}

// Without a place and time, the sky every other command makes (sky/default_sky.h: Paris,
// 2026-06-21T16:00Z), as `render --sky clear` does; they were required here alone.
TEST(SkyClearCli, PlaceAndTimeDefaultAsEverywhereElse) {
    const std::string dir = test::temp_dir("sky_clear_default");
    auto r = dynsky("sky clear --sky-res 32 -q -o " + dir + "/default.exr");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    r = dynsky("sky clear --sky-res 32 --lat 48.8566 --lon 2.3522 --time 2026-06-21T16:00:00Z -q -o " + dir +
               "/given.exr");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const SkyImage a = load_sky(dir + "/default.exr"), b = load_sky(dir + "/given.exr");
    ASSERT_TRUE(a.sun_direction && b.sun_direction);
    EXPECT_LT((*a.sun_direction - *b.sun_direction).norm(), 1e-6f);
    EXPECT_EQ(a.time_seconds, b.time_seconds);
    EXPECT_EQ(a.rgb, b.rgb);
    r = dynsky("sky sun");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    fs::remove_all(dir);
}

TEST(SkyClearCli, HelpDescribesOptionsAndUnits) {
    auto r = dynsky("sky clear --help");
    EXPECT_EQ(r.exit_code, 0);
    for (const char* s : {"--lat", "--lon", "--time", "--turbidity", "--albedo", "--no-sun", "--sky-res", "--out",
                          "--preview", "W m^-2 sr^-1", "EAST positive"})
        EXPECT_TRUE(contains(r.output, s)) << s << "\n" << r.output;
    r = dynsky("sky latlong --help");
    EXPECT_EQ(r.exit_code, 0);
    for (const char* s : {"--width", "--ground", "Blender", "zenith"}) EXPECT_TRUE(contains(r.output, s)) << s;
    r = dynsky("sky sun --help");
    EXPECT_EQ(r.exit_code, 0);
    EXPECT_TRUE(contains(r.output, "--no-refraction"));
}

}  // namespace
}  // namespace dynsky
