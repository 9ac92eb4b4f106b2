#include "motion/flow_extrapolation_model.h"

#include "motion/advection.h"
#include "sky/fisheye.h"

namespace dynsky {

FlowExtrapolationStepModel::FlowExtrapolationStepModel(double wind_from_deg, double degrees_per_second,
                                                       SkyFlowParams flow_params)
    : wind_from_deg_(wind_from_deg), degrees_per_second_(degrees_per_second), flow_params_(flow_params) {}

SkyImage FlowExtrapolationStepModel::step(const std::vector<std::shared_ptr<const SkyImage>>& history, double dt) {
    const SkyImage& last = *history.back();
    cv::Mat flow;
    if (history.size() >= 2) {
        flow = estimate_sky_flow(*history[history.size() - 2], last, flow_params_);
    } else {
        // Clouds overhead drift towards where the wind blows to: rotate the zenith towards it.
        Vec3d to = fisheye::direction_from_angles(kPiD / 2, (wind_from_deg_ + 180.0) * kPiD / 180.0);
        Vec3d axis = Vec3d::UnitY().cross(to);
        flow = rotation_flow(last.resolution, axis, degrees_per_second_ * dt * kPiD / 180.0);
    }
    last_flow_ = flow;
    SkyImage next = advect_great_arc(last, flow, 1.0);
    next.time_seconds = last.time_seconds + dt;
    // Named once: chained at every step the name grew with the step count (18 kB at step 800, a
    // stored timeline's description megabytes).
    const std::string prefix = "flow-extrapolation of ";
    next.source = last.source.rfind(prefix, 0) == 0 ? last.source : prefix + last.source;
    return next;
}

}  // namespace dynsky
