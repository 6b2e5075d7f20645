#include "haptel/config/fleet.hpp"

#include <set>

#include "haptel/config/interface_kinds.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/config/yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;

namespace {

/// A file the fleet names: relative to the fleet file's folder, and there.
std::filesystem::path ExistingFile(YamlMap& map, const std::filesystem::path& dir,
                                   const std::string& key, const std::string& what) {
  const std::string written = map.RequireString(key);
  const std::filesystem::path file = dir / written;
  if (!std::filesystem::is_regular_file(file)) {
    map.Fail(key, what + " (relative to the fleet file's folder); there is no file '" +
                      file.string() + "'");
  }
  return file;
}

}  // namespace

FleetConfig LoadFleet(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  const std::filesystem::path dir = file.parent_path();
  FleetConfig fleet;
  fleet.file = file;
  fleet.name = root.RequireString("name");
  if (const std::string problem = VehicleNameProblem(fleet.name); !problem.empty())
    root.Fail("name", problem);
  fleet.slice_s = root.Number("slice_s", 0.0, 0.0, 3600.0);
  if (fleet.slice_s > 0.0 && fleet.slice_s < 1.0) {
    root.Fail("slice_s",
              "0 (a whole lap each) or at least 1 s (a handover takes a good part of a second)");
  }
  if (!root.Has("vehicles"))
    root.Fail("vehicles", "a list of 1 to 9 vehicles, each {name, vehicle, world}");
  std::vector<YamlMap> vehicles = root.MapList("vehicles");
  if (vehicles.empty() || vehicles.size() > static_cast<size_t>(kMaxFleetVehicles)) {
    root.Fail("vehicles",
              "a list of 1 to 9 vehicles, each {name, vehicle, world} (keys 1-9 pick one)");
  }
  std::set<std::string> names;
  for (YamlMap& v : vehicles) {
    FleetVehicle vehicle;
    vehicle.name = v.RequireString("name");
    if (const std::string problem = VehicleNameProblem(vehicle.name); !problem.empty())
      v.Fail("name", problem);
    if (!names.insert(vehicle.name).second) {
      v.Fail("name",
             "a name no other vehicle of the fleet has ('" + vehicle.name +
                 "' appears twice: two vehicles under one name on one domain are a conflict)");
    }
    vehicle.vehicle =
        ExistingFile(v, dir, "vehicle", "a vehicle file such as ../vehicles/sim-robot.yaml");
    vehicle.world = ExistingFile(v, dir, "world",
                                 "the track (robot) or course (blimp) file it drives or flies");
    vehicle.interface = v.String("interface", "");
    if (!vehicle.interface.empty()) {
      // Checked here, against the vehicle's kind, so the mistake is named at
      // its key: a robot's interface on a blimp, or a name that is none.
      const VehicleFamily family = LoadVehicle(vehicle.vehicle).family();
      const InterfaceKindInfo* kind = FindInterfaceKind(vehicle.interface);
      if (kind == nullptr || kind->family != family) {
        v.Fail("interface",
               "one of " + InterfaceKindNames(family) + " (the interfaces that drive a " +
                   (family == VehicleFamily::kBlimp ? "blimp" : "robot") + " such as '" +
                   vehicle.vehicle.filename().string() + "'), or no key for its kind's usual one");
      }
    }
    vehicle.attach = v.Bool("attach", false);
    if (v.Has("reality")) {
      vehicle.reality = ExistingFile(v, dir, "reality",
                                     "a reality file such as ../realities/lab.yaml (a simulated "
                                     "vehicle's hidden truth)");
    }
    v.Finish();
    fleet.vehicles.push_back(std::move(vehicle));
  }
  root.Finish();
  return fleet;
}

}  // namespace haptel
