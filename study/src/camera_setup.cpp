#include "haptel/study/camera_setup.hpp"

#include <mutex>

#include "haptel/link/families.hpp"
#include "haptel/link/participant.hpp"
#include "haptel/link/topic.hpp"

namespace haptel::study {

std::string WithCameraSetup(const std::string& next, const StudyCondition& condition) {
  const std::string setup = CameraSetupText(condition);
  return setup.empty() ? next : next + "; " + setup;
}

std::string StationMissingLine(const std::string& condition, const std::string& camera,
                               const std::string& vehicle, int domain) {
  return "condition '" + condition + "' needs a second person at the " + camera +
         " station: nobody holds camera " + camera + " of " + vehicle +
         "; start `haptel station --vehicle " + vehicle + " --camera " + camera + " --domain " +
         std::to_string(domain) + "`, then Start again";
}

struct StationWatch::Impl {
  std::string vehicle, camera, condition;
  int domain = 0;
  std::unique_ptr<link::Participant> participant;
  std::unique_ptr<link::CameraCommandReader> commands;
  std::unique_ptr<link::CameraStatusReader> status;
  mutable std::mutex mutex;
  std::string holder;  ///< guarded by mutex
};

StationWatch::StationWatch(const LinkConfig& link, const std::string& vehicle,
                           const std::string& camera, const std::string& condition)
    : impl_(std::make_unique<Impl>()) {
  Impl& i = *impl_;
  i.vehicle = vehicle;
  i.camera = camera;
  i.condition = condition;
  i.domain = link.domain_id;
  i.participant = std::make_unique<link::Participant>(link, "haptel-study-station-watch");
  // Its samples are the vehicle's business: only the writer's presence counts here.
  i.commands = std::make_unique<link::CameraCommandReader>(
      *i.participant, link::CameraCommandTopic(vehicle, camera),
      link::CameraMessages::kCommandProfile, [](const msg::CameraCommand&) {});
  i.status = std::make_unique<link::CameraStatusReader>(
      *i.participant, link::CameraStatusTopic(vehicle), link::CameraMessages::kStatusProfile,
      [this](const msg::CameraStatus& s) {
        for (const msg::CameraInfo& c : s.cameras()) {
          if (impl_->camera != c.name().c_str()) continue;
          std::lock_guard lock(impl_->mutex);
          impl_->holder = c.holder().c_str();
        }
      });
}

StationWatch::~StationWatch() = default;

std::string StationWatch::Missing() const {
  if (impl_->commands->matched() > 0) return "";
  return StationMissingLine(impl_->condition, impl_->camera, impl_->vehicle, impl_->domain);
}

std::string StationWatch::holder() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->holder;
}

}  // namespace haptel::study
