#include "haptel/app/in_process_robot.hpp"

#include "haptel/config/error.hpp"
#include "haptel/config/vehicle_kinds.hpp"
#include "haptel/vehicles/vehicle_core.hpp"
#include "haptel/vehicles/vehicle_kinds.hpp"

namespace haptel::app {

namespace {

class CoreRobot final : public mediator::InProcessRobot {
 public:
  CoreRobot(const VehicleConfig& vehicle, std::unique_ptr<vehicles::VehicleAdapter> adapter)
      : core_(vehicle, std::move(adapter)) {}
  double control_rate_hz() const override { return core_.config().sim_rate_hz; }
  void OnCommand(const msg::TreadCommand& command, int64_t now_ns) override {
    core_.OnCommand(command, now_ns);
  }
  const msg::VehicleState* Tick(int64_t now_ns) override {
    if (!core_.ControlTick(now_ns) || !core_.state_due()) return nullptr;
    return &core_.MakeState(now_ns);
  }
  void MakeSafe() override { core_.MakeSafe(); }

 private:
  vehicles::RobotCore core_;
};

}  // namespace

std::unique_ptr<mediator::InProcessRobot> MakeInProcessRobot(const VehicleConfig& vehicle,
                                                             const Track& track) {
  const VehicleKindInfo* kind = FindVehicleKind(vehicle.kind);
  const auto* factory = vehicles::FindKindFactory<vehicles::RobotFamily>(vehicle.kind);
  if (kind == nullptr || !kind->steps_in_process || factory == nullptr) {
    throw ConfigError(
        vehicle.file.string() + ": key 'kind': '" + vehicle.kind +
        "' does not step in the operator's process; expected a simulated robot (sim-robot)");
  }
  return std::make_unique<CoreRobot>(vehicle, (*factory)(vehicle, track).adapter);
}

void RegisterInProcessRobot() { mediator::SetInProcessRobotFactory(&MakeInProcessRobot); }

}  // namespace haptel::app
