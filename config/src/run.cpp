#include "haptel/config/run.hpp"

#include <algorithm>

#include "link_section.hpp"
#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;

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
  const auto position = placement.Vec3("position", {0.0, 0.0, 0.0}, -100.0, 100.0);
  const auto rpy_deg = placement.Vec3("rpy_deg", {0.0, 0.0, 0.0}, -360.0, 360.0);
  placement.Finish();
  r.scene_placement.position = {position[0], position[1], position[2]};
  r.scene_placement.rotation = RotationFromRpyDeg({rpy_deg[0], rpy_deg[1], rpy_deg[2]});
  r.interface = root.String("interface", r.interface);
  r.interfaces = root.Strings("switchable_interfaces", r.interfaces);
  if (r.interfaces.empty() || r.interfaces.size() > 6) root.Fail("switchable_interfaces", "a list of 1 to 6 interface names (F1-F6)");
  r.interfaces_dir = dir / root.String("interfaces_dir", "interfaces");
  r.database = root.String("database", r.database.string());
  r.vehicle_timeout_s = root.Number("vehicle_timeout_s", r.vehicle_timeout_s, 0.05, 60.0);
  r.session_rate_hz = root.Number("session_rate_hz", r.session_rate_hz, 10.0, 1000.0);
  r.video_decode = root.Bool("video_decode", r.video_decode);
  r.person_time_limit_s = root.Number("person_time_limit_s", r.person_time_limit_s, 1.0, 86400.0);
  r.switch_ramp_s = root.Number("switch_ramp_s", r.switch_ramp_s, 0.01, 5.0);

  YamlMap op = root.Map("operator");
  r.op.reaction_delay_s = op.Number("reaction_delay_s", r.op.reaction_delay_s, 0.0, 2.0);
  r.op.arm_time_constant_s = op.Number("arm_time_constant_s", r.op.arm_time_constant_s, 0.0, 2.0);
  r.op.lookahead = op.Number("lookahead", r.op.lookahead, 0.05, 10.0);
  r.op.cruise = op.Number("cruise", r.op.cruise, 0.05, 1.0);
  r.op.min_forward = op.Number("min_forward", r.op.min_forward, 0.0, 1.0);
  r.op.slow_radius = op.Number("slow_radius", r.op.slow_radius, 0.0, 100.0);
  r.op.muscle_stiffness = op.Number("muscle_stiffness", r.op.muscle_stiffness, 1.0, 1e4);
  r.op.muscle_damping = op.Number("muscle_damping", r.op.muscle_damping, 0.0, 1e3);
  r.op.muscle_max_force = op.Number("muscle_max_force", r.op.muscle_max_force, 0.1, 100.0);
  r.op.muscle_integral_gain =
      op.Number("muscle_integral_gain", r.op.muscle_integral_gain, 0.0, 1e5);
  r.op.backoff_s = op.Number("backoff_s", r.op.backoff_s, 0.0, 10.0);
  r.op.grasp_reach_s = op.Number("grasp_reach_s", r.op.grasp_reach_s, 0.0, 10.0);
  r.op.grasp_close_s = op.Number("grasp_close_s", r.op.grasp_close_s, 0.0, 10.0);
  op.Finish();

  YamlMap link = root.Map("link");
  r.link = config_detail::ReadLink(link);
  root.Finish();
  if (r.op.min_forward > r.op.cruise) root.Fail("operator", "min_forward <= cruise");
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
