#pragma once
/// @file The interface catalogue: every mediator interface, of both vehicle
/// families, registered beside its code by one descriptor (its name, what it
/// needs, its config's loader and its factory), read from its file and built
/// for the session's parts. ros2_control's plugins are the model: a new
/// interface is its own files and one RegisterInterface in its .cpp; nothing
/// outside the catalogue asks an interface's name.
///
/// Registering: a static `RegisterInterface<Family, Config>` object in the
/// interface's .cpp (gesture.cpp, blimp_manual.cpp), or in a test's own file.
/// The interfaces library is linked whole (CMake's WHOLE_ARCHIVE, see
/// interfaces/CMakeLists.txt) so that no registration is dropped by the
/// linker; the catalogue lists interfaces in the order they register (the
/// library's source order). Register before any thread reads the catalogue.
#include <any>
#include <array>
#include <filesystem>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <typeinfo>
#include <utility>
#include <vector>

#include "haptel/config/device.hpp"
#include "haptel/config/interface_kinds.hpp"
#include "haptel/config/run.hpp"
#include "haptel/interfaces/blimp_interface.hpp"
#include "haptel/interfaces/input.hpp"
#include "haptel/interfaces/interface.hpp"
#include "haptel/interfaces/shared_control.hpp"

namespace haptel::interfaces {

class ControlsPort;

/// What an interface is built on.
struct InterfaceParts {
  ControlsPort* controls = nullptr;  ///< a cockpit's controls (physics)
  const InputBox* input = nullptr;   ///< a person's keys and controller
  int speed_levels = 8;              ///< the vehicle's levels per direction
  /// The vehicle's drive and body, for shared control's prediction (gesture-shared,
  /// cockpit-shared).
  VehicleGeometry vehicle;
};

/// One interface file, loaded: its row in the catalogue says what it is, its
/// config how it is set (the interface's own config struct).
struct InterfaceSpec {
  InterfaceSpec() = default;
  InterfaceSpec(std::string name_, std::any config_, double command_rate_hz)
      : name(std::move(name_)), config(std::move(config_)), command_rate_hz_(command_rate_hz) {}

  std::string name;
  std::any config;

  /// How often its command goes out, Hz (its config's `command_rate_hz`).
  double command_rate_hz() const { return command_rate_hz_; }

  /// Its row in the interface table (name, family, hands, input, physics).
  const InterfaceKindInfo& kind() const;
  /// The interface moves proxy hands among bodies (a physics world).
  bool needs_physics() const { return kind().physics; }
  /// Hands the interface uses ([left, right]).
  std::array<bool, 2> hands() const { return kind().hands; }
  /// Driven by a person's keys or controller, not by hands on a device.
  bool manual() const { return kind().manual(); }
  bool is_keyboard() const { return kind().input == InterfaceInput::kKeys; }
  bool is_gamepad() const { return kind().input == InterfaceInput::kGamepad; }
  /// Its config as `Config`, or null when it is another interface's.
  template <class Config>
  const Config* config_as() const {
    return std::any_cast<Config>(&config);
  }

 private:
  double command_rate_hz_ = 0.0;
};

/// What the catalogue knows of a family: its name in the vehicle table and
/// the base its interfaces derive from.
template <class Family>
struct FamilyOf;
template <>
struct FamilyOf<RobotFamily> {
  static constexpr VehicleFamily kValue = VehicleFamily::kRobot;
  using Base = MediatorInterface;
};
template <>
struct FamilyOf<BlimpFamily> {
  static constexpr VehicleFamily kValue = VehicleFamily::kBlimp;
  using Base = BlimpInterface;
};

/// A factory of one family's interfaces, from the loaded spec.
template <class Family>
using InterfaceFactory = std::function<std::unique_ptr<typename FamilyOf<Family>::Base>(
    const InterfaceSpec&, const InterfaceParts&)>;

/// One interface as the catalogue holds it.
struct InterfaceDescriptor {
  InterfaceKindInfo kind;  ///< name, family, hands, input, physics, summary
  /// Reads and validates its file (ConfigError naming file and key).
  std::function<InterfaceSpec(const std::filesystem::path& file)> load;
  InterfaceFactory<RobotFamily> make_robot;  ///< set for the robot's interfaces
  InterfaceFactory<BlimpFamily> make_blimp;  ///< set for the blimp's
};

/// Adds `descriptor` to the catalogue, and its row to the interface table the
/// config loaders check names against (config/interface_kinds.hpp).
/// std::invalid_argument when its name is taken.
void AddInterface(InterfaceDescriptor descriptor);
/// The interface named `name`, or null.
const InterfaceDescriptor* FindInterface(const std::string& name);
/// The first registered interface of `family` that takes `input` (a person
/// at a simulated device drives by the keys). std::logic_error when none.
const InterfaceKindInfo& FirstInterface(VehicleFamily family, InterfaceInput input);

/// Registers an interface of `Family` whose files load into `Config` (a
/// struct with `name` and `command_rate_hz`), under one or more names (the
/// four cockpits share a loader and factory). A static object of this type
/// in the interface's .cpp is its whole registration.
template <class Family, class Config>
struct RegisterInterface {
  using Load = Config (*)(const std::filesystem::path& file);
  using Make = std::function<std::unique_ptr<typename FamilyOf<Family>::Base>(
      const Config&, const InterfaceParts&)>;

  RegisterInterface(std::vector<InterfaceKindInfo> kinds, Load load, Make make) {
    for (InterfaceKindInfo& kind : kinds) {
      if (kind.family != FamilyOf<Family>::kValue)
        throw std::logic_error("interface '" + kind.name + "': registered in another family");
      InterfaceDescriptor d;
      d.load = [load, name = kind.name](const std::filesystem::path& file) {
        Config config = load(file);
        const double rate_hz = config.command_rate_hz;
        return InterfaceSpec(name, std::move(config), rate_hz);
      };
      InterfaceFactory<Family> factory = [make](const InterfaceSpec& spec,
                                                const InterfaceParts& parts) {
        return make(*spec.config_as<Config>(), parts);
      };
      if constexpr (FamilyOf<Family>::kValue == VehicleFamily::kRobot) {
        d.make_robot = std::move(factory);
      } else {
        d.make_blimp = std::move(factory);
      }
      d.kind = std::move(kind);
      d.kind.config = &typeid(Config);
      AddInterface(std::move(d));
    }
  }
};

/// Loads `<interfaces_dir>/<name>.yaml` for a vehicle of `family` (ConfigError
/// naming the file, and the family's interfaces, otherwise).
InterfaceSpec LoadInterfaceSpec(const RunConfig& run, const std::string& name,
                                VehicleFamily family = VehicleFamily::kRobot);

/// Throws ConfigError, naming the device file and its key 'sides', when one of
/// the interfaces a run builds uses a hand the device has no arm for (the
/// gesture interface the right, the cockpits both; keys and controllers none).
void CheckHands(const std::vector<InterfaceSpec>& specs, const DeviceConfig& device);

/// Builds a robot interface. Throws std::invalid_argument when a part it needs
/// is missing, std::logic_error when `spec` is not a robot's.
std::unique_ptr<MediatorInterface> MakeInterface(const InterfaceSpec& spec,
                                                 const InterfaceParts& parts);
/// Builds a blimp interface (as MakeInterface).
std::unique_ptr<BlimpInterface> MakeBlimpInterface(const InterfaceSpec& spec,
                                                   const InterfaceParts& parts);

/// The person's input `parts` hold; std::invalid_argument naming `interface` when none.
const InputBox& PersonsInput(const std::string& interface, const InterfaceParts& parts);

}  // namespace haptel::interfaces
