// End-to-end tests of `dynsky render`: bad input gives a clear error naming the file, a non-zero
// exit, and no output file; good input gives finite, non-black images.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "sky/sky_image.h"
#include "tests/test_support.h"
#include "util/error.h"
#include "util/image.h"

namespace dynsky {
namespace {

namespace fs = std::filesystem;

std::string exe() { return DYNSKY_EXE; }

// A small valid sky EXR.
std::string write_sky(const std::string& dir, const std::string& name, int w, int h, float value) {
    Image im(w, h, 3);
    for (auto& v : im.pixels) v = value;
    std::string path = dir + "/" + name;
    write_image(path, im);
    return path;
}

std::string box_glb() { return test::shared_path("scenes/Box/Box.glb"); }

struct Outcome {
    test::CommandResult result;
    bool output_exists;
};

Outcome render(const std::string& args, const std::string& out) {
    Outcome o;
    o.result = test::run_command(exe() + " render " + args + " --res 32x24 --spp 2 -q --out " + out);
    o.output_exists = fs::exists(out) || fs::exists(fs::path(out).replace_extension(".png"));
    return o;
}

void expect_clean_failure(const Outcome& o, const std::string& must_mention) {
    EXPECT_NE(o.result.exit_code, 0) << o.result.output;
    EXPECT_NE(o.result.output.find(must_mention), std::string::npos)
        << "message should name '" << must_mention << "':\n"
        << o.result.output;
    EXPECT_NE(o.result.output.find("error"), std::string::npos) << o.result.output;
    EXPECT_FALSE(o.output_exists) << "a failed render left an output file";
}

TEST(RenderCli, HelpDescribesEveryOption) {
    auto r = test::run_command(exe() + " render --help");
    EXPECT_EQ(r.exit_code, 0);
    for (const char* opt : {"--sky", "--spp", "--res", "--out", "--camera", "--seed", "--threads", "--ground-albedo"})
        EXPECT_NE(r.output.find(opt), std::string::npos) << opt;
}

// Options that shape only the skies made here, given with a sky file, are said to be ignored
// (they were ignored without a word); --sky-res takes the file at its size.
TEST(RenderCli, OptionsOfGeneratedSkiesWithASkyFileAreSaidToBeIgnored) {
    const std::string dir = test::temp_dir("render_ignored");
    ASSERT_EQ(test::run_command(exe() + " sky clear --lat 40 --lon 0 --time 2026-06-21T12:00:00Z --sky-res 16 -q -o " +
                                dir + "/s.exr")
                  .exit_code,
              0);
    auto r = test::run_command(exe() + " render builtin --sky " + dir + "/s.exr --sky-res 128 --res 8x6 --spp 1 -o " +
                               dir + "/r.exr");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(r.output.find("is ignored"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("(128x128)"), std::string::npos) << "the 16 px sky taken at 128: " << r.output;
    r = test::run_command(exe() + " animate builtin --sky " + dir + "/s.exr --coverage 0.9 --duration 1 --fps 1 " +
                          "--res 8x6 --spp 1 --no-video -q -o " + dir + "/a");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("--coverage is ignored"), std::string::npos) << r.output;
    r = test::run_command(exe() + " render builtin --sky clear --sky-res 16 --res 8x6 --spp 1 -q -o " + dir + "/c.exr");
    EXPECT_EQ(r.output.find("ignored"), std::string::npos) << r.output;
    fs::remove_all(dir);
}

TEST(RenderCli, MissingSceneFile) {
    std::string dir = test::temp_dir("render");
    expect_clean_failure(render(dir + "/nope.glb", dir + "/out.exr"), "nope.glb");
    // A relative name is looked for among the shipped scenes too: the message says where, and how
    // to name other data; a DYNSKY_DATA that is no folder is said to be ignored (it was silently).
    const Outcome relative = render("scenes/tower/towr.gltf", dir + "/out.exr");
    expect_clean_failure(relative, "scenes/tower/towr.gltf: no such file here, nor in dynsky's data (searched ");
    EXPECT_NE(relative.result.output.find("set DYNSKY_DATA"), std::string::npos) << relative.result.output;
    const auto r = test::run_command("DYNSKY_DATA=" + dir + "/no_data " + exe() + " sky clear --sky-res 16 -q -o " +
                                     dir + "/c.exr");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("warning: DYNSKY_DATA=" + dir + "/no_data is not a folder: it is ignored"),
              std::string::npos)
        << r.output;
    fs::remove_all(dir);
}

TEST(RenderCli, TruncatedGlb) {
    DYNSKY_REQUIRE_SHARED();
    std::string dir = test::temp_dir("render");
    std::ifstream in(box_glb(), std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    std::ofstream(dir + "/cut.glb", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    expect_clean_failure(render(dir + "/cut.glb", dir + "/out.exr"), "cut.glb");
}

TEST(RenderCli, InvalidJson) {
    std::string dir = test::temp_dir("render");
    std::ofstream(dir + "/bad.gltf") << "{ \"asset\": { \"version\": \"2.0\" }, \"nodes\": [ ";
    expect_clean_failure(render(dir + "/bad.gltf", dir + "/out.png"), "bad.gltf");
}

TEST(RenderCli, MissingTexture) {
    DYNSKY_REQUIRE_SHARED();
    std::string dir = test::temp_dir("render");
    // BoxTextured as .gltf with its image pointing at a file that is not there.
    std::string gltf = R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
      "meshes":[{"primitives":[{"attributes":{"POSITION":0,"TEXCOORD_0":1},"material":0}]}],
      "materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}],
      "textures":[{"source":0}],"images":[{"uri":"missing_texture.png"}],
      "buffers":[{"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAIA/AAAAAAAAgD8AAAAA","byteLength":60}],
      "bufferViews":[{"buffer":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":24}],
      "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},
                   {"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}]})";
    std::ofstream(dir + "/tex.gltf") << gltf;
    expect_clean_failure(render(dir + "/tex.gltf", dir + "/out.exr"), "missing_texture.png");
}

TEST(RenderCli, BadSkyPixelsAreRejected) {
    DYNSKY_REQUIRE_SHARED();
    std::string dir = test::temp_dir("render");
    struct Case {
        const char* name;
        float value;
        const char* says;
    } cases[] = {{"nan.exr", std::numeric_limits<float>::quiet_NaN(), "NaN"},
                 {"inf.exr", std::numeric_limits<float>::infinity(), "infinite"},
                 {"negative.exr", -1.0f, "negative"},
                 {"black.exr", 0.0f, "black"}};
    for (const Case& c : cases) {
        std::string sky = write_sky(dir, c.name, 16, 16, 1.0f);
        Image im = read_image(sky);
        if (std::string(c.name) == "black.exr")
            for (auto& v : im.pixels) v = 0;
        else im.at(8, 8, 1) = c.value;
        write_image(sky, im);
        Outcome o = render(box_glb() + " --sky " + sky, dir + "/out.exr");
        expect_clean_failure(o, c.name);
        EXPECT_NE(o.result.output.find(c.says), std::string::npos) << o.result.output;
    }
}

TEST(RenderCli, NonSquareSkyIsRejected) {
    DYNSKY_REQUIRE_SHARED();
    std::string dir = test::temp_dir("render");
    std::string sky = write_sky(dir, "wide.exr", 32, 20, 1.0f);  // neither square nor a 2:1 lat-long
    Outcome o = render(box_glb() + " --sky " + sky, dir + "/out.exr");
    expect_clean_failure(o, "wide.exr");
    EXPECT_NE(o.result.output.find("square"), std::string::npos) << o.result.output;
}

TEST(RenderCli, SkyThatIsNotAnImage) {
    DYNSKY_REQUIRE_SHARED();
    std::string dir = test::temp_dir("render");
    std::ofstream(dir + "/sky.exr") << "plain text, not OpenEXR";
    expect_clean_failure(render(box_glb() + " --sky " + dir + "/sky.exr", dir + "/out.exr"), "sky.exr");
}

TEST(RenderCli, BadArgumentsFailBeforeRendering) {
    std::string dir = test::temp_dir("render");
    expect_clean_failure(render("builtin --camera 7", dir + "/out.exr"), "camera");
    auto r = test::run_command(exe() + " render builtin --res 12by7 -q --out " + dir + "/o.exr");
    EXPECT_NE(r.exit_code, 0);
    EXPECT_NE(r.output.find("12by7"), std::string::npos) << r.output;
    r = test::run_command(exe() + " render builtin --res 8x8 -q --out " + dir + "/o.tiff");
    EXPECT_NE(r.exit_code, 0);
    EXPECT_TRUE(fs::is_empty(dir));
}

// --lat and --lon without --sky make the clear sky there, as --time does: the built-in Paris sky
// ignored them without a word. With a time: the same image as --sky clear at that place and time.
TEST(RenderCli, APlaceWithoutASkyMakesTheClearSkyThere) {
    const std::string dir = test::temp_dir("render_place");
    const std::string place = " --lat -33.9 --lon 151.2 --time 2026-06-21T12:00:00+10:00";
    Outcome a = render("builtin" + place, dir + "/a.exr");
    Outcome b = render("builtin --sky clear" + place, dir + "/b.exr");
    Outcome paris = render("builtin", dir + "/paris.exr");
    Outcome sydney = render("builtin --lat -33.9 --lon 151.2", dir + "/sydney.exr");
    for (const Outcome* o : {&a, &b, &paris, &sydney}) ASSERT_EQ(o->result.exit_code, 0) << o->result.output;
    const Image ia = read_image(dir + "/a.exr"), ib = read_image(dir + "/b.exr");
    EXPECT_EQ(ia.pixels, ib.pixels);
    EXPECT_NE(read_image(dir + "/paris.exr").pixels, read_image(dir + "/sydney.exr").pixels);
    // --sky-res sizes the built-in sky too (it stayed 1024 without a word): its report says so.
    test::CommandResult small = test::run_command(exe() + " render builtin --sky-res 32 --res 16x9 --spp 1 --out " +
                                                  dir + "/small.exr");
    ASSERT_EQ(small.exit_code, 0) << small.output;
    EXPECT_NE(small.output.find("(32x32)"), std::string::npos) << small.output;
    fs::remove_all(dir);
}

// A file's camera framing another aspect than the image (glTF aspectRatio, xmag / ymag) had it
// silently ignored: the image showed 3.6 m across where the file's camera frames 2 m. Its vertical
// extent is still kept (as viewers do), now with a warning naming the size that frames it as the file
// does; none where the aspects agree.
TEST(RenderCli, ACameraOfAnotherAspectIsToldWithTheSizeThatFramesIt) {
    DYNSKY_REQUIRE_SHARED();
    const std::string dir = test::temp_dir("render_aspect");
    const std::string scene = test::shared_path("scenes/Cameras/Cameras.gltf");
    for (const char* camera : {"0", "1"}) {  // perspective aspectRatio 1, orthographic xmag = ymag
        auto r = test::run_command(exe() + " render " + scene + " --camera " + camera + " --res 32x18 --spp 1 --out " +
                                   dir + "/wide.exr 2>&1");
        ASSERT_EQ(r.exit_code, 0) << r.output;
        EXPECT_NE(r.output.find("frames an aspect of 1 "), std::string::npos) << camera << "\n" << r.output;
        EXPECT_NE(r.output.find("--res 960x960"), std::string::npos) << r.output;
        r = test::run_command(exe() + " render " + scene + " --camera " + camera + " --res 24x24 --spp 1 --out " + dir +
                              "/square.exr 2>&1");
        ASSERT_EQ(r.exit_code, 0) << r.output;
        EXPECT_EQ(r.output.find("frames an aspect"), std::string::npos) << r.output;
    }
    fs::remove_all(dir);
}

TEST(RenderCli, WritesExrWithMetadataAndPng) {
    std::string dir = test::temp_dir("render");
    Outcome o = render("builtin --seed 5", dir + "/plaza.exr");
    ASSERT_EQ(o.result.exit_code, 0) << o.result.output;
    Image im = read_image(dir + "/plaza.exr");
    EXPECT_EQ(im.width, 32);
    EXPECT_EQ(im.metadata.numbers["dynsky:spp"], 2);
    EXPECT_EQ(im.metadata.numbers["dynsky:spp_mean"], 2);  // what was taken (the cap above)
    EXPECT_EQ(im.metadata.numbers["dynsky:seed"], 5);
    EXPECT_GT(im.metadata.numbers["dynsky:render_seconds"], 0);
    EXPECT_FALSE(im.metadata.strings["dynsky:sky"].empty());
    EXPECT_TRUE(fs::exists(dir + "/plaza.png"));
    // Everything that changes the image is in its header, to render it again from there.
    Outcome more = render(
        "builtin --max-depth 2 --override-material lambert --sampler uniform --look-at 0,1,3,0,0,0 "
        "--fov 33 --seed 18446744073709551615 --time-limit 600 --sky clear --time 2026-03-01T09:00:00Z --lat 10 "
        "--lon 20",
        dir + "/more.exr");
    ASSERT_EQ(more.result.exit_code, 0) << more.result.output;
    Image m = read_image(dir + "/more.exr");
    EXPECT_EQ(m.metadata.numbers["dynsky:max_depth"], 2);
    EXPECT_EQ(m.metadata.strings["dynsky:override_material"], "lambert");
    EXPECT_EQ(m.metadata.strings["dynsky:sky_sampler"], "uniform");
    EXPECT_EQ(m.metadata.strings["dynsky:look_at"], "0,1,3,0,0,0");
    EXPECT_NEAR(m.metadata.numbers["dynsky:camera_yfov_deg"], 33, 1e-4);
    // The seed exactly (a double holds 53 bits: animate --seed-per-frame's seeds reach 2^64 - 1),
    // the time limit, and the sky made here with its time and place.
    EXPECT_EQ(m.metadata.strings["dynsky:seed_exact"], "18446744073709551615");
    EXPECT_EQ(m.metadata.numbers["dynsky:time_limit_seconds"], 600);
    EXPECT_NE(m.metadata.strings["dynsky:sky"].find("at 2026-03-01T09:00:00Z, 10 N 20 E"), std::string::npos)
        << m.metadata.strings["dynsky:sky"];
    EXPECT_EQ(im.metadata.strings.count("dynsky:override_material"), 0u);  // none: not said
    EXPECT_EQ(im.metadata.strings["dynsky:sky_sampler"], "cdf+mis");
    // Lit by a sky in W m^-2 sr^-1, the image is radiance in them; under a sky of no stated units
    // (an HDRI) it says none. Its PNG says its exposure (PNGs dropped numbers) and no units.
    EXPECT_EQ(m.metadata.strings["dynsky:units"], "W m^-2 sr^-1");
    const auto png = image_header_strings(dir + "/more.png", {"dynsky:png_exposure_ev", "dynsky:units"});
    EXPECT_EQ(float(std::stod(png[0])), float(m.metadata.numbers["dynsky:png_exposure_ev"]));  // a float's text
    // Its header holds no timings: two runs of one render give the same PNG.
    Outcome again = render("builtin --seed 5", dir + "/again.exr");
    ASSERT_EQ(again.result.exit_code, 0) << again.result.output;
    EXPECT_EQ(test::read_text(dir + "/again.png"), test::read_text(dir + "/plaza.png"));
    EXPECT_EQ(png[1], "");
    Outcome hdri = render("builtin --sky " + write_sky(dir, "hdri.exr", 16, 16, 1.0f), dir + "/h.exr");
    ASSERT_EQ(hdri.result.exit_code, 0) << hdri.result.output;
    EXPECT_EQ(read_image(dir + "/h.exr").metadata.strings.count("dynsky:units"), 0u);
}

// A 2:1 image is a lat-long environment: its upper half lights the scene, its lower half is the ground.
TEST(RenderCli, LatlongSkyIsConvertedAndItsGroundUsed) {
    std::string dir = test::temp_dir("render");
    Image latlong(64, 32, 3);
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 64; ++x)
            for (int c = 0; c < 3; ++c) latlong.at(x, y, c) = y < 16 ? 2.0f : 0.5f;
    write_image(dir + "/hdri.exr", latlong);
    // A camera in the air 5 km from the plaza (60 m across), looking straight up, then straight down.
    Outcome up = render("builtin --sky " + dir + "/hdri.exr --look-at 5000,500,0,5000,600,0 --fov 20", dir + "/up.exr");
    ASSERT_EQ(up.result.exit_code, 0) << up.result.output;
    Outcome down = render("builtin --sky " + dir + "/hdri.exr --look-at 5000,500,0,5000,400,0 --fov 20",
                          dir + "/down.exr");
    ASSERT_EQ(down.result.exit_code, 0) << down.result.output;
    Image a = read_image(dir + "/up.exr"), b = read_image(dir + "/down.exr");
    EXPECT_NEAR(a.at(16, 12, 1), 2.0f, 1e-3f);  // the sky half
    EXPECT_NEAR(b.at(16, 12, 1), 0.5f, 1e-3f);  // the ground half, not the ground model
    EXPECT_NE(a.metadata.strings["dynsky:sky"].find("latlong"), std::string::npos);
    // Which file lit it, and which build rendered it: a sky file's own source names what made it,
    // not the file (two skies of one procedural sequence had identical headers).
    EXPECT_EQ(a.metadata.strings["dynsky:sky_file"], fs::absolute(dir + "/hdri.exr").lexically_normal().string());
    EXPECT_NE(a.metadata.strings["dynsky:sky_file_contents"].find("hdri.exr (" +
                                                                  std::to_string(fs::file_size(dir + "/hdri.exr")) +
                                                                  " bytes, fnv1a "),
              std::string::npos)
        << a.metadata.strings["dynsky:sky_file_contents"];
    EXPECT_EQ(a.metadata.strings["Software"].rfind("dynsky 0.", 0), 0u) << a.metadata.strings["Software"];
    EXPECT_EQ(a.metadata.strings.count("dynsky:scene_file"), 0u);  // the built-in scene is no file
}

// --sky-turn turns a sky file about the zenith (a lat-long exactly: the same image as the file rolled
// by hand, its ground too), and is refused for a sky made here, whose sun --time places.
TEST(RenderCli, SkyTurnTurnsASkyFile) {
    std::string dir = test::temp_dir("render_turn");
    Image ll(64, 32, 3), rolled(64, 32, 3);
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 64; ++x)
            for (int c = 0; c < 3; ++c) {
                const float v = 0.5f + float(x % 13) * (y < 16 ? 0.3f : 0.1f) + 0.1f * c;
                ll.at(x, y, c) = v, rolled.at((x + 16) % 64, y, c) = v;  // a quarter turn: 16 columns right
            }
    write_image(dir + "/ll.exr", ll);
    write_image(dir + "/rolled.exr", rolled);
    Outcome a = render("builtin --sky " + dir + "/ll.exr --sky-turn 90", dir + "/a.exr");
    Outcome b = render("builtin --sky " + dir + "/rolled.exr", dir + "/b.exr");
    Outcome c = render("builtin --sky " + dir + "/ll.exr", dir + "/c.exr");
    ASSERT_EQ(a.result.exit_code, 0) << a.result.output;
    ASSERT_EQ(b.result.exit_code, 0) << b.result.output;
    ASSERT_EQ(c.result.exit_code, 0) << c.result.output;
    EXPECT_EQ(read_image(dir + "/a.exr").pixels, read_image(dir + "/b.exr").pixels);
    EXPECT_NE(read_image(dir + "/a.exr").pixels, read_image(dir + "/c.exr").pixels);
    Outcome refused = render("builtin --sky clear --sky-turn 90", dir + "/d.exr");
    EXPECT_NE(refused.result.exit_code, 0);
    EXPECT_NE(refused.result.output.find("--sky-turn turns a sky file"), std::string::npos) << refused.result.output;
    EXPECT_FALSE(fs::exists(dir + "/d.exr"));
    fs::remove_all(dir);
}

TEST(RenderCli, AovsRegionAndCameraOptions) {
    std::string dir = test::temp_dir("render");
    Outcome o = render("builtin --aovs albedo,normal,depth,alpha,samples --region 4,2,20,14", dir + "/aov.exr");
    ASSERT_EQ(o.result.exit_code, 0) << o.result.output;
    // The region's pixels, placed in the full image as compositors expect (data window (4, 2)-(19, 13)
    // of a display window of the whole --res image), and refused where a whole image is needed.
    Image im = read_image(dir + "/aov.exr", DataWindow::PartAllowed);
    EXPECT_EQ(im.width, 16);
    EXPECT_EQ(im.height, 12);
    EXPECT_EQ(im.origin_x, 4);
    EXPECT_EQ(im.origin_y, 2);
    EXPECT_GT(im.full_width, 20);
    EXPECT_GT(im.full_height, 14);
    EXPECT_THROW(read_image(dir + "/aov.exr"), dynsky::Error);
    for (const char* name : {"R", "G", "B", "A", "Denoising Albedo.R", "Normal.Z", "Depth.Z", "Sample Count.X"})
        EXPECT_GE(im.channel_index(name), 0) << name;
    EXPECT_EQ(im.metadata.strings["dynsky:region"], "4,2,20,14");
    // Bad values: clear errors, no output.
    expect_clean_failure(render("builtin --aovs albedo,shadow", dir + "/a.exr"), "shadow");
    expect_clean_failure(render("builtin --region 0,0,33,10", dir + "/b.exr"), "--region");
    expect_clean_failure(render("builtin --look-at 1,2,3,1,2,3", dir + "/c.exr"), "same point");
    expect_clean_failure(render("builtin --fov 200", dir + "/d.exr"), "--fov");
    // The same range as animate and compare (one registration): a vanishing field of view is refused.
    expect_clean_failure(render("builtin --fov 1e-308", dir + "/d.exr"), "0.01");
    expect_clean_failure(render("builtin --aovs depth", dir + "/e.png"), "--aovs");
    expect_clean_failure(render("builtin --noise-threshold -1", dir + "/f.exr"), "--noise-threshold");
    expect_clean_failure(render("builtin --sampler-pattern halton", dir + "/h.exr"), "halton");
    Outcome sobol = render("builtin --sampler-pattern sobol --clamp-indirect 10 --filter-glossy 1", dir + "/s.exr");
    ASSERT_EQ(sobol.result.exit_code, 0) << sobol.result.output;
    EXPECT_EQ(read_image(dir + "/s.exr").metadata.strings["dynsky:sampler_pattern"], "sobol");
    auto r = test::run_command(exe() + " render builtin --look-at 1,2,3 -q --out " + dir + "/g.exr");
    EXPECT_NE(r.exit_code, 0);
    EXPECT_FALSE(fs::exists(dir + "/g.exr"));
}

// A camera inside a closed box sees nothing lit: render, animate and compare all write their
// outputs (that is what the scene shows) and say so (animate and compare were silent).
TEST(RenderCli, ACameraInsideClosedGeometryIsToldInEveryCommand) {
    DYNSKY_REQUIRE_SHARED();
    std::string dir = test::temp_dir("render");
    const std::string inside = " '" + box_glb() + "' --look-at 0,0,0,1,0,0 --sky-res 64 -q ";
    auto r = test::run_command(exe() + " render" + inside + "--res 16x12 --spp 1 -o " + dir + "/r.exr");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("the image is black everywhere: is the camera inside closed geometry"), std::string::npos)
        << r.output;
    r = test::run_command(exe() + " animate" + inside + "--res 16x12 --spp 1 --duration 1 --fps 2 --no-video -o " +
                          dir + "/a");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("frame 0 is black everywhere"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("frame 1 is black"), std::string::npos) << "said once: " << r.output;
    r = test::run_command(exe() + " compare" + inside + "--res 16x12 --spp 1 --chart-frames 2 --chart-res 8x6 -o " +
                          dir + "/c");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("the clear and the cloudy image are black"), std::string::npos) << r.output;
    // Outside the box it is lit, and nothing is said.
    r = test::run_command(exe() + " render '" + box_glb() + "' --sky-res 64 -q --res 16x12 --spp 1 -o " + dir +
                          "/lit.exr");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(r.output.find("black"), std::string::npos) << r.output;
    // Black for --max-depth 0 (a box lit only by the sky, which the camera does not see): that is said.
    r = test::run_command(exe() + " render '" + box_glb() + "' --sky-res 64 -q --res 16x12 --spp 1 --max-depth 0 " +
                          "--look-at 0,0,-3,0,0,0 --fov 8 -o " + dir + "/depth0.exr");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("--max-depth 0 shows only emitters"), std::string::npos) << r.output;
    fs::remove_all(dir);
}

// Every scene in ../shared/scenes renders to a finite, non-black image.
TEST(RenderCli, EverySharedSceneRendersFiniteAndNotBlack) {
    DYNSKY_REQUIRE_SHARED();
    std::string dir = test::temp_dir("render");
    std::vector<std::string> scenes;
    for (auto& e : fs::recursive_directory_iterator(test::shared_path("scenes"))) {
        std::string ext = e.path().extension().string();
        if ((ext == ".glb" || ext == ".gltf") && e.path().string().find("/reference/") == std::string::npos)
            scenes.push_back(e.path().string());
    }
    ASSERT_GE(scenes.size(), 16u);
    for (const std::string& scene : scenes) {
        std::string out = dir + "/" + fs::path(scene).stem().string() + ".exr";
        auto r = test::run_command(exe() + " render '" + scene + "' --res 24x16 --spp 2 -q --out " + out);
        ASSERT_EQ(r.exit_code, 0) << scene << "\n" << r.output;
        Image im = read_image(out);
        double sum = 0;
        for (float v : im.pixels) {
            ASSERT_TRUE(std::isfinite(v)) << scene;
            sum += v;
        }
        EXPECT_GT(sum, 0) << scene << " rendered black";
    }
}

}  // namespace
}  // namespace dynsky
