// Step model "network:FOLDER": the trained networks of a model folder (motion/cloud_model.h,
// CloudModel::step) as a medium-step model.
//
// Parameters (defaults):
//   folder   (required)  flownet.onnx, cloudnet.onnx, model.json; Delta t is the model's dt_s
#pragma once

#include <memory>
#include <string>

#include "motion/step_model.h"

namespace dynsky {

std::unique_ptr<MediumStepModel> make_network_step_model(const std::string& folder);

}  // namespace dynsky
