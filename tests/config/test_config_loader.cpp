// The strict config loader: every shipped file loads with the values it says;
// every kind of bad file is a ConfigError naming the file, the line and the key.
// Runs from the repository root (ctest sets the working directory).
#include <sys/stat.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "haptel/config/cockpit.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/gesture.hpp"
#include "haptel/config/keyboard.hpp"
#include "haptel/config/run.hpp"
#include "haptel/config/scene.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "test_env.hpp"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using haptel::ConfigError;

namespace {

std::string ReadText(const fs::path& file) {
  std::ifstream in(file);
  REQUIRE(in.good());
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// 1-based number of the first line of text that contains marker.
int LineOf(const std::string& text, const std::string& marker) {
  const auto lines = Lines(text);
  for (size_t i = 0; i < lines.size(); ++i) {
    if (lines[i].find(marker) != std::string::npos) return static_cast<int>(i) + 1;
  }
  FAIL("marker '" << marker << "' not in the fixture");
  return 0;
}

// The value text of the first "key: value" line (any indentation), comment
// and surrounding blanks removed: an independent reading of a shipped file.
std::string ValueText(const std::string& text, const std::string& key) {
  for (const auto& line : Lines(text)) {
    const auto start = line.find_first_not_of(' ');
    if (start == std::string::npos || line.compare(start, key.size() + 1, key + ":") != 0) continue;
    std::string v = line.substr(start + key.size() + 1);
    if (const auto hash = v.find('#'); hash != std::string::npos) v.resize(hash);
    const auto b = v.find_first_not_of(' ');
    const auto e = v.find_last_not_of(' ');
    return b == std::string::npos ? "" : v.substr(b, e - b + 1);
  }
  FAIL("key '" << key << "' not in the file");
  return "";
}

double NumberIn(const std::string& text, const std::string& key) {
  return std::stod(ValueText(text, key));
}

// The point "[x, y]" that starts at or after pos in line.
haptel::Vec2 PointIn(const std::string& line, size_t pos) {
  const auto open = line.find('[', pos);
  const auto comma = line.find(',', open);
  const auto close = line.find(']', comma);
  REQUIRE(open != std::string::npos);
  REQUIRE(comma != std::string::npos);
  REQUIRE(close != std::string::npos);
  return {std::stod(line.substr(open + 1, comma - open - 1)),
          std::stod(line.substr(comma + 1, close - comma - 1))};
}

// The number after each occurrence of key (one per line), in file order.
std::vector<double> NumbersAfter(const std::string& text, const std::string& key) {
  std::vector<double> out;
  for (const auto& line : Lines(text)) {
    const auto pos = line.find(key);
    if (pos != std::string::npos) out.push_back(std::stod(line.substr(pos + key.size())));
  }
  return out;
}

// The point after each occurrence of key (one per line), in file order.
std::vector<haptel::Vec2> PointsAfter(const std::string& text, const std::string& key) {
  std::vector<haptel::Vec2> out;
  for (const auto& line : Lines(text)) {
    const auto pos = line.find(key);
    if (pos != std::string::npos) out.push_back(PointIn(line, pos + key.size()));
  }
  return out;
}

// The block list of points under the top-level "centerline:" key.
std::vector<haptel::Vec2> CentrelineIn(const std::string& text) {
  std::vector<haptel::Vec2> out;
  bool inside = false;
  for (const auto& line : Lines(text)) {
    if (line.rfind("centerline:", 0) == 0) {
      inside = true;
    } else if (inside && line.rfind("  - [", 0) == 0) {
      out.push_back(PointIn(line, 0));
    } else if (inside && !line.empty() && line[0] != ' ' && line[0] != '#') {
      break;
    }
  }
  return out;
}

// A per-process scratch directory, removed at the end of the test case.
class TempDir {
 public:
  TempDir() {
    const char* env = std::getenv("HAPTEL_TEST_TMP");
    const fs::path base =
        env != nullptr && *env != '\0' ? fs::path(env) : fs::temp_directory_path();
    dir_ = base / ("test_config-" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  fs::path Write(const std::string& name, const std::string& text) const {
    const fs::path file = dir_ / name;
    std::ofstream out(file);
    out << text;
    REQUIRE(out.good());
    return file;
  }
  const fs::path& path() const { return dir_; }

 private:
  fs::path dir_;
};

// The message of the ConfigError that f throws.
template <typename F>
std::string ErrorOf(F&& f) {
  return haptel::test::WhatOf<ConfigError>(std::forward<F>(f));
}

std::string LineTag(int line) {
  // Appended piecewise: GCC 12 warns falsely (-Wrestrict) on ":" + std::string.
  std::string tag = ":";
  tag += std::to_string(line);
  tag += ':';
  return tag;
}

// A valid rectangular track (14 m of centre line) with the given gate lines.
std::string TrackText(const std::string& gates, const std::string& extra = "post_radius: 0.04\n") {
  return "name: fixture\n"
         "corridor_width: 1.0\n" +
         extra +
         "centerline:\n"
         "  - [0.0, 0.0]\n"
         "  - [4.0, 0.0]\n"
         "  - [4.0, 3.0]\n"
         "  - [0.0, 3.0]\n"
         "gates:\n" +
         gates;
}

}  // namespace

// ---------------------------------------------------------------- shipped files

TEST_CASE("Shipped run config loads and resolves its paths", "[config][shipped]") {
  const fs::path file = "config/haptel.yaml";
  const std::string text = ReadText(file);
  const haptel::RunConfig r = haptel::LoadRun(file);

  CHECK(r.file == file);
  CHECK(r.name == ValueText(text, "name"));
  CHECK(r.interface == ValueText(text, "interface"));
  // Config paths are relative to the config file ...
  CHECK(r.track == file.parent_path() / ValueText(text, "track"));
  CHECK(r.vehicle == file.parent_path() / ValueText(text, "vehicle"));
  CHECK(fs::is_regular_file(r.track));
  CHECK(fs::is_regular_file(r.vehicle));
  CHECK(fs::is_directory(r.interfaces_dir));
  // ... the database is relative to the working directory.
  CHECK(r.database == fs::path(ValueText(text, "database")));

  CHECK(r.vehicle_timeout_s == NumberIn(text, "vehicle_timeout_s"));
  CHECK(r.session_rate_hz == NumberIn(text, "session_rate_hz"));
  CHECK(r.video_decode == (ValueText(text, "video_decode") == "true"));
  CHECK(r.op.reaction_delay_s == NumberIn(text, "reaction_delay_s"));
  CHECK(r.op.lookahead == NumberIn(text, "lookahead"));
  CHECK(r.op.cruise == NumberIn(text, "cruise"));
  CHECK(r.op.min_forward == NumberIn(text, "min_forward"));
  CHECK(r.op.backoff_s == NumberIn(text, "backoff_s"));
  CHECK(std::filesystem::exists(r.device));
  CHECK(r.link.domain_id == static_cast<int>(NumberIn(text, "domain_id")));
  CHECK(r.link.command_deadline_s == NumberIn(text, "command_deadline_s"));
  std::string keys;
  for (const auto& n : r.interfaces) keys += (keys.empty() ? "" : ", ") + n;
  CHECK("[" + keys + "]" == ValueText(text, "switchable_interfaces"));
  CHECK(r.switch_ramp_s == NumberIn(text, "switch_ramp_s"));
  CHECK(r.person_time_limit_s == NumberIn(text, "person_time_limit_s"));
  REQUIRE(r.link.interfaces.size() == 1);
  CHECK("[" + r.link.interfaces[0] + "]" == ValueText(text, "interfaces"));
  REQUIRE(r.link.peers.size() == 1);
  CHECK("[" + r.link.peers[0] + "]" == ValueText(text, "peers"));
  // Keys the file leaves out keep their defaults.
  if (text.find("muscle_stiffness") == std::string::npos) {
    CHECK(r.op.muscle_stiffness == haptel::OperatorConfig{}.muscle_stiffness);
  }

  // The files it points at load too.
  CHECK_NOTHROW(haptel::LoadTrack(r.track));
  CHECK_NOTHROW(haptel::LoadVehicle(r.vehicle));
  CHECK_NOTHROW(haptel::LoadGesture(haptel::InterfaceFile(r, r.interface)));
}

TEST_CASE("Run config paths resolve against the file wherever it is named from",
          "[config][shipped]") {
  const fs::path absolute = fs::absolute("config/haptel.yaml");
  const haptel::RunConfig r = haptel::LoadRun(absolute);
  CHECK(r.track.is_absolute());
  CHECK(fs::is_regular_file(r.track));
  CHECK(fs::is_regular_file(r.vehicle));
  const haptel::RunConfig rel = haptel::LoadRun("config/haptel.yaml");
  CHECK(fs::equivalent(r.track, rel.track));
  CHECK(fs::equivalent(r.vehicle, rel.vehicle));
  CHECK(fs::equivalent(r.interfaces_dir, rel.interfaces_dir));
}

TEST_CASE("Run config: scene_placement (identity when shipped, a position and roll/pitch/yaw)",
          "[config]") {
  const haptel::RunConfig shipped = haptel::LoadRun("config/haptel.yaml");
  CHECK(shipped.scene_placement.IsIdentity());

  TempDir tmp;
  const fs::path file = tmp.Write("placed.yaml",
                                  "track: t.yaml\n"
                                  "vehicle: v.yaml\n"
                                  "scene_placement:\n"
                                  "  position: [0.1, -0.2, -0.75]\n"
                                  "  rpy_deg: [0, 0, 90]\n");
  const haptel::RunConfig r = haptel::LoadRun(file);
  CHECK(r.scene_placement.position.isApprox(Eigen::Vector3d(0.1, -0.2, -0.75)));
  // Yaw 90°: forward (x) turns to the left (y).
  CHECK((r.scene_placement.rotation * Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitY()).norm() <
        1e-12);
  CHECK_FALSE(r.scene_placement.IsIdentity());

  const std::string text =
      "track: t.yaml\n"
      "vehicle: v.yaml\n"
      "scene_placement: {position: [0, 0, 0], rpy: [0, 0, 90]}\n";
  const fs::path bad = tmp.Write("placed-bad.yaml", text);
  const std::string msg = ErrorOf([&] { haptel::LoadRun(bad); });
  CHECK_THAT(msg, Contains("'scene_placement.rpy'") && Contains(LineTag(3)));
}

TEST_CASE("Run config: the head that turns the camera and the view's stereo (head:, view:)",
          "[config]") {
  const haptel::RunConfig shipped = haptel::LoadRun("config/haptel.yaml");
  CHECK(shipped.head.source == haptel::HeadSourceKind::kMouse);
  CHECK(shipped.head.stick_rate_rad_s == 1.5);
  CHECK_FALSE(shipped.view.stereo);
  CHECK(shipped.view.ipd_m == 0.064);

  TempDir tmp;
  const haptel::RunConfig r = haptel::LoadRun(
      tmp.Write("head.yaml",
                "track: t.yaml\nvehicle: v.yaml\nhead: {source: gamepad, stick_dead_zone: 0.2}\n"
                "view: {stereo: true, ipd_m: 0.07}\n"));
  CHECK(r.head.source == haptel::HeadSourceKind::kGamepad);
  CHECK(r.head.stick_dead_zone == 0.2);
  CHECK(r.view.stereo);
  CHECK(r.view.ipd_m == 0.07);
  const std::string bad_source = ErrorOf([&] {
    haptel::LoadRun(
        tmp.Write("bad-head.yaml", "track: t.yaml\nvehicle: v.yaml\nhead: {source: kinect}\n"));
  });
  CHECK_THAT(bad_source, Contains("bad-head.yaml") && Contains("'head.source'") &&
                             Contains("mouse") && Contains("openxr"));
  const std::string bad_ipd = ErrorOf([&] {
    haptel::LoadRun(
        tmp.Write("bad-ipd.yaml", "track: t.yaml\nvehicle: v.yaml\nview: {ipd_m: 64}\n"));
  });
  CHECK_THAT(bad_ipd, Contains("bad-ipd.yaml") && Contains("'view.ipd_m'"));
}

TEST_CASE("Shipped tracks load with the values their files give", "[config][shipped]") {
  const std::string name = GENERATE(as<std::string>{}, "grand-prix", "test-short");
  const fs::path file = "config/tracks/" + name + ".yaml";
  INFO("track " << file);
  const std::string text = ReadText(file);
  const haptel::TrackConfig t = haptel::LoadTrack(file);
  CHECK(t.name == name);
  CHECK(t.file == file);
  CHECK(t.corridor_width == NumberIn(text, "corridor_width"));
  CHECK(t.post_radius == NumberIn(text, "post_radius"));
  CHECK(t.start_behind == NumberIn(text, "start_behind"));
  CHECK(t.lap_cap_s == NumberIn(text, "lap_cap_s"));
  // Optional: a track without a known expert lap has no baseline.
  if (text.find("reference_lap_s:") != std::string::npos) {
    CHECK(t.reference_lap_s == NumberIn(text, "reference_lap_s"));
  } else {
    CHECK_FALSE(t.reference_lap_s.has_value());
  }

  const std::vector<haptel::Vec2> points = CentrelineIn(text);
  REQUIRE(points.size() >= 3);
  REQUIRE(t.centerline.size() == points.size());
  for (size_t i = 0; i < points.size(); ++i) CHECK(t.centerline[i] == points[i]);

  const std::vector<double> along = NumbersAfter(text, "along:");
  REQUIRE(!along.empty());
  REQUIRE(t.gates.size() == along.size());
  for (size_t i = 0; i < along.size(); ++i) {
    CHECK(t.gates[i].along == along[i]);
    // No per-gate width in the shipped tracks: the file-wide gate_width applies.
    CHECK(t.gates[i].width == NumberIn(text, "gate_width"));
  }

  // Obstacles: "{center: [x, y], radius: r}" ("post_radius:" has no blank before "radius:").
  const std::vector<haptel::Vec2> centres = PointsAfter(text, "center:");
  const std::vector<double> radii = NumbersAfter(text, " radius:");
  REQUIRE(radii.size() == centres.size());
  REQUIRE(t.obstacles.size() == centres.size());
  for (size_t i = 0; i < centres.size(); ++i) {
    CHECK(t.obstacles[i].center == centres[i]);
    CHECK(t.obstacles[i].radius == radii[i]);
  }
}

TEST_CASE("Shipped grand prix has the thesis's five gates", "[config][shipped]") {
  const haptel::TrackConfig t = haptel::LoadTrack("config/tracks/grand-prix.yaml");
  CHECK(t.gates.size() == 5);
  CHECK(t.lap_cap_s == 600.0);  // the 10-minute cap
  // The thesis's optimum, 1 min 30 s by keyboard in direct view (section 8.1).
  REQUIRE(t.reference_lap_s.has_value());
  CHECK(*t.reference_lap_s == 90.0);
  CHECK_FALSE(t.obstacles.empty());
}

TEST_CASE("Shipped sim-robot vehicle loads", "[config][shipped]") {
  const fs::path file = "config/vehicles/sim-robot.yaml";
  const std::string text = ReadText(file);
  const haptel::VehicleConfig v = haptel::LoadVehicle(file);
  CHECK(v.name == ValueText(text, "name"));
  CHECK(v.kind == "sim-robot");
  CHECK(fs::is_regular_file(v.world));
  CHECK(fs::equivalent(v.world, "config/tracks/grand-prix.yaml"));
  CHECK(v.sim_rate_hz == NumberIn(text, "sim_rate_hz"));
  CHECK(v.state_rate_hz == NumberIn(text, "state_rate_hz"));
  CHECK(v.watchdog_timeout_s == NumberIn(text, "watchdog_timeout_s"));
  CHECK(v.drive.speed_levels == 8);
  CHECK(v.drive.max_speed == NumberIn(text, "max_speed"));
  CHECK(v.drive.track_width == NumberIn(text, "track_width"));
  CHECK(v.drive.left_gain == NumberIn(text, "left_gain"));
  CHECK(v.drive.right_gain == NumberIn(text, "right_gain"));
  CHECK(v.body.radius == NumberIn(text, "radius"));
  CHECK(v.body.bumper_half_angle_deg == NumberIn(text, "bumper_half_angle_deg"));
  CHECK(v.camera.rate_hz == NumberIn(text, "rate_hz"));
  CHECK(v.camera.width == static_cast<int>(NumberIn(text, "width")));
  CHECK(v.camera.height == static_cast<int>(NumberIn(text, "height")));
  CHECK(v.camera.jpeg_quality == static_cast<int>(NumberIn(text, "jpeg_quality")));
  // fov_deg is both the range scan's and the camera's: each read in its own section.
  const std::string camera = text.substr(text.find("\ncamera:"));
  const std::string ranges = text.substr(text.find("\nrange_sensors:"));
  CHECK(v.camera.fov_deg == NumberIn(camera, "fov_deg"));
  CHECK(v.range_sensors.fov_deg == NumberIn(ranges, "fov_deg"));
  CHECK(v.range_sensors.beams == static_cast<int>(NumberIn(ranges, "beams")));
  CHECK(v.camera.source == haptel::CameraSourceKind::kSynthetic);
  CHECK(ValueText(text, "source") == haptel::CameraSourceName(v.camera.source));
  CHECK(v.link.domain_id == static_cast<int>(NumberIn(text, "domain_id")));
}

TEST_CASE("Shipped gesture interface loads", "[config][shipped]") {
  const fs::path file = "config/interfaces/gesture.yaml";
  const std::string text = ReadText(file);
  const haptel::GestureConfig g = haptel::LoadGesture(file);
  CHECK(g.name == "gesture");
  CHECK(g.file == file);
  CHECK(g.neutral == std::array<double, 3>{0.0, 0.0, 0.0});
  CHECK(g.dead_zone == NumberIn(text, "dead_zone"));
  CHECK(g.full_forward == NumberIn(text, "full_forward"));
  CHECK(g.full_turn == NumberIn(text, "full_turn"));
  CHECK(g.turn_share == NumberIn(text, "turn_share"));
  CHECK(g.field_stiffness == NumberIn(text, "field_stiffness"));
  CHECK(g.field_stiffness_growth == NumberIn(text, "field_stiffness_growth"));
  CHECK(g.field_damping == NumberIn(text, "field_damping"));
  CHECK(g.wall_stiffness == NumberIn(text, "wall_stiffness"));
  CHECK(g.wall_release_s == NumberIn(text, "wall_release_s"));
  CHECK(g.command_rate_hz == NumberIn(text, "command_rate_hz"));
}

TEST_CASE("Shipped gesture-shared interface loads, with its shared control", "[config][shipped]") {
  const fs::path file = "config/interfaces/gesture-shared.yaml";
  const std::string text = ReadText(file);
  const haptel::GestureConfig g = haptel::LoadGesture(file);
  CHECK(g.name == "gesture-shared");
  REQUIRE(g.shared_control.enabled);
  CHECK(g.shared_control.horizon_s == NumberIn(text, "horizon_s"));
  CHECK(g.shared_control.max_force == NumberIn(text, "max_force"));
  CHECK(g.shared_control.stiffness == NumberIn(text, "stiffness"));
  CHECK(g.shared_control.clearance == NumberIn(text, "clearance"));
  CHECK_FALSE(haptel::LoadGesture("config/interfaces/gesture.yaml").shared_control.enabled);
}

TEST_CASE("Shared control's section is checked strictly", "[config]") {
  TempDir tmp;
  const std::string shared = "name: gesture-shared\nshared_control:\n";
  SECTION("a key it does not know") {
    const fs::path file = tmp.Write("s.yaml", shared + "  horizon_s: 1.0\n  strength: 2\n");
    CHECK_THAT(ErrorOf([&] { haptel::LoadGesture(file); }),
               Contains(file.string()) && Contains("strength"));
  }
  SECTION("a force no one could push through") {
    const fs::path file = tmp.Write("s.yaml", shared + "  max_force: 50\n");
    const std::string msg = ErrorOf([&] { haptel::LoadGesture(file); });
    CHECK_THAT(msg, Contains(file.string()) && Contains("shared_control.max_force") &&
                        Contains("[0, 15]"));
  }
  SECTION("gesture-shared without it") {
    const fs::path file = tmp.Write("s.yaml", "name: gesture-shared\n");
    CHECK_THAT(ErrorOf([&] { haptel::LoadGesture(file); }), Contains("'shared_control'"));
  }
  SECTION("plain gesture with it") {
    const fs::path file = tmp.Write("s.yaml", "name: gesture\nshared_control:\n  horizon_s: 1.0\n");
    CHECK_THAT(ErrorOf([&] { haptel::LoadGesture(file); }), Contains("'shared_control'"));
  }
}

TEST_CASE("Shipped cockpit-shared interface loads: the cockpit with shared control",
          "[config][shipped]") {
  const fs::path file = "config/interfaces/cockpit-shared.yaml";
  const std::string text = ReadText(file);
  const haptel::CockpitConfig c = haptel::LoadCockpit(file);
  CHECK(c.name == "cockpit-shared");
  REQUIRE(c.shared_control.enabled);
  CHECK(c.shared_control.horizon_s == NumberIn(text, "horizon_s"));
  CHECK(c.shared_control.max_force == NumberIn(text, "max_force"));
  CHECK(c.shared_control.stiffness == NumberIn(text, "stiffness"));
  CHECK(c.shared_control.clearance == NumberIn(text, "clearance"));
  for (const char* plain : {"cockpit", "cockpit-hud", "cockpit-assisted"}) {
    INFO(plain);
    CHECK_FALSE(haptel::LoadCockpit(fs::path("config/interfaces") / (std::string(plain) + ".yaml"))
                    .shared_control.enabled);
  }
}

TEST_CASE(
    "An interface file naming an interface its loader does not load is refused, with the names it "
    "does",
    "[config]") {
  // The names come from the interface catalogue (each interface registers
  // the config its file loads into), not from a list in the loader.
  TempDir tmp;
  const fs::path gesture_named = tmp.Write("g.yaml", "name: cockpit\n");
  CHECK_THAT(ErrorOf([&] { haptel::LoadGesture(gesture_named); }),
             Contains("key 'name': expected 'gesture' or 'gesture-shared'"));
  const fs::path cockpit_named = tmp.Write("c.yaml", "name: gesture\n");
  CHECK_THAT(ErrorOf([&] { haptel::LoadCockpit(cockpit_named); }),
             Contains("key 'name': expected one of: cockpit, cockpit-hud, cockpit-assisted, "
                      "cockpit-shared"));
  const fs::path keys_named = tmp.Write("k.yaml", "name: gamepad\n");
  CHECK_THAT(ErrorOf([&] { haptel::LoadKeyboard(keys_named); }),
             Contains("key 'name': expected 'keyboard'"));
}

TEST_CASE("A cockpit's shared control section: only on cockpit-shared, checked strictly",
          "[config]") {
  TempDir tmp;
  const std::string base = ReadText("config/interfaces/cockpit-shared.yaml");
  const std::string without = base.substr(0, base.find("shared_control:"));
  SECTION("cockpit-shared without it") {
    const fs::path file = tmp.Write("c.yaml", without);
    CHECK_THAT(ErrorOf([&] { haptel::LoadCockpit(file); }),
               Contains(file.string()) && Contains("'shared_control'"));
  }
  SECTION("plain cockpit with it") {
    std::string text = base;
    text.replace(text.find("name: cockpit-shared"), 20, "name: cockpit");
    const fs::path file = tmp.Write("c.yaml", text);
    CHECK_THAT(ErrorOf([&] { haptel::LoadCockpit(file); }),
               Contains("'shared_control'") && Contains("cockpit-shared"));
  }
  SECTION("a force no one could push through") {
    const fs::path file = tmp.Write("c.yaml", without + "shared_control:\n  max_force: 50\n");
    CHECK_THAT(
        ErrorOf([&] { haptel::LoadCockpit(file); }),
        Contains(file.string()) && Contains("shared_control.max_force") && Contains("[0, 15]"));
  }
}

TEST_CASE("Shipped sim robot carries range sensors; the CAN robot none", "[config][shipped]") {
  const haptel::VehicleConfig sim = haptel::LoadVehicle("config/vehicles/sim-robot.yaml");
  CHECK(sim.range_sensors.beams == 31);
  CHECK(sim.range_sensors.fov_deg == 180.0);
  TempDir tmp;
  const fs::path file = tmp.Write("v.yaml", "name: robot1\nrange_sensors:\n  beams: 64\n");
  const std::string msg = ErrorOf([&] { haptel::LoadVehicle(file); });
  CHECK_THAT(msg, Contains(file.string()) && Contains("range_sensors.beams"));
}

TEST_CASE("Absent optional keys take their defaults", "[config]") {
  TempDir tmp;
  const haptel::VehicleConfig v = haptel::LoadVehicle(tmp.Write("v.yaml", "name: robot2\n"));
  const haptel::VehicleConfig d;
  CHECK(v.name == "robot2");
  CHECK(v.world.empty());
  CHECK(v.drive.speed_levels == d.drive.speed_levels);
  CHECK(v.drive.max_speed == d.drive.max_speed);
  CHECK(v.camera.width == d.camera.width);
  CHECK(v.link.peers == d.link.peers);

  const haptel::GestureConfig g =
      haptel::LoadGesture(tmp.Write("g.yaml", "neutral: [0.01, -0.02, 0.03]\n"));
  CHECK(g.name == "gesture");
  CHECK(g.neutral == std::array<double, 3>{0.01, -0.02, 0.03});
  CHECK(g.dead_zone == haptel::GestureConfig{}.dead_zone);
}

TEST_CASE("The default camera is synthetic, 640x480 at 30 fps, in the struct and the shipped file",
          "[config][shipped]") {
  const haptel::CameraConfig d;
  CHECK(d.source == haptel::CameraSourceKind::kSynthetic);
  CHECK(d.width == 640);
  CHECK(d.height == 480);
  CHECK(d.rate_hz == 30.0);
  CHECK(d.loop);
  const haptel::VehicleConfig shipped = haptel::LoadVehicle("config/vehicles/sim-robot.yaml");
  CHECK(shipped.camera.source == d.source);
  CHECK(shipped.camera.width == d.width);
  CHECK(shipped.camera.height == d.height);
  CHECK(shipped.camera.rate_hz == d.rate_hz);
}

TEST_CASE("Camera sources: synthetic, device or file", "[config]") {
  TempDir tmp;
  SECTION("a file, relative to the config file's folder, looping unless told") {
    const haptel::VehicleConfig v = haptel::LoadVehicle(
        tmp.Write("file.yaml", "name: robot1\ncamera:\n  source: file\n  file: clips/lap.avi\n"));
    CHECK(v.camera.source == haptel::CameraSourceKind::kFile);
    CHECK(v.camera.file == tmp.path() / "clips/lap.avi");
    CHECK(v.camera.loop);
    const haptel::VehicleConfig once = haptel::LoadVehicle(tmp.Write(
        "once.yaml", "name: robot1\ncamera: {source: file, file: /data/lap.mp4, loop: false}\n"));
    CHECK(once.camera.file == "/data/lap.mp4");
    CHECK_FALSE(once.camera.loop);
  }
  SECTION("a device by path or by index") {
    const haptel::VehicleConfig path = haptel::LoadVehicle(
        tmp.Write("dev.yaml", "name: robot1\ncamera:\n  source: device\n  device: /dev/video2\n"));
    CHECK(path.camera.source == haptel::CameraSourceKind::kDevice);
    CHECK(path.camera.device == "/dev/video2");
    const haptel::VehicleConfig index = haptel::LoadVehicle(
        tmp.Write("index.yaml", "name: robot1\ncamera: {source: device, device: 0}\n"));
    CHECK(index.camera.device == "0");
  }
  SECTION("codec h264 with its bitrate") {
    const haptel::VehicleConfig v = haptel::LoadVehicle(
        tmp.Write("h264.yaml", "name: robot1\ncamera: {codec: h264, bitrate_kbps: 750}\n"));
    CHECK(v.camera.codec == haptel::CameraCodec::kH264);
    CHECK(v.camera.bitrate_kbps == 750);
    CHECK(std::string(haptel::CameraCodecName(v.camera.codec)) == "h264");
  }
  SECTION("device and file may stay in the file while the camera is synthetic") {
    const haptel::VehicleConfig v = haptel::LoadVehicle(tmp.Write(
        "kept.yaml", "name: robot1\ncamera: {source: synthetic, device: 1, file: lap.avi}\n"));
    CHECK(v.camera.source == haptel::CameraSourceKind::kSynthetic);
  }
}

TEST_CASE("A vehicle's cameras: one camera: is the pilot; cameras: lists them, the driven first",
          "[config][shipped]") {
  const haptel::VehicleConfig one = haptel::LoadVehicle("config/vehicles/sim-blimp.yaml");
  CHECK(one.camera.name == "pilot");
  CHECK(one.extra_cameras.empty());
  CHECK(one.Cameras().size() == 1);

  const std::string path = "config/vehicles/sim-blimp-surveillance.yaml";
  const std::string text = ReadText(path);
  const haptel::VehicleConfig two = haptel::LoadVehicle(path);
  CHECK(two.camera.name == "pilot");
  CHECK(two.camera.fov_deg == 90.0);
  REQUIRE(two.extra_cameras.size() == 1);
  const haptel::CameraConfig& surv = two.extra_cameras[0];
  CHECK(surv.name == "surveillance");
  CHECK(surv.priority == 1);
  CHECK(surv.zoom_max == NumberIn(text, "zoom_max"));
  CHECK(surv.Range().zooms());
  CHECK(surv.Range().pan_max == Approx(170.0 * 3.14159265 / 180.0));
  CHECK(surv.zoom_servo.channel == 9);
  const haptel::ServoControllerConfig servo = two.ServoWithCameras();
  REQUIRE(servo.camera_channels.size() == 3);
  CHECK(servo.camera_channels[0].camera == 1);
  CHECK(servo.camera_channels[2].axis == haptel::CameraServoChannel::Axis::kZoom);
  CHECK(servo.camera_channels[2].max == 10.0);

  // The robot's rear camera looks backwards from its back.
  const haptel::VehicleConfig robot =
      haptel::LoadVehicle("config/vehicles/sim-robot-rear-camera.yaml");
  REQUIRE(robot.extra_cameras.size() == 1);
  CHECK(robot.extra_cameras[0].name == "rear");
  CHECK(robot.extra_cameras[0].mount_yaw_deg == 180.0);
  CHECK(robot.extra_cameras[0].mount_forward < 0.0);
  CHECK(robot.camera.codec == haptel::CameraCodec::kH264);
}

TEST_CASE("Bad file: cameras", "[config][bad]") {
  TempDir tmp;
  const std::string maestro =
      "servo:\n  protocol: PROTOCOL\n  channels:\n"
      "    elevator: {channel: 0}\n    rudder: {channel: 1}\n"
      "    power: {channel: 2, min_us: 1000, neutral_us: 1000}\n    helix: {channel: 3}\n"
      "    tail_rotor: {channel: 4}\n    camera_pan: {channel: 5}\n"
      "    camera_tilt: {channel: 6}\n";
  const auto blimp = [&](const std::string& protocol, int zoom_channel) {
    std::string servo = maestro;
    servo.replace(servo.find("PROTOCOL"), 8, protocol);
    return "name: b\nkind: servo-blimp-sim\nairship: {}\ncameras:\n  - {name: pilot}\n"
           "  - name: surveillance\n    zoom_max: 10\n    zoom_servo: {channel: " +
           std::to_string(zoom_channel) + "}\n" + servo;
  };
  SECTION("a good one loads") {
    CHECK(haptel::LoadVehicle(tmp.Write("good.yaml", blimp("maestro", 9))).extra_cameras.size() ==
          1);
  }
  SECTION("both camera: and cameras:") {
    const fs::path file =
        tmp.Write("both.yaml", "name: r\ncamera: {fov_deg: 60}\ncameras:\n  - {name: a}\n");
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'cameras'"));
    CHECK_THAT(msg, Contains("not both"));
  }
  SECTION("two cameras under one name") {
    const std::string text = "name: r\ncameras:\n  - {name: front}\n  - {name: front}\n";
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(tmp.Write("dup.yaml", text)); });
    CHECK_THAT(msg, Contains("'cameras[1].name'"));
    CHECK_THAT(msg, Contains("appears twice"));
  }
  SECTION("a name that cannot be a topic's") {
    const std::string text = "name: r\ncameras:\n  - {name: pilot}\n  - {name: Rear Cam}\n";
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(tmp.Write("name.yaml", text)); });
    CHECK_THAT(msg, Contains("'cameras[1].name'"));
    CHECK_THAT(msg, Contains("lower-case letters"));
  }
  SECTION("a range whose ends are swapped") {
    const std::string text =
        "name: r\ncameras:\n  - {name: pilot}\n  - {name: rear, pan_min_deg: 30, "
        "pan_max_deg: -30}\n";
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(tmp.Write("range.yaml", text)); });
    CHECK_THAT(msg, Contains("'cameras[1].pan_max_deg'"));
  }
  SECTION("a channel the SC-8000 lacks") {
    const fs::path file = tmp.Write("sc8000.yaml", blimp("sc8000", 9));
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'cameras[1].zoom_servo.channel'"));
    CHECK_THAT(msg, Contains("0..7"));
  }
  SECTION("an output the seven channels use") {
    const std::string msg =
        ErrorOf([&] { haptel::LoadVehicle(tmp.Write("taken.yaml", blimp("maestro", 5))); });
    CHECK_THAT(msg, Contains("'cameras[1].zoom_servo.channel'"));
    CHECK_THAT(msg, Contains("5 is taken"));
  }
  SECTION("a servo on the driven camera") {
    const std::string text =
        "name: b\nkind: sim-blimp\nairship: {}\ncameras:\n  - {name: pilot, zoom_max: 2, "
        "zoom_servo: {channel: 9}}\n";
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(tmp.Write("driven.yaml", text)); });
    CHECK_THAT(msg, Contains("'cameras[0].zoom_servo'"));
    CHECK_THAT(msg, Contains("driven camera"));
  }
}

