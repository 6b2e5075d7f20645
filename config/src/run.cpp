#include "haptel/config/run.hpp"

#include <algorithm>

#include "haptel/config/archives.hpp"
#include "haptel/config/check.hpp"
#include "haptel/config/yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

void OperatorConfig::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  if (min_forward > cruise) check::Fail("min_forward", "min_forward <= cruise", {"cruise"});
}

const char* ToString(HeadSourceKind kind) {
  switch (kind) {
    case HeadSourceKind::kGamepad:
      return "gamepad";
    case HeadSourceKind::kOpenXr:
      return "openxr";
    case HeadSourceKind::kMouse:
      break;
  }
  return "mouse";
}

void HeadConfig::ValidateOrThrow() const { config_detail::CheckFields(*this); }
void ViewConfig::ValidateOrThrow() const { config_detail::CheckFields(*this); }

void RunConfig::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  if (interfaces.empty() || interfaces.size() > 6) {
    check::Fail("switchable_interfaces", "a list of 1 to 6 interface names (F1-F6)");
  }
  for (size_t i = 0; i < interfaces.size(); ++i) {
    check::NonEmpty("switchable_interfaces[" + std::to_string(i) + "]", interfaces[i]);
  }
  check::Nested("scene_placement", scene_placement);
}

RunConfig LoadRun(const std::filesystem::path& file) {
  return config_detail::LoadFile<RunConfig>(file, [&file](YamlMap& root, RunConfig& r) {
    const std::filesystem::path dir = file.parent_path();
    if (r.device.empty()) r.device = dir / "devices/sim.yaml";
    if (r.physics.empty()) r.physics = dir / "physics.yaml";
    if (r.interfaces_dir.empty()) r.interfaces_dir = dir / "interfaces";
    YamlMap placement = root.Map("scene_placement");
    const auto position = placement.Vec3("position", {0.0, 0.0, 0.0});
    // Only the rotation they make is kept (and checked): their range is the file's.
    const auto rpy_deg = placement.Vec3("rpy_deg", {0.0, 0.0, 0.0}, -360.0, 360.0);
    placement.Finish();
    r.scene_placement.position = {position[0], position[1], position[2]};
    r.scene_placement.rotation = RotationFromRpyDeg({rpy_deg[0], rpy_deg[1], rpy_deg[2]});
  });
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
