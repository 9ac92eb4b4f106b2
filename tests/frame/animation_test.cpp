// The frame stage in-process (frame/animation.h, frame/frame_store.h): frame ranges rendered apart
// equal one run, a resumed run keeps complete frames and renders only the missing ones, and the
// frame store's names and completeness rule (whole files, the run's size and settings).
#include "frame/animation.h"

#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "frame/frame_metadata.h"
#include "frame/frame_store.h"
#include "frame/video.h"
#include "tests/test_support.h"
#include "util/error.h"
#include "util/image.h"

namespace dynsky {
namespace {

namespace fs = std::filesystem;

// 4 frames at 4 fps, Delta t 0.5 s: a medium-step boundary and Gamma's keys in between.
AnimationSettings small_animation(const std::string& out) {
    AnimationSettings a;
    a.scene.scene = "builtin";
    a.sky.sky = "procedural:3";
    a.sky.sky_resolution = 64;
    a.model.model = "procedural";
    a.model.dt = 0.5;
    a.duration = 1.0, a.fps = 4.0;
    a.width = 32, a.height = 18, a.spp = 1, a.max_depth = 3;
    a.out = out;
    a.no_video = true, a.quiet = true;
    return a;
}

bool complete(const FrameStore& store, int k, const std::string& settings) {
    return store.check(k, 32, 18, settings).state == FrameCheck::Complete;
}

void expect_same_frames(const FrameStore& a, const FrameStore& b, int count, const std::string& settings) {
    for (int k = 0; k < count; ++k) {
        ASSERT_TRUE(complete(a, k, settings)) << a.frame_exr(k);
        ASSERT_TRUE(complete(b, k, settings)) << b.frame_exr(k);
        Image ia = read_image(a.frame_exr(k)), ib = read_image(b.frame_exr(k));
        EXPECT_TRUE(ia.pixels == ib.pixels) << "frame " << k << " differs";
        EXPECT_EQ(ia.metadata.numbers["dynsky:frame"], k);
        EXPECT_DOUBLE_EQ(ia.metadata.numbers["dynsky:time"], k / 4.0);
    }
}

TEST(Animation, FrameRangesRenderedApartEqualOneRun) {
    const std::string dir = test::temp_dir("frame_ranges");
    AnimationReport whole = render_animation(small_animation(dir + "/whole"));
    EXPECT_EQ(whole.total, 4);
    EXPECT_EQ(whole.rendered, 4);
    EXPECT_TRUE(whole.complete);
    EXPECT_TRUE(fs::exists(dir + "/whole/contact_sheet.png"));

    AnimationSettings part = small_animation(dir + "/parts");
    part.frames = "2-3";  // the later frames first: the medium steps are still computed from step 0
    AnimationReport late = render_animation(part);
    EXPECT_EQ(late.first, 2);
    EXPECT_EQ(late.rendered, 2);
    EXPECT_FALSE(late.complete);
    EXPECT_FALSE(fs::exists(dir + "/parts/contact_sheet.png"));
    part.frames = "0-1";
    AnimationReport early = render_animation(part);
    EXPECT_TRUE(early.complete);
    EXPECT_EQ(early.settings, whole.settings);
    expect_same_frames(FrameStore(dir + "/whole"), FrameStore(dir + "/parts"), 4, whole.settings);
    fs::remove_all(dir);
}

std::string file_bytes(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    EXPECT_TRUE(f.good()) << path;
    return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

// The render farm's path (docs/render-farm.md): keys stored once, frame ranges rendered from them
// as separate tasks in any order, then encoded: every file equals one single run's, byte for byte.
TEST(Animation, FrameRangesFromAStoredTimelineEqualOneRunByteForByte) {
    for (const char* gamma : {"constant", "paper"}) {
        SCOPED_TRACE(gamma);
        const std::string dir = test::temp_dir(std::string("frame_farm_") + gamma);
        AnimationSettings one = small_animation(dir + "/one");
        one.model.gamma = gamma;
        one.duration = 1.5, one.fps = 4.0;  // 6 frames, steps 0-3: two whole intervals and one part
        AnimationReport whole = render_animation(one);
        ASSERT_TRUE(whole.complete);

        AnimationSettings farm = one;
        farm.out = dir + "/farm";
        farm.timeline = dir + "/farm/timeline";
        farm.stage = "keys";
        render_animation(farm);
        ASSERT_TRUE(fs::exists(farm.timeline + "/timeline.json"));
        EXPECT_TRUE(fs::exists(farm.timeline + "/step_0003.exr"));
        EXPECT_FALSE(fs::exists(farm.timeline + "/step_0004.exr"));
        farm.stage = "frames";
        for (const char* range : {"3-5", "0-2"}) {
            farm.frames = range;
            AnimationReport r = render_animation(farm);
            EXPECT_EQ(r.rendered, 3);
            EXPECT_EQ(r.settings, whole.settings);
        }
        // No task writes another's file, nor what the encode stage writes.
        EXPECT_TRUE(fs::exists(dir + "/farm/timings_0-2.csv"));
        EXPECT_TRUE(fs::exists(dir + "/farm/timings_3-5.csv"));
        EXPECT_FALSE(fs::exists(dir + "/farm/timings.csv"));
        EXPECT_FALSE(fs::exists(dir + "/farm/contact_sheet.png"));
        farm.stage = "encode";
        farm.frames = "";
        EXPECT_TRUE(render_animation(farm).complete);

        const FrameStore a(one.out), b(farm.out);
        for (int k = 0; k < 6; ++k)
            for (const std::string& f : {a.frame_exr(k), a.frame_png(k), a.sky_png(k)}) {
                const std::string g = b.file(fs::path(f).filename().string());
                EXPECT_TRUE(file_bytes(f) == file_bytes(g)) << f << " and " << g << " differ";
            }
        EXPECT_TRUE(file_bytes(a.file("contact_sheet.png")) == file_bytes(b.file("contact_sheet.png")));
        fs::remove_all(dir);
    }
}

TEST(Animation, StoredTimelineOfOtherSettingsOrTooShortIsRefused) {
    const std::string dir = test::temp_dir("frame_farm_refused");
    AnimationSettings a = small_animation(dir + "/frames");
    a.timeline = dir + "/timeline";
    a.stage = "keys";
    render_animation(a);
    a.stage = "frames";
    AnimationSettings other = a;
    other.sky.coverage = 0.7;
    try {
        render_animation(other);
        FAIL() << "a timeline of other settings was used";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("coverage"), std::string::npos) << e.what();
    }
    AnimationSettings longer = a;
    longer.duration = 3.0;  // frames up to t = 2.75 s; the timeline ends at 1 s
    longer.frames = "8-11";
    EXPECT_THROW(render_animation(longer), Error);
    // Encoding before every frame exists names the missing ones.
    a.frames = "0-1";
    render_animation(a);
    a.stage = "encode", a.frames = "";
    try {
        render_animation(a);
        FAIL() << "encoded an incomplete animation";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("2-3"), std::string::npos) << e.what();
    }
    fs::remove_all(dir);
}

TEST(Animation, ResumeKeepsCompleteFramesAndRendersTheRest) {
    const std::string dir = test::temp_dir("frame_resume");
    const FrameStore whole(dir + "/whole"), resumed(dir + "/resumed");
    const std::string settings = render_animation(small_animation(whole.folder())).settings;
    AnimationSettings a = small_animation(resumed.folder());
    render_animation(a);
    // Frame 1 loses a file (as if killed between its writes): it is no longer complete.
    fs::remove(resumed.sky_png(1));
    EXPECT_EQ(resumed.check(1, 32, 18, settings).state, FrameCheck::Damaged);
    AnimationReport r = render_animation(a);
    EXPECT_EQ(r.rendered, 1);
    EXPECT_EQ(r.skipped, 3);
    EXPECT_EQ(r.replaced, 1);
    EXPECT_TRUE(r.complete);
    expect_same_frames(whole, resumed, 4, settings);
    fs::remove_all(dir);
}

// The contact sheet's grid shows as many frames as a full grid can: 9 frames in 3 x 3 (rows of 4
// dropped one), 10 and 11 in rows of 5, never an empty cell.
TEST(ContactSheet, GridShowsTheMostFramesAFullGridCan) {
    const std::vector<std::array<int, 3>> expected = {{1, 1, 1},   {3, 3, 3},   {5, 5, 5},   {6, 6, 3},
                                                      {7, 6, 3},   {8, 8, 4},   {9, 9, 3},   {10, 10, 5},
                                                      {11, 10, 5}, {12, 12, 4}, {13, 12, 4}, {400, 12, 4}};
    for (const auto& [total, count, columns] : expected) {
        int n = 0, c = 0;
        contact_sheet_grid(total, &n, &c);
        EXPECT_EQ(n, count) << total << " frames";
        EXPECT_EQ(c, columns) << total << " frames";
        EXPECT_EQ(n % c, 0);
    }
}

// Labels a person reads at any duration (a day-long animation said "t = 1.44e+04 s").
TEST(ContactSheet, TimeLabelsReadAtAnyDuration) {
    EXPECT_EQ(frame_time_label(0), "0 s");
    EXPECT_EQ(frame_time_label(12.5), "12.5 s");
    EXPECT_EQ(frame_time_label(99), "99 s");
    EXPECT_EQ(frame_time_label(120), "2 min");
    EXPECT_EQ(frame_time_label(864), "14 min 24 s");
    EXPECT_EQ(frame_time_label(14400), "4 h");
    EXPECT_EQ(frame_time_label(82800 + 300), "23 h 05 min");
    EXPECT_EQ(frame_time_label(3600 + 330), "1 h 05 min 30 s");
    EXPECT_EQ(frame_time_label(86400 * 2), "48 h");
}

TEST(FrameStore, NamesAndCompleteness) {
    const std::string dir = test::temp_dir("frame_store");
    FrameStore store(dir);
    EXPECT_EQ(fs::path(store.frame_exr(7)).filename(), "frame_0007.exr");
    EXPECT_EQ(fs::path(store.frame_png(12345)).filename(), "frame_12345.png");
    EXPECT_EQ(fs::path(store.sky_png(0)).filename(), "sky_0000.png");
    const std::string settings = canonical_settings({{"spp", "2"}, {"res", "2x1"}});
    EXPECT_EQ(store.check(0, 2, 1, settings).state, FrameCheck::Missing);
    Image frame(2, 1, 3);
    FrameMetadata meta;
    meta.settings = settings;
    meta.write_to(&frame.metadata);
    write_image(store.frame_exr(0), frame);
    write_image(store.frame_png(0), frame);
    FrameCheck c = store.check(0, 2, 1, settings);
    EXPECT_EQ(c.state, FrameCheck::Damaged);  // the sky PNG is still missing
    EXPECT_NE(c.reason.find("sky_0000.png"), std::string::npos) << c.reason;
    write_image(store.sky_png(0), frame);
    EXPECT_EQ(store.check(0, 2, 1, settings).state, FrameCheck::Complete);
    // Another size, other settings: not this run's frame, and the check says what differs.
    EXPECT_EQ(store.check(0, 4, 2, settings).state, FrameCheck::OtherSettings);
    c = store.check(0, 2, 1, canonical_settings({{"spp", "8"}, {"res", "2x1"}}));
    EXPECT_EQ(c.state, FrameCheck::OtherSettings);
    EXPECT_EQ(c.reason, "spp 2 -> 8");
    // A file cut short or emptied under its final name (not our writer's doing, but a disk's) is damaged.
    std::string bytes;
    {
        std::ifstream f(store.frame_exr(0), std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
    }
    std::ofstream(store.frame_exr(0), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    c = store.check(0, 2, 1, settings);
    EXPECT_EQ(c.state, FrameCheck::Damaged);
    EXPECT_NE(c.reason.find("frame_0000.exr"), std::string::npos) << c.reason;
    std::ofstream(store.frame_exr(0), std::ios::binary | std::ios::trunc).flush();
    EXPECT_EQ(store.check(0, 2, 1, settings).state, FrameCheck::Damaged);
    fs::remove_all(dir);
}

TEST(FrameStore, SettingsAreCanonicalAndHashed) {
    FrameSettings a{{"spp", "2"}, {"model", "procedural"}}, b{{"model", "procedural"}, {"spp", "2"}};
    EXPECT_EQ(canonical_settings(a), "model=procedural\nspp=2\n");
    EXPECT_EQ(canonical_settings(a), canonical_settings(b));
    EXPECT_EQ(parse_settings(canonical_settings(a)), a);
    // FNV-1a 64 of "" and "a" (the published test vectors).
    EXPECT_EQ(settings_hash(""), "cbf29ce484222325");
    EXPECT_EQ(settings_hash("a"), "af63dc4c8601ec8c");
    EXPECT_NE(settings_hash(canonical_settings(a)), settings_hash(canonical_settings({{"spp", "4"}})));
    EXPECT_EQ(describe_settings_change(a, {{"spp", "4"}, {"model", "procedural"}, {"res", "8x8"}}),
              "res (default) -> 8x8, spp 2 -> 4");
}

TEST(FrameStore, FrameRanges) {
    int first = -1, last = -1;
    parse_frame_range("", 10, &first, &last);
    EXPECT_EQ(first, 0);
    EXPECT_EQ(last, 9);
    parse_frame_range("3-5", 10, &first, &last);
    EXPECT_EQ(first, 3);
    EXPECT_EQ(last, 5);
    parse_frame_range("7", 10, &first, &last);
    EXPECT_EQ(first, 7);
    EXPECT_EQ(last, 7);
    EXPECT_THROW(parse_frame_range("5-3", 10, &first, &last), Error);
    EXPECT_THROW(parse_frame_range("0-10", 10, &first, &last), Error);
    EXPECT_THROW(parse_frame_range("a-b", 10, &first, &last), Error);
    EXPECT_THROW(parse_frame_range("-1", 10, &first, &last), Error);
}

// --play-anim: a quad in front of a fixed glTF camera slides out of view over one second (its
// node's translation animated, LINEAR); played, frame 3 (t = 0.75 s) sees the sky where frame 0 saw
// the quad; not played, both see the quad; rendering frame 3 alone poses it the same.
// The end of the test scenes' glTF: node 0 slides along +x over a second (slide.bin: the quad, its
// indices, key times and translations), and where its data lie.
const char* const kSlideTail =
    R"("animations":[{"samplers":[{"input":2,"output":3}],"channels":[{"sampler":0,"target":{"node":0,"path":"translation"}}]}],
"buffers":[{"uri":"slide.bin","byteLength":92}],
"bufferViews":[{"buffer":0,"byteLength":48},{"buffer":0,"byteOffset":48,"byteLength":12},
{"buffer":0,"byteOffset":60,"byteLength":8},{"buffer":0,"byteOffset":68,"byteLength":24}],
"accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[-2,-2,0],"max":[2,2,0]},
{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"},
{"bufferView":2,"componentType":5126,"count":2,"type":"SCALAR","min":[0],"max":[1]},
{"bufferView":3,"componentType":5126,"count":2,"type":"VEC3"}]})";

TEST(Animation, PlayedSceneAnimationMovesTheScenePerFrame) {
    const std::string dir = test::temp_dir("play_anim");
    // Buffer: the quad (4 x VEC3, 48 bytes), its indices (6 x uint16, 12), key times (2 floats, 8),
    // translations (2 x VEC3, 24).
    const float data[] = {-2, -2, 0, 2, -2, 0, 2, 2, 0, -2, 2, 0};
    const uint16_t idx[] = {0, 1, 2, 0, 2, 3};
    const float times[] = {0, 1}, moves[] = {0, 0, 0, 10, 0, 0};
    std::string bin(reinterpret_cast<const char*>(data), sizeof data);
    bin.append(reinterpret_cast<const char*>(idx), sizeof idx);
    bin.append(reinterpret_cast<const char*>(times), sizeof times);
    bin.append(reinterpret_cast<const char*>(moves), sizeof moves);
    std::ofstream(dir + "/slide.bin", std::ios::binary) << bin;
    std::ofstream(dir + "/slide.gltf") << R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0,1]}],
