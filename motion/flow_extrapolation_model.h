// Step model "flow": flow extrapolation. The Farneback flow of the last two steps (motion/flow.h,
// estimate_sky_flow), applied once more along great arcs (motion/advection.h). From a single input
// sky there is no motion to measure yet: the first step drifts the sky by a uniform wind aloft, a
// rotation about a horizontal axis.
//
// Parameters (defaults):
//   wind_from_deg        270    where the first step's drift comes from, degrees clockwise from north
//   degrees_per_second   0.25   the first step's angular speed of the cloud field overhead
//   flow_params          SkyFlowParams{}  the Farneback estimate of later steps
#pragma once

#include "motion/flow.h"
#include "motion/step_model.h"

namespace dynsky {

class FlowExtrapolationStepModel : public MediumStepModel {
  public:
    FlowExtrapolationStepModel(double wind_from_deg = 270.0, double degrees_per_second = 0.25,
                               SkyFlowParams flow_params = {});
    SkyImage step(const std::vector<std::shared_ptr<const SkyImage>>& history, double dt) override;
    std::string name() const override { return "flow-extrapolation"; }
    cv::Mat last_step_flow() const override { return last_flow_; }

  private:
    double wind_from_deg_, degrees_per_second_;
    SkyFlowParams flow_params_;
    cv::Mat last_flow_;  // the flow the last step advected along
};

}  // namespace dynsky
