#include "motion/procedural_step_model.h"

namespace dynsky {

SkyImage ProceduralStepModel::step(const std::vector<std::shared_ptr<const SkyImage>>& history, double dt) {
    const SkyImage& last = *history.back();
    SkyImage next = sky_.render(last.time_seconds + dt, last.resolution);
    next.time_seconds = last.time_seconds + dt;
    return next;
}

}  // namespace dynsky
