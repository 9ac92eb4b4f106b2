// The folder of an animation (glossary: "frame store"): what each frame's files are called, when a
// frame counts as done, and which frames a run renders (--frames A-B).
//
// Frame k consists of frame_NNNN.exr (linear radiance with its metadata, frame/frame_metadata.h),
// frame_NNNN.png (display) and sky_NNNN.png (the sky it was lit by). Every file is written
// atomically (util/atomic_file.h), so a file under its final name was complete when written. A
// frame counts as done only when all three read back whole at the run's frame size and its EXR
// records the run's settings (frame/frame_metadata.h FrameSettings): a damaged file or a frame made
// with other settings is rendered again, and the reason is said.
#pragma once

#include <string>

namespace dynsky {

struct FrameCheck {
    enum State { Missing, Damaged, OtherSettings, Complete } state = Missing;
    std::string reason;  // for Damaged and OtherSettings: which file and what is wrong / which settings differ
};

class FrameStore {
  public:
    // `count`: the animation's frames (names are padded to its largest number; util/frame_names.h).
    explicit FrameStore(std::string folder, int count = 0) : folder_(std::move(folder)), count_(count) {}
    const std::string& folder() const { return folder_; }

    std::string frame_exr(int k) const;
    std::string frame_png(int k) const;
    std::string sky_png(int k) const;
    std::string file(const std::string& name) const;  // another file of the folder

    // Whether frame k is there, whole (all three files decode; the frame is width x height) and made
    // with `settings` (canonical_settings of this run).
    FrameCheck check(int k, int width, int height, const std::string& settings) const;

  private:
    std::string folder_;
    int count_ = 0;
};

// Inclusive frame range from "A-B" or "A" (numbered from 0) for an animation of `total` frames;
// "" is every frame. Throws dynsky::Error naming --frames.
void parse_frame_range(const std::string& text, int total, int* first, int* last);

}  // namespace dynsky