"nodes":[{"mesh":0},{"camera":0,"translation":[0,0,4]}],
"cameras":[{"type":"perspective","perspective":{"yfov":0.6,"znear":0.1}}],
"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]}],
"materials":[{"pbrMetallicRoughness":{"baseColorFactor":[0.05,0.05,0.05,1],"metallicFactor":0}}],)"
                                       << kSlideTail;
    auto centre = [](const std::string& exr) {
        const Image im = read_image(exr);
        return im.at(im.width / 2, im.height / 2, 1);
    };
    AnimationSettings played = small_animation(dir + "/played");
    played.scene.scene = dir + "/slide.gltf";
    played.play_scene_animation = true;
    ASSERT_TRUE(render_animation(played).complete);
    AnimationSettings still = played;
    still.out = dir + "/still", still.play_scene_animation = false;
    ASSERT_TRUE(render_animation(still).complete);
    const FrameStore p(played.out), q(still.out);
    const float quad = centre(q.frame_exr(0)), sky = centre(p.frame_exr(3));
    EXPECT_NEAR(centre(p.frame_exr(0)), quad, 1e-6f) << "frame 0: the quad where it rests";
    EXPECT_GT(sky, 3 * quad) << "played: the quad has slid away, the sky shows";
    EXPECT_NEAR(centre(q.frame_exr(3)), quad, 0.2f * quad) << "not played: the quad stays";
    AnimationSettings alone = played;
    alone.out = dir + "/alone", alone.frames = "3";
    ASSERT_EQ(render_animation(alone).rendered, 1);
    EXPECT_TRUE(read_image(FrameStore(alone.out).frame_exr(3)).pixels == read_image(p.frame_exr(3)).pixels);

    // A key moved and exported again changes only the .bin: its frames are rendered again, not kept.
    const float back[] = {0, 0, 0, -10, 0, 0};
    std::ofstream(dir + "/slide.bin", std::ios::binary | std::ios::trunc)
        << bin.substr(0, 68) + std::string(reinterpret_cast<const char*>(back), sizeof back);
    EXPECT_EQ(render_animation(played).rendered, 4) << "the frames of the old .bin were kept";

    // Without a camera the view is framed once, on the first pose: a still, glowing quad keeps its
    // place and size while the other slides away (framed on every pose, it shrank to a ninth).
    std::ofstream(dir + "/nocam.gltf") << R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0,1]}],