TEST_CASE("Bad file: camera source", "[config][bad]") {
  TempDir tmp;
  SECTION("unknown source") {
    const std::string text = "name: robot1\ncamera:\n  width: 640\n  source: webcam\n";
    const fs::path file = tmp.Write("bad-source.yaml", text);
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "webcam"))));
    CHECK_THAT(msg, Contains("'camera.source'"));
    CHECK_THAT(msg, Contains("synthetic, device, file"));
    CHECK_THAT(msg, Contains("got 'webcam'"));
  }
  SECTION("file source without a file") {
    const std::string text = "name: robot1\ncamera:\n  source: file\n";
    const fs::path file = tmp.Write("no-file.yaml", text);
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'camera.file'"));
    CHECK_THAT(msg, Contains("missing"));
  }
  SECTION("device source without a device") {
    const std::string text = "name: robot1\ncamera:\n  source: device\n";
    const fs::path file = tmp.Write("no-device.yaml", text);
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'camera.device'"));
    CHECK_THAT(msg, Contains("missing"));
  }
  SECTION("a device that is neither a path nor an index") {
    const std::string text = "name: robot1\ncamera:\n  source: device\n  device: video0\n";
    const fs::path file = tmp.Write("bad-device.yaml", text);
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(file); });
    CHECK_THAT(msg, Contains("'camera.device'"));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "video0"))));
    CHECK_THAT(msg, Contains("/dev/video0"));
  }
  SECTION("unknown codec") {
    const std::string text = "name: robot1\ncamera:\n  width: 640\n  codec: vp9\n";
    const fs::path file = tmp.Write("bad-codec.yaml", text);
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "vp9"))));
    CHECK_THAT(msg, Contains("'camera.codec'"));
    CHECK_THAT(msg, Contains("jpeg, h264"));
    CHECK_THAT(msg, Contains("got 'vp9'"));
  }
  SECTION("codec that is not a name") {
    const fs::path file = tmp.Write("list-codec.yaml", "name: robot1\ncamera:\n  codec: [h264]\n");
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'camera.codec'"));
  }
  SECTION("bitrate out of range or not a number") {
    const fs::path zero =
        tmp.Write("zero-rate.yaml", "name: robot1\ncamera:\n  codec: h264\n  bitrate_kbps: 0\n");
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(zero); });
    CHECK_THAT(msg, Contains(zero.string()));
    CHECK_THAT(msg, Contains("'camera.bitrate_kbps'"));
    CHECK_THAT(msg, Contains("50"));
    const fs::path word = tmp.Write(
        "word-rate.yaml", "name: robot1\ncamera:\n  codec: h264\n  bitrate_kbps: 1Mbit\n");
    const std::string word_msg = ErrorOf([&] { haptel::LoadVehicle(word); });
    CHECK_THAT(word_msg, Contains(word.string()));
    CHECK_THAT(word_msg, Contains("'camera.bitrate_kbps'"));
  }
  SECTION("loop that is not true or false") {
    const std::string text =
        "name: robot1\ncamera:\n  source: file\n  file: a.avi\n  loop: forever\n";
    const fs::path file = tmp.Write("bad-loop.yaml", text);
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(file); });
    CHECK_THAT(msg, Contains("'camera.loop'"));
    CHECK_THAT(msg, Contains("true or false"));
  }
}

