// The reality files (config/realities/*.yaml): the shipped ones load, one
// seed draws one robot and another seed another, `none` is the vehicle
// file's model exactly, and a mistake is refused naming file, key and what
// was expected. The truth record's lines read back what was written.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>

#include "haptel/config/error.hpp"
#include "haptel/config/reality.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/truth_format.hpp"
#include "haptel/config/vehicle.hpp"
#include "test_env.hpp"

using namespace haptel;
using Catch::Matchers::Contains;

namespace {

const VehicleConfig& Robot() {
  static const VehicleConfig robot = LoadVehicle("config/vehicles/sim-robot.yaml");
  return robot;
}
const Track& ShortTrack() {
  static const Track track(LoadTrack("config/tracks/test-short.yaml"));
  return track;
}
DrawnReality Draw(const std::string& name, uint64_t seed) {
  return DrawReality(LoadReality(RealityFile(name)), seed, Robot(), &ShortTrack());
}
/// Every drawn number, by name.
std::vector<std::pair<std::string, double>> Numbers(const DrawnReality& d) {
  std::vector<std::pair<std::string, double>> out;
  DrawnReality::ForEach(d, [&](const char* name, double v) { out.emplace_back(name, v); });
  for (const FloorPatch& p : d.floor_patches) {
    for (double v : {p.x, p.y, p.radius, p.traction}) out.emplace_back("floor_patch", v);
  }
  return out;
}

std::string RealityError(const std::string& text) {
  const auto file = test::WriteFile(test::ScratchDir("config-reality") / "bad.yaml", text);
  std::string message;
  try {
    LoadReality(file);
  } catch (const ConfigError& e) {
    message = e.what();
  }
  INFO(message);
  CHECK_THAT(message, Contains(file.string()));
  return message;
}

}  // namespace

TEST_CASE("a bare reality name is a shipped file; a path is itself") {
  CHECK(RealityFile("lab") == std::filesystem::path(RealityFile("lab")).parent_path() / "lab.yaml");
  CHECK(RealityFile("lab").parent_path().filename() == "realities");
  CHECK(RealityFile("my/lab.yaml") == std::filesystem::path("my/lab.yaml"));
  CHECK(RealityFile("lab.yaml") == std::filesystem::path("lab.yaml"));
}

TEST_CASE("none is the vehicle file's model exactly") {
  const DrawnReality none = Draw("none", 7);
  CHECK(none.name == "none");
  DrawnReality nominal = NominalReality(Robot());
  nominal.name = "none";
  nominal.seed = 7;
  CHECK(Numbers(none) == Numbers(nominal));
  CHECK(none.odometry == 0.0);
  CHECK(none.effective_track_width == Robot().drive.track_width);
}

TEST_CASE("one seed draws one robot, another seed another") {
  const DrawnReality a = Draw("lab", 3);
  CHECK(Numbers(a) == Numbers(Draw("lab", 3)));
  const DrawnReality b = Draw("lab", 4);
  CHECK(Numbers(a) != Numbers(b));
  CHECK(a.effective_track_width != b.effective_track_width);
  // Within what the lab file says: a skid-steer's width 1.35 ± 2 × 0.08 × geometric.
  for (const DrawnReality& d : {a, b}) {
    CHECK(d.effective_track_width / d.track_width >= 1.35 - 0.16 - 1e-12);
    CHECK(d.effective_track_width / d.track_width <= 1.35 + 0.16 + 1e-12);
    REQUIRE(d.floor_patches.size() == 2);
    for (const FloorPatch& p : d.floor_patches) {
      // On the corridor: within its half width of the centre line.
      const Vec2 at(p.x, p.y);
      const Vec2 nearest = ShortTrack().PointAt(ShortTrack().ClosestArcLength(at));
      CHECK((at - nearest).norm() <= 0.5 * ShortTrack().config().corridor_width + 1e-6);
    }
  }
  CHECK(Draw("harsh", 3).effective_track_width > Robot().drive.track_width * 1.3);
}

TEST_CASE("a lab's track stands off its file within the spread; none's is the file") {
  const Track& track = ShortTrack();
  const DrawnReality none = Draw("none", 3);
  CHECK(none.true_walls.empty());
  CHECK(none.true_posts.empty());
  CHECK(&TrueWalls(none, track) == &track.walls());
  CHECK(&TruePosts(none, track) == &track.round_obstacles());
  CHECK(none.range_spurious_fraction == 0.0);
  CHECK(none.range_dropout_fraction == 0.0);

  const RealityConfig lab = LoadReality(RealityFile("lab"));
  const MapErrorConfig& map = lab.robot.map_error;
  const DrawnReality d = Draw("lab", 3);
  CHECK(d.range_spurious_fraction == lab.robot.range_spurious_fraction);
  CHECK(d.range_spurious_fraction > 0.0);
  REQUIRE(d.true_walls.size() == track.walls().size());
  REQUIRE(d.true_posts.size() == track.round_obstacles().size());
  // Turned about the start by at most 2 sd, then each point by at most 2 sd per axis.
  const double turn = 2.0 * map.layout_rotation_deg.sd * std::numbers::pi / 180.0;
  const auto bound = [&](const Vec2& p, double sd) {
    return turn * (p - track.StartPosition()).norm() + 2.0 * sd * std::sqrt(2.0) + 1e-9;
  };
  bool moved = false;
  for (size_t i = 0; i < d.true_posts.size(); ++i) {
    const CircleObstacle& file = track.round_obstacles()[i];
    const double off = (d.true_posts[i].center - file.center).norm();
    CHECK(off <= bound(file.center, map.post_sd));
    CHECK(d.true_posts[i].radius == file.radius);
    moved = moved || off > 1e-3;
  }
  CHECK(moved);
  for (size_t i = 0; i < d.true_walls.size(); ++i) {
    const Segment2& file = track.walls()[i];
    CHECK((d.true_walls[i].a - file.a).norm() <= bound(file.a, map.wall_corner_sd));
    // Walls meeting at a corner in the file still meet there: the corner moved once.
    for (size_t j = 0; j < d.true_walls.size(); ++j) {
      if (track.walls()[j].a == file.b) CHECK(d.true_walls[j].a == d.true_walls[i].b);
    }
  }
  // One seed, one layout; another seed, another.
  CHECK(Draw("lab", 3).true_posts[0].center == d.true_posts[0].center);
  CHECK(Draw("lab", 4).true_posts[0].center != d.true_posts[0].center);
}

