#pragma once
/// @file A fleet file (config/fleets/*.yaml): the vehicles one operator
/// drives in one run, one at a time (`haptel run --fleet FILE`).
///
/// ```yaml
/// name: three-robots
/// slice_s: 5            # the automatic operator's time slice (0: a whole lap each)
/// vehicles:
///   - {name: robot-a, vehicle: ../vehicles/sim-robot.yaml, world: ../tracks/test-short.yaml}
///   - {name: blimp-a, vehicle: ../vehicles/sim-blimp.yaml, world: ../tracks/blimp-hop.yaml,
///      interface: blimp-gesture, attach: true}
/// ```
///
/// Paths are relative to the fleet file's folder. Each vehicle's name is
/// its name on the DDS domain (its topics are `haptel/<name>/...`), so the
/// fleet's vehicles share one domain; `world` is the track a robot drives
/// or the course a blimp flies; `attach: true` drives a vehicle already
/// running under that name instead of spawning one. The files named are
/// loaded (and checked against each other) by `haptel run`; this loader
/// checks the fleet file itself: its keys, the names, that the files exist.
#include <filesystem>
#include <string>
#include <vector>

namespace haptel {

struct FleetVehicle {
  std::string name;               ///< on the domain and in the results
  std::filesystem::path vehicle;  ///< its vehicle file
  std::filesystem::path world;    ///< its track (robot) or course (blimp) file
  std::string interface;          ///< the interface it is driven with ("": the run's)
  bool attach = false;            ///< already running: spawn none
  /// Its reality (config/reality.hpp; a simulated vehicle's), over the
  /// vehicle file's and the run's --reality; empty: those.
  std::filesystem::path reality;
};

struct FleetConfig {
  std::filesystem::path file;
  std::string name;
  /// The automatic operator drives each vehicle at most this long before
  /// it turns to the next one whose course is not done; 0: until the lap
  /// is done. A person switches when they choose.
  double slice_s = 0.0;
  std::vector<FleetVehicle> vehicles;  ///< 1 to kMaxFleetVehicles, names unique
};

/// Keys 1..9 pick a vehicle: no more than that in one fleet.
constexpr int kMaxFleetVehicles = 9;

/// Loads and checks a fleet file. Throws ConfigError naming the file, the
/// line, the key (e.g. "vehicles[1].name") and what was expected.
FleetConfig LoadFleet(const std::filesystem::path& file);

}  // namespace haptel