// ---------------------------------------------------------------- InterfaceFile

TEST_CASE("InterfaceFile resolves names and lists the choices when it cannot", "[config]") {
  const haptel::RunConfig r = haptel::LoadRun("config/haptel.yaml");
  const fs::path g = haptel::InterfaceFile(r, "gesture");
  CHECK(fs::is_regular_file(g));
  CHECK(g.filename() == "gesture.yaml");
  CHECK(fs::equivalent(g, "config/interfaces/gesture.yaml"));

  REQUIRE_THROWS_AS(haptel::InterfaceFile(r, "joystick"), ConfigError);
  const std::string msg = ErrorOf([&] { haptel::InterfaceFile(r, "joystick"); });
  CHECK_THAT(msg, Contains("haptel.yaml"));
  CHECK_THAT(msg, Contains("'interface'"));
  CHECK_THAT(msg, Contains("gesture"));
  CHECK_THAT(msg, Contains("joystick"));
}

// ---------------------------------------------------------------- bad files

TEST_CASE("Bad file: unknown top-level key", "[config][bad]") {
  TempDir tmp;
  const std::string text =
      "name: robot1\n"
      "sim_rate_hz: 200\n"
      "watchdog_timeout: 0.3\n";
  const fs::path file = tmp.Write("unknown-top.yaml", text);
  REQUIRE_THROWS_AS(haptel::LoadVehicle(file), ConfigError);
  const std::string msg = ErrorOf([&] { haptel::LoadVehicle(file); });
  CHECK_THAT(msg, Contains(file.string()));
  CHECK_THAT(msg, Contains("'watchdog_timeout'"));
  CHECK_THAT(msg, Contains(LineTag(LineOf(text, "watchdog_timeout:"))));
  CHECK_THAT(msg, Contains("unknown key"));
}

