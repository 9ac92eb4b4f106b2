// Step model "procedural": the procedural sky's own next frame (sky/procedural_clouds.h), i.e. the
// ground-truth motion of a procedural input. It renders its own sun, following the clock.
//
// Parameters (defaults): those of ProceduralSkyParams (sky/procedural_clouds.h).
#pragma once

#include "motion/step_model.h"
#include "sky/procedural_clouds.h"

namespace dynsky {

class ProceduralStepModel : public MediumStepModel {
  public:
    explicit ProceduralStepModel(const ProceduralSkyParams& params) : sky_(params) {}
    SkyImage step(const std::vector<std::shared_ptr<const SkyImage>>& history, double dt) override;
    std::string name() const override { return "procedural"; }
    bool makes_own_sun() const override { return true; }
    void set_sun_direction(const Vec3d& d) override { sky_.set_sun_direction(d); }
    ProceduralSky& sky() { return sky_; }

  private:
    ProceduralSky sky_;
};

}  // namespace dynsky
