#include "haptel/config/device.hpp"

#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;

DeviceConfig LoadDevice(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  DeviceConfig d;
  d.file = file;
  d.name = root.RequireString("name");
  d.driver = root.String("driver", d.driver);
  if (d.driver != "sim" && d.driver != "udp" && d.driver != "replay") {
    root.Fail("driver", "one of: sim, udp, replay");
  }
  const std::vector<std::string> sides = root.Strings("sides", {"left", "right"});
  d.sides = {false, false};
  for (const std::string& s : sides) {
    if (s == "left") {
      d.sides[0] = true;
    } else if (s == "right") {
      d.sides[1] = true;
    } else {
      root.Fail("sides", "a list of 'left' and/or 'right'");
    }
  }
  if (!d.sides[0] && !d.sides[1]) root.Fail("sides", "at least one of 'left', 'right'");
  d.has_glove = root.Bool("has_glove", d.has_glove);
  d.has_grasp = root.Bool("has_grasp", d.has_grasp);
  if (root.Has("calibration")) d.calibration = root.String("calibration", "");
  if (root.Has("gravity")) d.gravity = root.String("gravity", "");

  YamlMap servo = root.Map("servo");
  d.servo.rate_hz = servo.Number("rate_hz", d.servo.rate_hz, 100.0, 10000.0);
  d.servo.two_sided = servo.Bool("two_sided", d.servo.two_sided);
  d.servo.slow_channel_divider = servo.Integer("slow_channel_divider", d.servo.slow_channel_divider, 1, 1000);
  d.servo.realtime_priority = servo.Integer("realtime_priority", d.servo.realtime_priority, 0, 99);
  d.servo.lock_memory = servo.Bool("lock_memory", d.servo.lock_memory);
  servo.Finish();

  YamlMap safety = root.Map("safety");
  d.safety.wrist_force_limit = safety.Number("wrist_force_limit", d.safety.wrist_force_limit, 0.0, 200.0);
  d.safety.finger_force_limit = safety.Number("finger_force_limit", d.safety.finger_force_limit, 0.0, 100.0);
  d.safety.max_force_rate = safety.Number("max_force_rate", d.safety.max_force_rate, 1.0, 1e6);
  d.safety.soft_start_s = safety.Number("soft_start_s", d.safety.soft_start_s, 0.0, 60.0);
  d.safety.setpoint_timeout_s = safety.Number("setpoint_timeout_s", d.safety.setpoint_timeout_s, 0.001, 10.0);
  d.safety.fade_s = safety.Number("fade_s", d.safety.fade_s, 0.0, 10.0);
  safety.Finish();
  if (d.safety.setpoint_timeout_s + d.safety.fade_s > 0.05 + 1e-9) {
    root.Fail("safety", "setpoint_timeout_s + fade_s <= 0.05 (forces must be gone 50 ms after a stall)");
  }

  YamlMap sim = root.Map("sim");
  SimArmConfig& s = d.sim;
  s.arm_mass = sim.Number("arm_mass", s.arm_mass, 0.01, 100.0);
  s.damping = sim.Number("damping", s.damping, 0.0, 1e3);
  s.coulomb_friction = sim.Number("coulomb_friction", s.coulomb_friction, 0.0, 100.0);
  s.exo_unbalanced_mass = sim.Number("exo_unbalanced_mass", s.exo_unbalanced_mass, 0.0, 20.0);
  s.encoder_resolution = sim.Number("encoder_resolution", s.encoder_resolution, 0.0, 0.01);
  s.force_limit = sim.Number("force_limit", s.force_limit, 0.0, 200.0);
  s.glove_noise = sim.Number("glove_noise", s.glove_noise, 0.0, 100.0);
  s.workspace_min = sim.Vec3("workspace_min", s.workspace_min, -5.0, 5.0);
  s.workspace_max = sim.Vec3("workspace_max", s.workspace_max, -5.0, 5.0);
  s.seed = sim.Integer("seed", s.seed, 0, 1 << 30);
  sim.Finish();
  for (int i = 0; i < 3; ++i) {
    if (s.workspace_min[i] >= s.workspace_max[i]) root.Fail("sim", "workspace_min < workspace_max on every axis");
  }

  YamlMap udp = root.Map("udp");
  const char* names[2] = {"left", "right"};
  for (int i = 0; i < 2; ++i) {
    YamlMap arm = udp.Map(names[i]);
    d.udp.arms[i].host = arm.String("host", d.udp.arms[i].host);
    d.udp.arms[i].port = arm.Integer("port", d.udp.arms[i].port, 0, 65535);
    arm.Finish();
  }
  d.udp.timeout_s = udp.Number("timeout_s", d.udp.timeout_s, 1e-5, 5.0);
  d.udp.retries = udp.Integer("retries", d.udp.retries, 0, 100);
  d.udp.lost_after_s = udp.Number("lost_after_s", d.udp.lost_after_s, 1e-3, 60.0);
  udp.Finish();
  if (d.driver == "udp") {
    for (int i = 0; i < 2; ++i) {
      if (d.sides[i] && d.udp.arms[i].port == 0) {
        root.Fail("udp", std::string("a port for the ") + names[i] + " arm (udp." + names[i] + ".port)");
      }
    }
  }

  YamlMap replay = root.Map("replay");
  if (replay.Has("trace")) d.replay.trace = file.parent_path() / replay.String("trace", "");
  d.replay.loop = replay.Bool("loop", d.replay.loop);
  replay.Finish();
  if (d.driver == "replay" && d.replay.trace.empty()) root.Fail("replay", "a 'trace' file for the replay driver");
  root.Finish();
  return d;
}

}  // namespace haptel
