#include "haptel/config/device.hpp"

#include <map>
#include <stdexcept>

#include "haptel/config/check.hpp"
#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

namespace {
/// The sides as the file names them: [left, right].
constexpr const char* kSideNames[2] = {"left", "right"};

/// The registered drivers' own checks, by name (AddDeviceDriverCheck).
std::map<std::string, std::function<void(const DeviceConfig&)>>& DriverChecks() {
  static std::map<std::string, std::function<void(const DeviceConfig&)>> checks;
  return checks;
}

/// "replay, sim, udp": the registered drivers, for an error's "expected".
std::string DriverNames() {
  std::string names;
  for (const auto& [name, check] : DriverChecks()) names += (names.empty() ? "" : ", ") + name;
  return names;
}
}  // namespace

void AddDeviceDriverCheck(const std::string& driver,
                          std::function<void(const DeviceConfig&)> check) {
  if (!DriverChecks().emplace(driver, std::move(check)).second)
    throw std::invalid_argument("device driver '" + driver + "' is registered already");
}

void ServoLoopConfig::ValidateOrThrow() const {
  check::Number("rate_hz", rate_hz, 100.0, 10000.0);
  check::Whole("slow_channel_divider", slow_channel_divider, 1, 1000);
  check::Whole("realtime_priority", realtime_priority, 0, 99);
  check::Number("passivity_max_damping", passivity_max_damping, 0.0, 1e4);
  check::Number("passivity_min_speed", passivity_min_speed, 1e-6, 1.0);
}

void SafetyConfig::ValidateOrThrow() const {
  check::Number("wrist_force_limit", wrist_force_limit, 0.0, 200.0);
  check::Number("finger_force_limit", finger_force_limit, 0.0, 100.0);
  check::Number("max_force_rate", max_force_rate, 1.0, 1e6);
  check::Number("soft_start_s", soft_start_s, 0.0, 60.0);
  check::Number("setpoint_timeout_s", setpoint_timeout_s, 0.001, 10.0);
  check::Number("fade_s", fade_s, 0.0, 10.0);
  if (setpoint_timeout_s + fade_s > 0.05 + 1e-9) {
    check::Fail("fade_s",
                "setpoint_timeout_s + fade_s <= 0.05 (forces must be gone 50 ms after a stall)",
                {"setpoint_timeout_s"});
  }
}

void SimArmConfig::ValidateOrThrow() const {
  check::Number("arm_mass", arm_mass, 0.01, 100.0);
  check::Number("damping", damping, 0.0, 1e3);
  check::Number("coulomb_friction", coulomb_friction, 0.0, 100.0);
  check::Number("exo_unbalanced_mass", exo_unbalanced_mass, 0.0, 20.0);
  check::Number("encoder_resolution", encoder_resolution, 0.0, 0.01);
  check::Number("force_limit", force_limit, 0.0, 200.0);
  check::Number("glove_noise", glove_noise, 0.0, 100.0);
  check::Vec3("workspace_min", workspace_min, -5.0, 5.0);
  check::Vec3("workspace_max", workspace_max, -5.0, 5.0);
  check::Whole("seed", seed, 0, 1 << 30);
  for (int i = 0; i < 3; ++i) {
    if (workspace_min[i] >= workspace_max[i]) {
      check::Fail("workspace_max", "workspace_min < workspace_max on every axis",
                  {"workspace_min"});
    }
  }
}

void UdpArmEndpoint::ValidateOrThrow() const {
  check::NonEmpty("host", host);
  check::Whole("port", port, 0, 65535);
}

void UdpDeviceConfig::ValidateOrThrow() const {
  for (int i = 0; i < 2; ++i) check::Nested(kSideNames[i], arms[i]);
  check::Number("timeout_s", timeout_s, 1e-5, 5.0);
  check::Whole("retries", retries, 0, 100);
  check::Number("lost_after_s", lost_after_s, 1e-3, 60.0);
}

void ReplayDeviceConfig::ValidateOrThrow() const {}

void DeviceConfig::ValidateOrThrow() const {
  check::NonEmpty("name", name);
  const auto driver_check = DriverChecks().find(driver);
  if (driver_check == DriverChecks().end()) check::Fail("driver", "one of: " + DriverNames());
  if (!sides[0] && !sides[1]) check::Fail("sides", "at least one of 'left', 'right'");
  check::Nested("servo", servo);
  check::Nested("safety", safety);
  check::Nested("sim", sim);
  check::Nested("udp", udp);
  check::Nested("replay", replay);
  if (driver_check->second) driver_check->second(*this);
}

