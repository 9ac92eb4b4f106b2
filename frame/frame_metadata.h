// What a rendered frame records about itself (glossary: "frame metadata"), stored as dynsky:*
// attributes of its EXR header (util/image.h ImageMetadata), so a frame file says how it was made.
#pragma once

#include <cstdint>
#include <string>

#include "util/image.h"

namespace dynsky {

struct FrameMetadata {
    int frame = 0;            // k, from 0
    double time_seconds = 0;  // t = k / fps, sky time since t = 0  (dynsky:time)
    double fps = 0;
    int spp = 0;
    uint64_t seed = 0;
    double sky_seconds = 0;           // Gamma + amortised xi for this frame
    double distribution_seconds = 0;  // the sky's sampling distribution rebuild
    double render_seconds = 0;
    double medium_step_seconds = 0;  // Delta t
    double png_exposure_ev = 0;
    std::string sky, sky_model, scene, camera;
    std::string gamma;  // the in-between: constant | paper (dynsky:gamma)

    void write_to(ImageMetadata* m) const;
};

}  // namespace dynsky