"extensionsUsed":["KHR_materials_emissive_strength"],
"nodes":[{"mesh":0},{"mesh":1,"translation":[0,5,0]}],
"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]},
{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":1}]}],
"materials":[{"pbrMetallicRoughness":{"baseColorFactor":[0.05,0.05,0.05,1],"metallicFactor":0}},
{"emissiveFactor":[1,1,1],"extensions":{"KHR_materials_emissive_strength":{"emissiveStrength":1000}}}],)"
                                       << kSlideTail;
    AnimationSettings framed = played;
    framed.scene.scene = dir + "/nocam.gltf", framed.out = dir + "/nocam";
    ASSERT_TRUE(render_animation(framed).complete);
    auto glowing = [](const std::string& exr) {
        const Image im = read_image(exr);
        int count = 0;
        for (int y = 0; y < im.height; ++y)
            for (int x = 0; x < im.width; ++x) count += im.at(x, y, 1) > 100 && im.at(x, y, 1) < 1e5f;
        return count;
    };
    const FrameStore f(framed.out);
    ASSERT_GT(glowing(f.frame_exr(0)), 10);
    EXPECT_EQ(glowing(f.frame_exr(3)), glowing(f.frame_exr(0)));
    fs::remove_all(dir);
}

}  // namespace
}  // namespace dynsky
