// The frame stage in-process (frame/animation.h, frame/frame_store.h): frame ranges rendered apart
// equal one run, a resumed run keeps complete frames and renders only the missing ones, and the
// frame store's names and completeness rule.
#include "frame/animation.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "frame/frame_store.h"
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

void expect_same_frames(const FrameStore& a, const FrameStore& b, int count) {
    for (int k = 0; k < count; ++k) {
        ASSERT_TRUE(a.is_complete(k)) << a.frame_exr(k);
        ASSERT_TRUE(b.is_complete(k)) << b.frame_exr(k);
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
    expect_same_frames(FrameStore(dir + "/whole"), FrameStore(dir + "/parts"), 4);
    fs::remove_all(dir);
}

TEST(Animation, ResumeKeepsCompleteFramesAndRendersTheRest) {
    const std::string dir = test::temp_dir("frame_resume");
    const FrameStore whole(dir + "/whole"), resumed(dir + "/resumed");
    render_animation(small_animation(whole.folder()));
    AnimationSettings a = small_animation(resumed.folder());
    render_animation(a);
    // Frame 1 loses a file (as if killed between its writes): it is no longer complete.
    fs::remove(resumed.sky_png(1));
    EXPECT_FALSE(resumed.is_complete(1));
    AnimationReport r = render_animation(a);
    EXPECT_EQ(r.rendered, 1);
    EXPECT_EQ(r.skipped, 3);
    EXPECT_TRUE(r.complete);
    expect_same_frames(whole, resumed, 4);
    fs::remove_all(dir);
}

TEST(FrameStore, NamesAndCompleteness) {
    const std::string dir = test::temp_dir("frame_store");
    FrameStore store(dir);
    EXPECT_EQ(fs::path(store.frame_exr(7)).filename(), "frame_0007.exr");
    EXPECT_EQ(fs::path(store.frame_png(12345)).filename(), "frame_12345.png");
    EXPECT_EQ(fs::path(store.sky_png(0)).filename(), "sky_0000.png");
    EXPECT_FALSE(store.is_complete(0));
    Image tiny(1, 1, 3);
    write_image(store.frame_exr(0), tiny);
    write_image(store.frame_png(0), tiny);
    EXPECT_FALSE(store.is_complete(0));  // the sky PNG is still missing
    write_image(store.sky_png(0), tiny);
    EXPECT_TRUE(store.is_complete(0));
    EXPECT_TRUE(store.all_complete(1));
    EXPECT_FALSE(store.all_complete(2));
    fs::remove_all(dir);
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

}  // namespace
}  // namespace dynsky