TEST_CASE("a reality file's mistakes name the file, the key and what was expected") {
  CHECK_THAT(RealityError("name: x\nrobot: {tread_gain: {mean: 1.0, sd: 0.0}, wobble: 2}\n"),
             Contains("wobble"));
  const std::string range =
      RealityError("name: x\nrobot:\n  track_width_factor: {mean: 0.8, sd: 0.1}\n");
  CHECK_THAT(range, Contains("robot.track_width_factor.mean"));
  CHECK_THAT(range, Contains("[1, 2.5]"));
  CHECK_THAT(RealityError("seed: 3\n"), Contains("name"));
  CHECK_THAT(RealityError("name: x\nrobot:\n  command_jitter_s: 2\n"),
             Contains("robot.command_jitter_s"));
  CHECK_THAT(RealityError("name: x\nrobot:\n  map_error: {post_sd: -0.1}\n"),
             Contains("robot.map_error.post_sd"));
  CHECK_THAT(RealityError("name: x\nrobot:\n  range_spurious_fraction: 0.9\n"),
             Contains("robot.range_spurious_fraction"));
}

TEST_CASE("a vehicle file's reality is a simulated kind's, and a path beside the file") {
  const auto dir = test::ScratchDir("config-vehicle-reality");
  const std::string robot = std::filesystem::absolute("config/vehicles/sim-robot.yaml").string();
  std::string text = "name: r\nkind: sim-robot\nreality: realities/lab.yaml\n";
  const VehicleConfig v = LoadVehicle(test::WriteFile(dir / "v.yaml", text));
  CHECK(v.reality == dir / "realities/lab.yaml");
  std::string message;
  try {
    LoadVehicle(test::WriteFile(dir / "ros.yaml",
                                "name: r\nkind: ros2\nros2: {}\nreality: ../realities/lab.yaml\n"));
  } catch (const ConfigError& e) {
    message = e.what();
  }
  CHECK_THAT(message, Contains("reality"));
  CHECK_THAT(message, Contains("simulated"));
}

TEST_CASE("the truth record's header and rows read back what was written") {
  const DrawnReality d = Draw("lab", 11);
  DrawnReality back;
  const std::string header = TruthHeaderText(d);
  size_t start = 0;
  bool columns = false;
  while (start < header.size()) {
    const size_t end = header.find('\n', start);
    const std::string line = header.substr(start, end - start);
    start = end + 1;
    if (IsTruthColumnLine(line)) {
      columns = true;
    } else {
      CHECK(ParseTruthHeaderLine(line, back));
    }
  }
  CHECK(columns);
  CHECK(back.name == "lab");
  CHECK(back.seed == 11);
  CHECK(Numbers(back) == Numbers(d));
  // Where the walls and posts truly stood, exactly.
  REQUIRE(back.true_walls.size() == d.true_walls.size());
  REQUIRE(back.true_posts.size() == d.true_posts.size());
  REQUIRE_FALSE(d.true_posts.empty());
  for (size_t i = 0; i < d.true_walls.size(); ++i) {
    CHECK(back.true_walls[i].a == d.true_walls[i].a);
    CHECK(back.true_walls[i].b == d.true_walls[i].b);
  }
  for (size_t i = 0; i < d.true_posts.size(); ++i) {
    CHECK(back.true_posts[i].center == d.true_posts[i].center);
    CHECK(back.true_posts[i].radius == d.true_posts[i].radius);
  }

  const TruthRow row{123456789012345, 1.5, -0.25, 0.0, 3.0, 0.3, -0.5};
  char text[256];
  const size_t n = FormatTruthRow(row, text, sizeof text);
  REQUIRE(n > 0);
  const TruthRow read = ParseTruthRow(std::string(text, n - 1));
  CHECK(read.operator_ns == row.operator_ns);
  CHECK(read.x == row.x);
  CHECK(read.heading == row.heading);
  CHECK(read.yaw_rate == row.yaw_rate);
  CHECK_THROWS_AS(ParseTruthRow("1,2,3"), std::invalid_argument);
  CHECK_THROWS_AS(ParseTruthHeaderLine("# wobble 3", back), std::invalid_argument);
}
