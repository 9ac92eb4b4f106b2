#include "motion/network_step_model.h"

#include <filesystem>

#include "motion/cloud_model.h"
#include "util/data_path.h"
#include "util/error.h"

namespace dynsky {

namespace {

class NetworkStepModel : public MediumStepModel {
  public:
    explicit NetworkStepModel(const std::string& folder) : model_(CloudModel::load(folder)) {}
    SkyImage step(const std::vector<std::shared_ptr<const SkyImage>>& history, double dt) override {
        SkyImage next = model_.step(*history.back());
        next.time_seconds = history.back()->time_seconds + dt;
        return next;
    }
    std::string name() const override { return "network:" + model_.info().folder; }
    double native_dt() const override { return model_.info().dt; }

  private:
    CloudModel model_;
};

}  // namespace

std::unique_ptr<MediumStepModel> make_network_step_model(const std::string& folder, const CloudMotion& motion) {
    if (folder == "advect")
        return std::make_unique<AdvectResidualStepModel>(AdvectResidualNetwork::pure_advection(), motion);
    if (cloud_model_kind(folder) == "advect-residual")
        return std::make_unique<AdvectResidualStepModel>(AdvectResidualNetwork::load(folder), motion);
    return std::make_unique<NetworkStepModel>(folder);
}

std::string resolve_cloud_model(const std::string& name_in) {
    // "network:FOLDER", as animate and sky timeline write a folder, is the folder.
    const bool named_folder = name_in.rfind("network:", 0) == 0;
    const std::string name = named_folder ? name_in.substr(8) : name_in;
    if (name == "flow" || name == "procedural")
        throw Error("--model " + name +
                    ": a model of the moving sky of 'animate' and 'sky timeline' (it needs their sky); give auto, "
                    "advect, paper or a model folder");
    auto installed = [](const std::string& rel) -> std::string {
        try {
            std::string p = data_path(rel + "/model.json");
            return p.substr(0, p.size() - std::string("/model.json").size());
        } catch (const Error&) {
            return "";
        }
    };
    if (name.empty() || name == "auto") {
        std::string f = installed("networks/models/advect_residual");
        return f.empty() ? "advect" : f;
    }
    if (name == "paper") {
        std::string f = installed("networks/models/arm_tsi");
        if (f.empty()) throw Error("--model paper: networks/models/arm_tsi is not installed");
        return f;
    }
    if (name == "advect") return name;  // pure advection (make_network_step_model)
    // A folder: from the working folder, else the shipped one of that name. A word that names none
    // is a mistyped choice (a usage error, as animate says it); a path that is missing is a file error.
    const std::string folder = resolve_user_path(name);
    std::error_code ec;
    if (!named_folder && name.find('/') == std::string::npos && !std::filesystem::is_directory(folder, ec))
        throw Error("--model '" + name + "': expected auto, advect, paper or a model folder (no folder '" + name +
                    "' here or among the shipped models)");
    return folder;
}


}  // namespace dynsky