TEST_CASE("Bad file: unknown nested key", "[config][bad]") {
  TempDir tmp;
  SECTION("vehicle drive.speeed") {
    const std::string text =
        "name: robot1\n"
        "drive:\n"
        "  speed_levels: 8\n"
        "  speeed: 0.3\n";
    const fs::path file = tmp.Write("unknown-nested.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadVehicle(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'drive.speeed'"));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "speeed:"))));
    // The message offers the keys the section does take.
    CHECK_THAT(msg, Contains("speed_levels"));
  }
  SECTION("run link.domian_id") {
    const std::string text =
        "track: t.yaml\n"
        "vehicle: v.yaml\n"
        "link:\n"
        "  domian_id: 3\n";
    const fs::path file = tmp.Write("unknown-link.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadRun(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadRun(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'link.domian_id'"));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "domian_id"))));
  }
  SECTION("track gates[1].widht") {
    const std::string text = TrackText(
        "  - {along: 1.0}\n"
        "  - {along: 2.0, widht: 0.5}\n");
    const fs::path file = tmp.Write("unknown-gate.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadTrack(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadTrack(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'gates[1].widht'"));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "widht"))));
  }
}

TEST_CASE("Bad file: value out of range", "[config][bad]") {
  TempDir tmp;
  SECTION("vehicle integer") {
    const std::string text =
        "name: robot1\n"
        "drive:\n"
        "  max_speed: 0.3\n"
        "  speed_levels: 0\n";
    const fs::path file = tmp.Write("range-int.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadVehicle(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'drive.speed_levels'"));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "speed_levels"))));
    CHECK_THAT(msg, Contains("got '0'"));
  }
  SECTION("run number") {
    const std::string text =
        "track: t.yaml\n"
        "vehicle: v.yaml\n"
        "session_rate_hz: 5\n";
    const fs::path file = tmp.Write("range-run.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadRun(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadRun(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'session_rate_hz'"));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "session_rate_hz"))));
    CHECK_THAT(msg, Contains("got '5'"));
  }
  SECTION("gesture vector element") {
    const std::string text =
        "name: gesture\n"
        "neutral: [0.0, 5.0, 0.0]\n";
    const fs::path file = tmp.Write("range-vec.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadGesture(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadGesture(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'neutral'"));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "neutral"))));
  }
  SECTION("track reference lap beyond the lap cap") {
    const std::string text =
        "name: fixture\n"
        "corridor_width: 1.0\n"
        "lap_cap_s: 60\n"
        "reference_lap_s: 90\n"
        "centerline: [[0, 0], [4, 0], [4, 3], [0, 3]]\n"
        "gates: [{along: 1.0}]\n";
    const fs::path file = tmp.Write("range-reference-lap.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadTrack(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadTrack(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'reference_lap_s'"));
    CHECK_THAT(msg, Contains("60"));  // the range it must be in ends at the cap
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "reference_lap_s"))));
  }
  SECTION("track corridor width") {
    const std::string text =
        "name: fixture\n"
        "corridor_width: 50\n"
        "centerline: [[0, 0], [4, 0], [4, 3], [0, 3]]\n"
        "gates: [{along: 1.0}]\n";
    const fs::path file = tmp.Write("range-track.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadTrack(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadTrack(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'corridor_width'"));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "corridor_width"))));
  }
}

