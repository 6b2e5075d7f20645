#include "haptel/config/cockpit.hpp"

#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;

CockpitConfig LoadCockpit(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  CockpitConfig c;
  c.file = file;
  c.name = root.RequireString("name");
  if (c.name != "cockpit" && c.name != "cockpit-hud" && c.name != "cockpit-assisted") {
    root.Fail("name", "one of: cockpit, cockpit-hud, cockpit-assisted");
  }
  c.hud = root.Bool("hud", c.hud);
  c.return_to_zero = root.Bool("return_to_zero", c.return_to_zero);
  c.turn_share = root.Number("turn_share", c.turn_share, 0.0, 1.0);
  c.command_rate_hz = root.Number("command_rate_hz", c.command_rate_hz, 1.0, 1000.0);

  YamlMap wheel = root.Map("wheel");
  c.wheel_hub = wheel.Vec3("hub", c.wheel_hub, -1.0, 1.0);
  c.wheel_radius = wheel.Number("radius", c.wheel_radius, 0.03, 0.5);
  c.wheel_max_angle_deg = wheel.Number("max_angle_deg", c.wheel_max_angle_deg, 10.0, 720.0);
  c.wheel_full_turn_deg = wheel.Number("full_turn_deg", c.wheel_full_turn_deg, 5.0, 720.0);
  c.wheel_return_stiffness = wheel.Number("return_stiffness", c.wheel_return_stiffness, 0.0, 100.0);
  wheel.Finish();
  if (c.wheel_full_turn_deg > c.wheel_max_angle_deg) root.Fail("wheel", "full_turn_deg <= max_angle_deg");

  YamlMap throttle = root.Map("throttle");
  c.throttle_centre = throttle.Vec3("centre", c.throttle_centre, -1.0, 1.0);
  c.throttle_travel = throttle.Number("travel", c.throttle_travel, 0.01, 0.5);
  c.throttle_return_stiffness = throttle.Number("return_stiffness", c.throttle_return_stiffness, 0.0, 1e4);
  throttle.Finish();

  YamlMap contact = root.Map("contact");
  c.shake_s = contact.Number("shake_s", c.shake_s, 0.0, 10.0);
  c.shake_torque = contact.Number("shake_torque", c.shake_torque, 0.0, 10.0);
  c.shake_hz = contact.Number("shake_hz", c.shake_hz, 0.5, 100.0);
  c.throttle_lock_s = contact.Number("throttle_lock_s", c.throttle_lock_s, 0.0, 30.0);
  contact.Finish();
  root.Finish();
  return c;
}

}  // namespace haptel
