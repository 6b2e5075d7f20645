#include "haptel/config/run.hpp"

#include <algorithm>

#include "haptel/config/check.hpp"
#include "link_section.hpp"
#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

void OperatorConfig::ValidateOrThrow() const {
  check::Number("reaction_delay_s", reaction_delay_s, 0.0, 2.0);
  check::Number("arm_time_constant_s", arm_time_constant_s, 0.0, 2.0);
  check::Number("lookahead", lookahead, 0.05, 10.0);
  check::Number("cruise", cruise, 0.05, 1.0);
  check::Number("min_forward", min_forward, 0.0, 1.0);
  check::Number("slow_radius", slow_radius, 0.0, 100.0);
  check::Number("muscle_stiffness", muscle_stiffness, 1.0, 1e4);
  check::Number("muscle_damping", muscle_damping, 0.0, 1e3);
  check::Number("muscle_max_force", muscle_max_force, 0.1, 100.0);
  check::Number("muscle_integral_gain", muscle_integral_gain, 0.0, 1e5);
  check::Number("backoff_s", backoff_s, 0.0, 10.0);
  check::Number("careful_s", careful_s, 0.0, 60.0);
  check::Number("grasp_reach_s", grasp_reach_s, 0.0, 10.0);
  check::Number("grasp_close_s", grasp_close_s, 0.0, 10.0);
  if (min_forward > cruise) check::Fail("min_forward", "min_forward <= cruise", {"cruise"});
}

void RunConfig::ValidateOrThrow() const {
  check::NonEmpty("name", name);
  check::NonEmpty("interface", interface);
  if (interfaces.empty() || interfaces.size() > 6) {
    check::Fail("switchable_interfaces", "a list of 1 to 6 interface names (F1-F6)");
  }
  for (size_t i = 0; i < interfaces.size(); ++i) {
    check::NonEmpty("switchable_interfaces[" + std::to_string(i) + "]", interfaces[i]);
  }
  check::Number("person_time_limit_s", person_time_limit_s, 1.0, 86400.0);
  check::Number("switch_ramp_s", switch_ramp_s, 0.01, 5.0);
  check::Number("vehicle_timeout_s", vehicle_timeout_s, 0.05, 60.0);
  check::Number("session_rate_hz", session_rate_hz, 10.0, 1000.0);
  check::Nested("scene_placement", scene_placement);
  check::Nested("operator", op);
  check::Nested("link", link);
}

RunConfig LoadRun(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  const std::filesystem::path dir = file.parent_path();
  RunConfig r;
  r.file = file;
  r.name = root.String("name", r.name);
  r.track = dir / root.RequireString("track");
  r.vehicle = dir / root.RequireString("vehicle");
  r.device = dir / root.String("device", "devices/sim.yaml");
  r.physics = dir / root.String("physics", "physics.yaml");
  if (const std::string scene = root.String("scene", ""); !scene.empty()) r.scene = dir / scene;
  YamlMap placement = root.Map("scene_placement");
  const auto position = placement.Vec3("position", {0.0, 0.0, 0.0});
  // Only the rotation they make is kept (and checked): their range is the file's.
  const auto rpy_deg = placement.Vec3("rpy_deg", {0.0, 0.0, 0.0}, -360.0, 360.0);
  placement.Finish();
  r.scene_placement.position = {position[0], position[1], position[2]};
  r.scene_placement.rotation = RotationFromRpyDeg({rpy_deg[0], rpy_deg[1], rpy_deg[2]});
  r.interface = root.String("interface", r.interface);
  r.interfaces = root.Strings("switchable_interfaces", r.interfaces);
  r.interfaces_dir = dir / root.String("interfaces_dir", "interfaces");
  r.database = root.String("database", r.database.string());
  r.vehicle_timeout_s = root.Number("vehicle_timeout_s", r.vehicle_timeout_s);
  r.session_rate_hz = root.Number("session_rate_hz", r.session_rate_hz);
  r.video_decode = root.Bool("video_decode", r.video_decode);
  r.person_time_limit_s = root.Number("person_time_limit_s", r.person_time_limit_s);
  r.switch_ramp_s = root.Number("switch_ramp_s", r.switch_ramp_s);

  YamlMap op = root.Map("operator");
  r.op.reaction_delay_s = op.Number("reaction_delay_s", r.op.reaction_delay_s);
  r.op.arm_time_constant_s = op.Number("arm_time_constant_s", r.op.arm_time_constant_s);
  r.op.lookahead = op.Number("lookahead", r.op.lookahead);
  r.op.cruise = op.Number("cruise", r.op.cruise);
  r.op.min_forward = op.Number("min_forward", r.op.min_forward);
  r.op.slow_radius = op.Number("slow_radius", r.op.slow_radius);
  r.op.muscle_stiffness = op.Number("muscle_stiffness", r.op.muscle_stiffness);
  r.op.muscle_damping = op.Number("muscle_damping", r.op.muscle_damping);
  r.op.muscle_max_force = op.Number("muscle_max_force", r.op.muscle_max_force);
  r.op.muscle_integral_gain = op.Number("muscle_integral_gain", r.op.muscle_integral_gain);
  r.op.backoff_s = op.Number("backoff_s", r.op.backoff_s);
  r.op.careful_s = op.Number("careful_s", r.op.careful_s);
  r.op.grasp_reach_s = op.Number("grasp_reach_s", r.op.grasp_reach_s);
  r.op.grasp_close_s = op.Number("grasp_close_s", r.op.grasp_close_s);
  op.Finish();

  YamlMap link = root.Map("link");
  r.link = config_detail::ReadLink(link, dir);
  root.Finish();
  config_detail::ValidateIn(root, r);
  return r;
}

std::filesystem::path InterfaceFile(const RunConfig& run, const std::string& name) {
  const std::filesystem::path file = run.interfaces_dir / (name + ".yaml");
  if (std::filesystem::exists(file)) return file;
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(run.interfaces_dir, ec)) {
    if (entry.path().extension() == ".yaml") names.push_back(entry.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
  throw ConfigError(run.file.string() + ": key 'interface': expected one of: " + list +
                    " (files in " + run.interfaces_dir.string() + "), got '" + name + "'");
}

std::string InterfaceName(const std::filesystem::path& file) {
  return YamlMap::Load(file).RequireString("name");
}

}  // namespace haptel