TEST_CASE("Bad file: wrong type", "[config][bad]") {
  TempDir tmp;
  SECTION("string where a number is expected") {
    const std::string text =
        "name: robot1\n"
        "state_rate_hz: 50\n"
        "sim_rate_hz: fast\n";
    const fs::path file = tmp.Write("type-string.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadVehicle(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'sim_rate_hz'"));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "sim_rate_hz"))));
    CHECK_THAT(msg, Contains("got 'fast'"));
  }
  SECTION("fraction where a whole number is expected") {
    const std::string text =
        "name: robot1\n"
        "camera:\n"
        "  width: 320.5\n";
    const fs::path file = tmp.Write("type-int.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadVehicle(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(file); });
    CHECK_THAT(msg, Contains("'camera.width'"));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "width"))));
  }
  SECTION("list where a number is expected") {
    const std::string text =
        "name: gesture\n"
        "dead_zone: [0.01, 0.02]\n";
    const fs::path file = tmp.Write("type-list.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadGesture(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadGesture(file); });
    CHECK_THAT(msg, Contains("'dead_zone'"));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "dead_zone"))));
    CHECK_THAT(msg, Contains("a list"));
  }
  SECTION("scalar where a section is expected") {
    const std::string text =
        "track: t.yaml\n"
        "vehicle: v.yaml\n"
        "servo: 1000\n";
    const fs::path file = tmp.Write("type-map.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadRun(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadRun(file); });
    CHECK_THAT(msg, Contains("'servo'"));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "servo"))));
  }
  SECTION("word where true/false is expected") {
    const std::string text =
        "track: t.yaml\n"
        "vehicle: v.yaml\n"
        "video_decode: sometimes\n";
    const fs::path file = tmp.Write("type-bool.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadRun(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadRun(file); });
    CHECK_THAT(msg, Contains("'video_decode'"));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "video_decode"))));
  }
  SECTION("malformed centre-line point") {
    const std::string text =
        "name: fixture\n"
        "corridor_width: 1.0\n"
        "centerline:\n"
        "  - [0.0, 0.0]\n"
        "  - [4.0, 0.0, 1.0]\n"
        "  - [4.0, 3.0]\n"
        "gates: [{along: 1.0}]\n";
    const fs::path file = tmp.Write("type-point.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadTrack(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadTrack(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'centerline[1]'"));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "[4.0, 0.0, 1.0]"))));
  }
}

