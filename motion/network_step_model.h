// Step model "network:FOLDER": the trained networks of a model folder as a medium-step model, by
// the folder's kind (model.json): advect-residual (motion/advect_residual.h: moved along a given
// motion, corrected by a network) or the paper's FlowNet + CloudNet (motion/cloud_model.h, v1
// folders; its motion comes from the sky alone, so `motion` is not used).
//
// Parameters (defaults):
//   folder   (required)  model.json and its ONNX files; Delta t is the model's dt_s
//   motion   the default wind (motion/advect_residual.h CloudMotion)
#pragma once

#include <memory>
#include <string>

#include "motion/advect_residual.h"
#include "motion/step_model.h"

namespace dynsky {

std::unique_ptr<MediumStepModel> make_network_step_model(const std::string& folder, const CloudMotion& motion = {});

// The folder (or "advect") a model name stands for: "" and "auto" -> networks/models/advect_residual
// when installed (else "advect": pure advection); "paper" -> networks/models/arm_tsi; "advect";
// else the name itself, "network:" taken off (a folder; a relative one not found from the working
// folder is looked up among the shipped data, util/data_path.h). "flow" and "procedural" (models of
// the timeline's own skies) throw.
std::string resolve_cloud_model(const std::string& name);

}  // namespace dynsky
