#include "haptel/config/cockpit.hpp"

#include "haptel/config/check.hpp"
#include "shared_control_section.hpp"
#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

void CockpitConfig::ValidateOrThrow() const {
  check::NonEmpty("name", name);
  check::Number("turn_share", turn_share, 0.0, 1.0);
  check::Number("command_rate_hz", command_rate_hz, 1.0, 1000.0);

  check::Vec3("wheel.hub", wheel_hub, -1.0, 1.0);
  check::Number("wheel.radius", wheel_radius, 0.03, 0.5);
  // The hinge's end stops: a 6-DoF joint's first angular axis turns less than
  // half a turn each way.
  if (!(wheel_max_angle_deg >= 10.0 && wheel_max_angle_deg < 180.0)) {
    check::Fail("wheel.max_angle_deg", "a number in [10, 180) (the hinge's end stops, ±)");
  }
  check::Number("wheel.full_turn_deg", wheel_full_turn_deg, 5.0, 720.0);
  check::Number("wheel.return_stiffness", wheel_return_stiffness, 0.0, 100.0);
  if (wheel_full_turn_deg > wheel_max_angle_deg) {
    check::Fail("wheel.full_turn_deg", "full_turn_deg <= max_angle_deg", {"wheel.max_angle_deg"});
  }

  check::Vec3("throttle.centre", throttle_centre, -1.0, 1.0);
  check::Number("throttle.travel", throttle_travel, 0.01, 0.5);
  check::Number("throttle.return_stiffness", throttle_return_stiffness, 0.0, 1e4);

  check::Number("contact.shake_s", shake_s, 0.0, 10.0);
  check::Number("contact.shake_torque", shake_torque, 0.0, 10.0);
  check::Number("contact.shake_hz", shake_hz, 0.5, 100.0);
  check::Number("contact.throttle_lock_s", throttle_lock_s, 0.0, 30.0);
  if (shared_control.enabled) check::Nested("shared_control", shared_control);
}

CockpitConfig LoadCockpit(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  CockpitConfig c;
  c.file = file;
  c.name = root.RequireString("name");
  // The name says which loader reads a file (InterfaceName); in code it is a label.
  if (c.name != "cockpit" && c.name != "cockpit-hud" && c.name != "cockpit-assisted" &&
      c.name != "cockpit-shared") {
    root.Fail("name", "one of: cockpit, cockpit-hud, cockpit-assisted, cockpit-shared");
  }
  c.hud = root.Bool("hud", c.hud);
  c.return_to_zero = root.Bool("return_to_zero", c.return_to_zero);
  c.turn_share = root.Number("turn_share", c.turn_share);
  c.command_rate_hz = root.Number("command_rate_hz", c.command_rate_hz);

  YamlMap wheel = root.Map("wheel");
  c.wheel_hub = wheel.Vec3("hub", c.wheel_hub);
  c.wheel_radius = wheel.Number("radius", c.wheel_radius);
  c.wheel_max_angle_deg = wheel.Number("max_angle_deg", c.wheel_max_angle_deg);
  c.wheel_full_turn_deg = wheel.Number("full_turn_deg", c.wheel_full_turn_deg);
  c.wheel_return_stiffness = wheel.Number("return_stiffness", c.wheel_return_stiffness);
  wheel.Finish();

  YamlMap throttle = root.Map("throttle");
  c.throttle_centre = throttle.Vec3("centre", c.throttle_centre);
  c.throttle_travel = throttle.Number("travel", c.throttle_travel);
  c.throttle_return_stiffness = throttle.Number("return_stiffness", c.throttle_return_stiffness);
  throttle.Finish();

  YamlMap contact = root.Map("contact");
  c.shake_s = contact.Number("shake_s", c.shake_s);
  c.shake_torque = contact.Number("shake_torque", c.shake_torque);
  c.shake_hz = contact.Number("shake_hz", c.shake_hz);
  c.throttle_lock_s = contact.Number("throttle_lock_s", c.throttle_lock_s);
  contact.Finish();
  config_detail::ReadSharedControl(root, c.name, "cockpit-shared", c.shared_control);
  root.Finish();
  config_detail::ValidateIn(root, c);
  return c;
}

}  // namespace haptel