TEST_CASE("Bad file: missing required key", "[config][bad]") {
  TempDir tmp;
  SECTION("track without centerline") {
    const std::string text =
        "name: fixture\n"
        "corridor_width: 1.0\n"
        "gates: [{along: 1.0}]\n";
    const fs::path file = tmp.Write("missing-centerline.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadTrack(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadTrack(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'centerline'"));
    CHECK_THAT(msg, Contains("missing"));
  }
  SECTION("track without gates") {
    const std::string text =
        "name: fixture\n"
        "corridor_width: 1.0\n"
        "centerline: [[0, 0], [4, 0], [4, 3], [0, 3]]\n";
    const fs::path file = tmp.Write("missing-gates.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadTrack(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadTrack(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'gates'"));
  }
  SECTION("gate without along") {
    const std::string text = TrackText(
        "  - {along: 1.0}\n"
        "  - {width: 0.5}\n");
    const fs::path file = tmp.Write("missing-along.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadTrack(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadTrack(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'gates[1].along'"));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "{width: 0.5}"))));
  }
  SECTION("vehicle without name") {
    const fs::path file = tmp.Write("missing-name.yaml", "sim_rate_hz: 200\n");
    REQUIRE_THROWS_AS(haptel::LoadVehicle(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'name'"));
    CHECK_THAT(msg, Contains("missing"));
  }
  SECTION("run without track") {
    const fs::path file = tmp.Write("missing-track.yaml", "vehicle: v.yaml\n");
    REQUIRE_THROWS_AS(haptel::LoadRun(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadRun(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'track'"));
    CHECK_THAT(msg, Contains("missing"));
  }
}

TEST_CASE("Bad file: malformed YAML", "[config][bad]") {
  TempDir tmp;
  const std::string text =
      "name: robot1\n"
      "drive:\n"
      "  speed_levels: 8\n"
      "  max_speed: : 0.3\n"
      "  track_width: 0.16\n";
  const fs::path file = tmp.Write("malformed.yaml", text);
  REQUIRE_THROWS_AS(haptel::LoadVehicle(file), ConfigError);
  const std::string msg = ErrorOf([&] { haptel::LoadVehicle(file); });
  CHECK_THAT(msg, Contains(file.string()));
  CHECK_THAT(msg, Contains(LineTag(LineOf(text, "max_speed: :"))));
  CHECK_THAT(msg, Contains("YAML"));
}

TEST_CASE("Bad file: top level is not a mapping", "[config][bad]") {
  TempDir tmp;
  const fs::path list = tmp.Write("list.yaml", "- name: robot1\n- name: robot2\n");
  REQUIRE_THROWS_AS(haptel::LoadVehicle(list), ConfigError);
  CHECK_THAT(ErrorOf([&] { haptel::LoadVehicle(list); }), Contains(list.string()));
  const fs::path empty = tmp.Write("empty.yaml", "");
  REQUIRE_THROWS_AS(haptel::LoadTrack(empty), ConfigError);
  CHECK_THAT(ErrorOf([&] { haptel::LoadTrack(empty); }), Contains(empty.string()));
}

TEST_CASE("Bad file: missing file", "[config][bad]") {
  TempDir tmp;
  const fs::path file = tmp.path() / "does-not-exist.yaml";
  REQUIRE_THROWS_AS(haptel::LoadTrack(file), ConfigError);
  CHECK_THAT(ErrorOf([&] { haptel::LoadTrack(file); }), Contains(file.string()));
  REQUIRE_THROWS_AS(haptel::LoadVehicle(file), ConfigError);
  CHECK_THAT(ErrorOf([&] { haptel::LoadVehicle(file); }), Contains(file.string()));
  REQUIRE_THROWS_AS(haptel::LoadGesture(file), ConfigError);
  CHECK_THAT(ErrorOf([&] { haptel::LoadGesture(file); }), Contains(file.string()));
  REQUIRE_THROWS_AS(haptel::LoadRun(file), ConfigError);
  CHECK_THAT(ErrorOf([&] { haptel::LoadRun(file); }), Contains(file.string()));
}

TEST_CASE("Bad file: gates not in increasing order", "[config][bad]") {
  TempDir tmp;
  SECTION("a gate behind the one before it") {
    const std::string text = TrackText(
        "  - {along: 2.0}\n"
        "  - {along: 6.0}\n"
        "  - {along: 5.0}\n");
    const fs::path file = tmp.Write("gates-order.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadTrack(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadTrack(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'gates[2].along'"));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "{along: 5.0}"))));
  }
  SECTION("two gates at the same place") {
    const std::string text = TrackText(
        "  - {along: 2.0}\n"
        "  - {along: 2.0}\n");
    const fs::path file = tmp.Write("gates-equal.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadTrack(file), ConfigError);
    CHECK_THAT(ErrorOf([&] { haptel::LoadTrack(file); }), Contains("'gates[1].along'"));
  }
  SECTION("a gate past the end of the lap") {
    // The fixture's centre line is 14 m long.
    const std::string text = TrackText(
        "  - {along: 2.0}\n"
        "  - {along: 14.5}\n");
    const fs::path file = tmp.Write("gates-past.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadTrack(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadTrack(file); });
    CHECK_THAT(msg, Contains("'gates[1].along'"));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "{along: 14.5}"))));
  }
  SECTION("the valid fixture loads") {
    // Guards the fixtures above: only their gates are wrong.
    const std::string text = TrackText(
        "  - {along: 2.0}\n"
        "  - {along: 6.0}\n");
    const haptel::TrackConfig t = haptel::LoadTrack(tmp.Write("gates-ok.yaml", text));
    CHECK(t.gates.size() == 2);
  }
}