DeviceConfig LoadDevice(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  DeviceConfig d;
  d.file = file;
  d.name = root.RequireString("name");
  d.driver = root.String("driver", d.driver);
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
  d.has_glove = root.Bool("has_glove", d.has_glove);
  d.has_grasp = root.Bool("has_grasp", d.has_grasp);
  if (root.Has("calibration")) d.calibration = root.String("calibration", "");
  if (root.Has("gravity")) d.gravity = root.String("gravity", "");

  YamlMap servo = root.Map("servo");
  d.servo.rate_hz = servo.Number("rate_hz", d.servo.rate_hz);
  d.servo.two_sided = servo.Bool("two_sided", d.servo.two_sided);
  d.servo.slow_channel_divider =
      servo.Integer("slow_channel_divider", d.servo.slow_channel_divider);
  d.servo.realtime_priority = servo.Integer("realtime_priority", d.servo.realtime_priority);
  d.servo.lock_memory = servo.Bool("lock_memory", d.servo.lock_memory);
  if (servo.Has("passivity")) {
    const std::string passivity = servo.String("passivity", "");
    if (passivity != "on" && passivity != "off") servo.Fail("passivity", "on or off");
    d.servo.passivity = passivity == "on";
  }
  if (servo.Has("passivity_link")) {
    const std::string link = servo.String("passivity_link", "");
    if (link != "admittance" && link != "charge")
      servo.Fail("passivity_link", "admittance or charge");
    d.servo.passivity_link_admittance = link == "admittance";
  }
  d.servo.passivity_max_damping =
      servo.Number("passivity_max_damping", d.servo.passivity_max_damping);
  d.servo.passivity_min_speed = servo.Number("passivity_min_speed", d.servo.passivity_min_speed);
  servo.Finish();

  YamlMap safety = root.Map("safety");
  SafetyConfig& f = d.safety;
  f.wrist_force_limit = safety.Number("wrist_force_limit", f.wrist_force_limit);
  f.finger_force_limit = safety.Number("finger_force_limit", f.finger_force_limit);
  f.max_force_rate = safety.Number("max_force_rate", f.max_force_rate);
  f.soft_start_s = safety.Number("soft_start_s", f.soft_start_s);
  f.setpoint_timeout_s = safety.Number("setpoint_timeout_s", f.setpoint_timeout_s);
  f.fade_s = safety.Number("fade_s", f.fade_s);
  safety.Finish();

  YamlMap sim = root.Map("sim");
  SimArmConfig& s = d.sim;
  s.arm_mass = sim.Number("arm_mass", s.arm_mass);
  s.damping = sim.Number("damping", s.damping);
  s.coulomb_friction = sim.Number("coulomb_friction", s.coulomb_friction);
  s.exo_unbalanced_mass = sim.Number("exo_unbalanced_mass", s.exo_unbalanced_mass);
  s.encoder_resolution = sim.Number("encoder_resolution", s.encoder_resolution);
  s.force_limit = sim.Number("force_limit", s.force_limit);
  s.glove_noise = sim.Number("glove_noise", s.glove_noise);
  s.workspace_min = sim.Vec3("workspace_min", s.workspace_min);
  s.workspace_max = sim.Vec3("workspace_max", s.workspace_max);
  s.seed = sim.Integer("seed", s.seed);
  sim.Finish();

  YamlMap udp = root.Map("udp");
  for (int i = 0; i < 2; ++i) {
    YamlMap arm = udp.Map(kSideNames[i]);
    d.udp.arms[i].host = arm.String("host", d.udp.arms[i].host);
    d.udp.arms[i].port = arm.Integer("port", d.udp.arms[i].port);
    arm.Finish();
  }
  d.udp.timeout_s = udp.Number("timeout_s", d.udp.timeout_s);
  d.udp.retries = udp.Integer("retries", d.udp.retries);
  d.udp.lost_after_s = udp.Number("lost_after_s", d.udp.lost_after_s);
  udp.Finish();

  YamlMap replay = root.Map("replay");
  if (replay.Has("trace")) d.replay.trace = file.parent_path() / replay.String("trace", "");
  d.replay.loop = replay.Bool("loop", d.replay.loop);
  replay.Finish();
  root.Finish();
  config_detail::ValidateIn(root, d);
  return d;
}

}  // namespace haptel
