// The folder of an animation (glossary: "frame store"): what each frame's files are called, when a
// frame counts as done, and which frames a run renders (--frames A-B).
//
// Frame k consists of frame_NNNN.exr (linear radiance with its metadata, frame/frame_metadata.h),
// frame_NNNN.png (display) and sky_NNNN.png (the sky it was lit by). Every file is written
// atomically (util/image.h), so a file under its final name is complete; a frame counts as done
// when all three exist.
#pragma once

#include <string>

namespace dynsky {

class FrameStore {
  public:
    explicit FrameStore(std::string folder) : folder_(std::move(folder)) {}
    const std::string& folder() const { return folder_; }

    std::string frame_exr(int k) const;
    std::string frame_png(int k) const;
    std::string sky_png(int k) const;
    std::string file(const std::string& name) const;  // another file of the folder

    bool is_complete(int k) const;
    bool all_complete(int total) const;  // frames 0 .. total - 1

  private:
    std::string folder_;
};

// Inclusive frame range from "A-B" or "A" (numbered from 0) for an animation of `total` frames;
// "" is every frame. Throws dynsky::Error naming --frames.
void parse_frame_range(const std::string& text, int total, int* first, int* last);

}  // namespace dynsky
