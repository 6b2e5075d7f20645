// End to end, the ROS 2 adapter (kind ros2) against an independent DDS: a
// ROS 2 differential-drive robot stood in for by haptel-ros2-standin, on
// Cyclone DDS. `haptel run` spawns haptel-vehicle with the adapter, which
// speaks Twist, Odometry, CompressedImage and LaserScan with the stand-in on
// a ROS domain of their own; the automatic operator drives the short track.
#include <signal.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "child.hpp"
#include "test_env.hpp"

using namespace haptel;
using haptel::test::Child;
using haptel::test::JsonField;

namespace {

std::string Bin(const std::string& name) { return (test::BinDir() / name).string(); }

/// The shipped ros2-robot.yaml with the robot's domain and an absolute world.
std::filesystem::path VehicleFile(const std::filesystem::path& dir, int ros_domain) {
  std::ifstream in("config/vehicles/ros2-robot.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), {});
  const auto replace = [&](const std::string& from, const std::string& to) {
    const size_t at = text.find(from);
    REQUIRE(at != std::string::npos);
    text.replace(at, from.size(), to);
  };
  replace("world: ../tracks/test-short.yaml",
          "world: " + std::filesystem::absolute("config/tracks/test-short.yaml").string());
  replace("  domain_id: 0                     # the robot's",
          "  domain_id: " + std::to_string(ros_domain) + "  #");
  return test::WriteFile(dir / "ros2-robot.yaml", text);
}

/// The stand-in robot's command line on `ros_domain` (its top speed the vehicle file's
/// drive.max_speed).
std::vector<std::string> StandIn(int ros_domain) {
  return {Bin("haptel-ros2-standin"),
          "--domain",
          std::to_string(ros_domain),
          "--unicast",
          "127.0.0.1",
          "--max-speed",
          "0.3"};
}

/// `haptel run` of the short track with the vehicle file in `dir`, on a domain of its own.
std::vector<std::string> Lap(const std::filesystem::path& dir, const std::filesystem::path& vehicle,
                             int salt) {
  return {Bin("haptel"),
          "run",
          "--vehicle",
          vehicle.string(),
          "--track",
          "config/tracks/test-short.yaml",
          "--domain",
          std::to_string(test::UniqueDomain(salt)),
          "--database",
          (dir / "runs.db").string(),
          "--json",
          "--vehicle-timeout",
          "5"};
}

}  // namespace

TEST_CASE(
    "the ROS 2 adapter drives a Cyclone DDS robot round the short track, its camera on the "
    "operator's screen, "
    "its laser in the operator's state") {
  const auto dir = test::ScratchDir("e2e-ros2");
  const int ros_domain = test::UniqueDomain(41);
  const auto vehicle = VehicleFile(dir, ros_domain);
  Child robot(StandIn(ros_domain));
  REQUIRE(test::WaitForErr(robot, "up on domain", 30.0));
  Child run(Lap(dir, vehicle, 40));
  const int code = run.Wait(180.0);
  INFO(run.out() << run.err());
  CHECK(code == 0);
  const std::string json = run.LastLine();
  CHECK(JsonField(json, "outcome") == "completed");
  CHECK(JsonField(json, "gates_passed") == "2");
  CHECK(JsonField(json, "vehicle_kind") == "ros2");
  // The stand-in's camera (CompressedImage) came through to the mediator.
  CHECK(std::stoi(JsonField(json, "video_frames")) > 10);
  // Its JPEGs are the vehicle file's size (320x240) and fit the link: they
  // went to the operator as the robot made them, neither decoded nor encoded.
  CHECK(run.err().find("passed through as the camera made them") != std::string::npos);
  // The stand-in's 360-beam LaserScan reached the operator's state as the
  // range field: 30 sectors of 12 degrees all round (each at its middle),
  // up to the laser's 8 m.
  const size_t said = run.err().find("range sensors: 30 beams from -17");
  CHECK(said != std::string::npos);
  CHECK(run.err().find("up to 8.00 m", said) != std::string::npos);
  // The vehicle names the robot's graph it joined.
  CHECK(run.err().find("ROS 2 robot on domain " + std::to_string(ros_domain)) != std::string::npos);

  // The robot obeyed twists and drove the lap the mediator measured (about 2.9 m).
  REQUIRE(kill(robot.pid(), SIGTERM) == 0);
  REQUIRE(robot.Wait(30.0) == 0);
  const std::string done = robot.LastLine();
  INFO(robot.err());
  CHECK(std::stoi(JsonField(done, "twists")) > 50);
  CHECK(JsonField(done, "twists_dropped") == "0");
  CHECK(std::stoi(JsonField(done, "scans_published")) > 10);
  CHECK(std::stod(JsonField(done, "distance_m")) > 2.5);
}

TEST_CASE(
    "a ROS 2 robot that goes silent mid-lap is reported lost and the run made safe (exit 3)") {
  const auto dir = test::ScratchDir("e2e-ros2-silent");
  const int ros_domain = test::UniqueDomain(43);
  const auto vehicle = VehicleFile(dir, ros_domain);
  Child robot(StandIn(ros_domain));
  REQUIRE(test::WaitForErr(robot, "up on domain", 30.0));
  Child run(Lap(dir, vehicle, 42));
  // Driving: the first progress line with a lap clock running.
  REQUIRE(test::WaitFor(
      [&] {
        run.Pump();
        return run.err().find("gates 1/2") != std::string::npos;
      },
      120.0));
  REQUIRE(kill(robot.pid(), SIGKILL) == 0);
  const int code = run.Wait(60.0);
  INFO(run.out() << run.err());
  CHECK(code == 3);
  CHECK(JsonField(run.LastLine(), "outcome") == "vehicle lost");
  CHECK(run.err().find("ROS 2 robot silent: no odometry on /odom") != std::string::npos);
}