TEST_CASE("Bad file: gate wider than the corridor", "[config][bad]") {
  TempDir tmp;
  SECTION("per-gate width") {
    const std::string text = TrackText(
        "  - {along: 2.0}\n"
        "  - {along: 6.0, width: 0.95}\n");
    const fs::path file = tmp.Write("gate-wide.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadTrack(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadTrack(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'gates[1].width'"));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "width: 0.95"))));
  }
  SECTION("file-wide gate_width") {
    const std::string text = TrackText("  - {along: 2.0}\n",
                                       "post_radius: 0.04\n"
                                       "gate_width: 1.2\n");
    const fs::path file = tmp.Write("gate-wide-default.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadTrack(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadTrack(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'gates[0].width'"));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "{along: 2.0}"))));
  }
  SECTION("posts that would touch the wall") {
    // 0.9 m between post centres plus 2 * 0.06 m of post > 1.0 m corridor.
    const std::string text = TrackText("  - {along: 2.0, width: 0.9}\n", "post_radius: 0.06\n");
    const fs::path file = tmp.Write("gate-posts.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadTrack(file), ConfigError);
    CHECK_THAT(ErrorOf([&] { haptel::LoadTrack(file); }), Contains("'gates[0].width'"));
  }
}

TEST_CASE("Bad file: centre line turning back on itself", "[config][bad]") {
  TempDir tmp;
  const std::string text =
      "name: fixture\n"
      "corridor_width: 1.0\n"
      "centerline:\n"
      "  - [0.0, 0.0]\n"
      "  - [4.0, 0.0]\n"
      "  - [0.5, 0.3]\n"
      "gates: [{along: 1.0}]\n";
  const fs::path file = tmp.Write("sharp.yaml", text);
  REQUIRE_THROWS_AS(haptel::LoadTrack(file), ConfigError);
  const std::string msg = ErrorOf([&] { haptel::LoadTrack(file); });
  CHECK_THAT(msg, Contains(file.string()));
  CHECK_THAT(msg, Contains("'centerline[0]'"));  // the point where it turns back
}

