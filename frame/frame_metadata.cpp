#include "frame/frame_metadata.h"

namespace dynsky {

void FrameMetadata::write_to(ImageMetadata* m) const {
    m->numbers["dynsky:frame"] = frame;
    m->numbers["dynsky:time"] = time_seconds;
    m->numbers["dynsky:fps"] = fps;
    m->numbers["dynsky:spp"] = spp;
    m->numbers["dynsky:seed"] = double(seed);
    m->numbers["dynsky:sky_seconds"] = sky_seconds;
    m->numbers["dynsky:sky_distribution_seconds"] = distribution_seconds;
    m->numbers["dynsky:render_seconds"] = render_seconds;
    m->numbers["dynsky:medium_step_seconds"] = medium_step_seconds;
    m->numbers["dynsky:png_exposure_ev"] = png_exposure_ev;
    m->strings["dynsky:sky"] = sky;
    m->strings["dynsky:sky_model"] = sky_model;
    m->strings["dynsky:gamma"] = gamma;
    m->strings["dynsky:scene"] = scene;
    m->strings["dynsky:camera"] = camera;
}

}  // namespace dynsky
