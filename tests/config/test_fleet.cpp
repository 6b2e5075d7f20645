// The fleet file (config/fleets/*.yaml): the shipped ones load, and every
// mistake is refused naming the file, the key and what was expected.
#include <catch2/catch.hpp>
#include <filesystem>
#include <string>

#include "haptel/config/error.hpp"
#include "haptel/config/fleet.hpp"
#include "test_env.hpp"

using Catch::Matchers::Contains;
namespace fs = std::filesystem;

namespace {

/// The ConfigError `LoadFleet` throws for a fleet file of `text` (its
/// vehicles' files named by absolute paths, so it can live in a scratch folder).
std::string FleetError(const std::string& text) {
  const fs::path file = haptel::test::ScratchDir("config-fleet") / "fleet.yaml";
  haptel::test::WriteFile(file, text);
  std::string message;
  try {
    haptel::LoadFleet(file);
  } catch (const haptel::ConfigError& e) {
    message = e.what();
  }
  INFO(message);
  CHECK_THAT(message, Contains(file.string()));
  return message;
}

const std::string kRobot = fs::absolute("config/vehicles/sim-robot.yaml").string();
const std::string kTrack = fs::absolute("config/tracks/test-short.yaml").string();

std::string Vehicle(const std::string& name, const std::string& extra = "") {
  // Appended piece by piece: GCC 12 warns falsely on a long chain of + here.
  std::string line = "  - {name: ";
  line.append(name).append(", vehicle: ").append(kRobot).append(", world: ").append(kTrack);
  return line.append(extra).append("}\n");
}

}  // namespace

TEST_CASE("the shipped fleet files load: names, files beside them, the time slice") {
  const haptel::FleetConfig three = haptel::LoadFleet("config/fleets/three-robots.yaml");
  CHECK(three.name == "three-robots");
  REQUIRE(three.vehicles.size() == 3);
  CHECK(three.vehicles[1].name == "robot-b");
  CHECK(fs::is_regular_file(three.vehicles[1].vehicle));
  CHECK(three.vehicles[1].world.filename() == "test-short.yaml");
  CHECK_FALSE(three.vehicles[2].attach);
  CHECK(three.slice_s > 0.0);

  const haptel::FleetConfig mixed = haptel::LoadFleet("config/fleets/robot-and-blimp.yaml");
  REQUIRE(mixed.vehicles.size() == 2);
  CHECK(mixed.vehicles[1].interface == "blimp-gesture");

  // Issue 30's target: three robots, then the blimp (`haptel bench fleet` takes the first 1..4).
  const haptel::FleetConfig four = haptel::LoadFleet("config/fleets/four.yaml");
  REQUIRE(four.vehicles.size() == 4);
  for (int i = 0; i < 3; ++i)
    CHECK(four.vehicles[static_cast<size_t>(i)].vehicle.filename() == "sim-robot.yaml");
  CHECK(four.vehicles[3].vehicle.filename() == "sim-blimp.yaml");
  CHECK(four.vehicles[3].world.filename() == "blimp-hop.yaml");
  CHECK(four.vehicles[3].interface == "blimp-gesture");
  CHECK(four.slice_s > 0.0);
}

TEST_CASE("a fleet file's mistakes are refused naming the key and what was expected") {
  SECTION("no vehicles") {
    CHECK_THAT(FleetError("name: f\n"), Contains("'vehicles'") && Contains("1 to 9"));
    CHECK_THAT(FleetError("name: f\nvehicles: []\n"), Contains("'vehicles'"));
  }
  SECTION("a name twice: two vehicles under one name on one domain") {
    CHECK_THAT(FleetError("name: f\nvehicles:\n" + Vehicle("a") + Vehicle("a")),
               Contains("'vehicles[1].name'") && Contains("appears twice"));
  }
  SECTION("a name that cannot be part of a topic name") {
    CHECK_THAT(FleetError("name: f\nvehicles:\n" + Vehicle("robot a")),
               Contains("'vehicles[0].name'"));
  }
  SECTION("a vehicle file that is not there") {
    CHECK_THAT(
        FleetError("name: f\nvehicles:\n  - {name: a, vehicle: ../vehicles/nope.yaml, world: " +
                   kTrack + "}\n"),
        Contains("'vehicles[0].vehicle'") && Contains("nope.yaml"));
  }
  SECTION("a missing world") {
    CHECK_THAT(FleetError("name: f\nvehicles:\n  - {name: a, vehicle: " + kRobot + "}\n"),
               Contains("'vehicles[0].world'"));
  }
  SECTION("an unknown key, in a vehicle or at the top") {
    CHECK_THAT(FleetError("name: f\nvehicles:\n" + Vehicle("a", ", spawn: yes")),
               Contains("spawn"));
    CHECK_THAT(FleetError("name: f\nslices: 3\nvehicles:\n" + Vehicle("a")), Contains("slices"));
  }
  SECTION("a time slice too short for a handover, or negative") {
    CHECK_THAT(FleetError("name: f\nslice_s: 0.2\nvehicles:\n" + Vehicle("a")),
               Contains("'slice_s'"));
    CHECK_THAT(FleetError("name: f\nslice_s: -1\nvehicles:\n" + Vehicle("a")),
               Contains("'slice_s'"));
  }
  SECTION("more vehicles than keys 1-9") {
    std::string text = "name: f\nvehicles:\n";
    for (const char* name : {"r0", "r1", "r2", "r3", "r4", "r5", "r6", "r7", "r8", "r9"})
      text += Vehicle(name);
    CHECK_THAT(FleetError(text), Contains("'vehicles'") && Contains("1 to 9"));
  }
  SECTION("an interface that does not drive the vehicle's kind, or is none") {
    CHECK_THAT(
        FleetError("name: f\nvehicles:\n" + Vehicle("a", ", interface: blimp-keys")),
        Contains("'vehicles[0].interface'") && Contains("keyboard") && Contains("blimp-keys"));
    CHECK_THAT(
        FleetError("name: f\nvehicles:\n" + Vehicle("a") + Vehicle("b", ", interface: wheel")),
        Contains("'vehicles[1].interface'") && Contains("cockpit") && Contains("'wheel'"));
  }
  SECTION("attach is a yes or no") {
    CHECK_THAT(FleetError("name: f\nvehicles:\n" + Vehicle("a", ", attach: maybe")),
               Contains("'vehicles[0].attach'"));
  }
}