TEST_CASE("Bad file: values the loaders check beyond their type", "[config][bad]") {
  TempDir tmp;
  SECTION("vehicle name unusable in topic names") {
    const std::string text = "name: robot 1\n";
    const fs::path file = tmp.Write("bad-name.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadVehicle(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(file); });
    CHECK_THAT(msg, Contains("'name'"));
    CHECK_THAT(msg, Contains(LineTag(1)));
  }
  SECTION("unknown vehicle kind") {
    const std::string text = "name: robot1\nkind: hovercraft\n";
    const fs::path file = tmp.Write("bad-kind.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadVehicle(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(file); });
    CHECK_THAT(msg, Contains("'kind'"));
    CHECK_THAT(msg, Contains(LineTag(LineOf(text, "hovercraft"))));
  }
  SECTION("gesture file for another interface") {
    const std::string text = "name: cockpit\n";
    const fs::path file = tmp.Write("bad-gesture.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadGesture(file), ConfigError);
    CHECK_THAT(ErrorOf([&] { haptel::LoadGesture(file); }), Contains("'name'"));
  }
  SECTION("operator slower in turns than on straights") {
    const std::string text =
        "track: t.yaml\n"
        "vehicle: v.yaml\n"
        "operator:\n"
        "  cruise: 0.4\n"
        "  min_forward: 0.6\n";
    const fs::path file = tmp.Write("bad-operator.yaml", text);
    REQUIRE_THROWS_AS(haptel::LoadRun(file), ConfigError);
    const std::string msg = ErrorOf([&] { haptel::LoadRun(file); });
    CHECK_THAT(msg, Contains(file.string()));
    CHECK_THAT(msg, Contains("'operator.min_forward'"));
  }
}

TEST_CASE(
    "a FIFO (or any file that is not a regular file) is refused before it is opened, never waited "
    "on") {
  // Opening a FIFO for reading waits for a writer: without the check this
  // test would hang until ctest's time-out, and so fail.
  const auto dir = haptel::test::ScratchDir("config-fifo");
  for (const std::string name : {"run.yaml", "scene.xml"}) {
    const auto fifo = dir / name;
    REQUIRE(mkfifo(fifo.c_str(), 0600) == 0);
  }
  const std::string run =
      haptel::test::WhatOf<ConfigError>([&] { haptel::LoadRun(dir / "run.yaml"); });
  CHECK_THAT(run, Contains("run.yaml: is not a regular file") && Contains("expected a YAML file"));
  CHECK_THAT(haptel::test::WhatOf<ConfigError>([&] { haptel::LoadVehicle(dir / "run.yaml"); }),
             Contains("is not a regular file"));
  CHECK_THAT(
      haptel::test::WhatOf<ConfigError>([&] { haptel::LoadSceneFile(dir / "scene.xml"); }),
      Contains("scene.xml: is not a regular file") && Contains("expected an XML scene file"));
  CHECK_THAT(haptel::test::WhatOf<ConfigError>([&] { haptel::LoadRun(dir); }),
             Contains("is a folder"));
}

TEST_CASE(
    "a key given twice in any config file is refused, naming both lines (loaded strictly; issue "
    "41)") {
  // yaml-cpp keeps both and a lookup finds the first: the second, the one a
  // user edited last, was silently ignored.
  const auto dir = haptel::test::ScratchDir("config-duplicates");
  const auto track = haptel::test::WriteFile(
      dir / "track.yaml",
      "name: t\ncorridor_width: 1.0\ncenterline: [[0,0],[4,0],[4,4],[0,4]]\n"
      "corridor_width: 2.0\n");
  CHECK_THAT(haptel::test::WhatOf<ConfigError>([&] { haptel::LoadTrack(track); }),
             Contains("track.yaml:4:1: key 'corridor_width': given twice (first at line 2)"));
  // Nested, in a list's mapping too.
  const auto gates = haptel::test::WriteFile(
      dir / "gates.yaml",
      "name: t\ncorridor_width: 1.0\ncenterline: [[0,0],[4,0],[4,4],[0,4]]\n"
      "gates:\n  - {along: 1.0, width: 0.8, along: 2.0}\n");
  CHECK_THAT(haptel::test::WhatOf<ConfigError>([&] { haptel::LoadTrack(gates); }),
             Contains("gates.yaml:5:") && Contains("key 'gates[0].along': given twice"));
  const auto vehicle = haptel::test::WriteFile(
      dir / "vehicle.yaml", "name: v\ndrive:\n  max_speed: 0.3\n  max_speed: 3.0\n");
  CHECK_THAT(haptel::test::WhatOf<ConfigError>([&] { haptel::LoadVehicle(vehicle); }),
             Contains("vehicle.yaml:4:3: key 'drive.max_speed': given twice (first at line 3)"));
}
