// xi, the medium-timescale step model: the next medium step of a sky from the steps so far
// (glossary: "medium step", "step model"). Implementations, each in its own file with its
// parameters first: flow_extrapolation_model.h, procedural_step_model.h, network_step_model.h.
// motion/sky_timeline.h calls them once per Delta t.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "sky/sky_image.h"

namespace dynsky {

class MediumStepModel {
  public:
    virtual ~MediumStepModel() = default;
    // history.back() is the latest step (at least one). The result's time must be
    // history.back().time_seconds + dt.
    virtual SkyImage step(const std::vector<std::shared_ptr<const SkyImage>>& history, double dt) = 0;
    virtual std::string name() const = 0;
    // True when the model's skies already hold the right sun (the timeline then leaves it alone).
    virtual bool makes_own_sun() const { return false; }
    // Where the sun is for the next step (models that make their own sun follow it).
    virtual void set_sun_direction(const Vec3d&) {}
    // The Delta t the model was made for (a trained network's), 0 when any is fine.
    virtual double native_dt() const { return 0.0; }
    // How opaque the clouds are that the step just made shows, when the model knows more than the
    // sky's look: it moved the input's clouds and measured their opacity where they were seen
    // (motion/advect_residual.h CloudRollout::opacity). A square CV_32FC1 map in the sky's layout (0
    // clear .. 1 cloud) at any resolution; empty: no opinion (the timeline judges the sun from the
    // sky alone, motion/sun_patch.h). input_cloud_opacity: the same for the input.
    virtual cv::Mat last_cloud_opacity() const { return cv::Mat(); }
    virtual cv::Mat input_cloud_opacity() const { return cv::Mat(); }
    // How much of the input's sun a cloud hid (1 - its share of the clear sun), told before the
    // first step: models with an opacity count the sun's cut-out pixels at least this opaque.
    virtual void set_input_sun_cover(double) {}
    // How much of the clear sun the input showed before its sun was cut out (sun_patch_share),
    // told before the first step: a sky that shows its sun whole is not overcast.
    virtual void set_input_sun_share(double) {}
    // True when only native_dt() is right (the paper's networks learnt one step's motion); models
    // that take their motion as an input work at any Delta t.
    virtual bool dt_is_fixed() const { return native_dt() > 0; }
    // The motion the step just made gave the clouds, when the model knows it (it moved them along
    // a flow): CV_32FC2 at the sky's resolution, in its pixels per step, the content at x carried to
    // about x + F(x). Empty: unknown, and the timeline measures the motion between the two steps
    // (Farneback, which loses displacements of more than a few pixels: in-betweens of a 16 px step
    // stalled, then jumped).
    virtual cv::Mat last_step_flow() const { return cv::Mat(); }
};

}  // namespace dynsky
