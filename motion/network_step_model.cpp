#include "motion/network_step_model.h"

#include "motion/cloud_model.h"

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

std::unique_ptr<MediumStepModel> make_network_step_model(const std::string& folder) {
    return std::make_unique<NetworkStepModel>(folder);
}

}  // namespace dynsky
