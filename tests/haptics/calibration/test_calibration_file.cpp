// The calibration file: SaveCalibration → LoadCalibration round trip, and the
// strict loader's errors (file, line, key path, expectation).
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "haptel/config/calibration.hpp"
#include "haptel/config/error.hpp"
#include "test_env.hpp"

using namespace haptel;

namespace {

std::string Repeat(const std::string& value, int count) {
  std::string out;
  for (int i = 0; i < count; ++i) out += (i ? ", " : "") + value;
  return "[" + out + "]";
}

/// A valid calibration file, one key per line (line numbers in the comments
/// are what the error tests expect). `right` replaces keys of the right arm;
/// an empty replacement drops the key.
std::string ValidFile(const std::vector<std::pair<std::string, std::string>>& right = {},
                      const std::string& extra_right_line = "", bool with_right = true) {
  std::vector<std::pair<std::string, std::string>> keys = {
      {"tracker_scale", "[0.01, 0.0101, 0.0099]"},  // right: line 13
      {"tracker_offset", "[0.01, -0.02, 0.005]"},   // 14
      {"glove_gain", Repeat("0.005", 22)},          // 15
      {"glove_offset", Repeat("-0.1", 22)},         // 16
      {"force_slope", "[1.1, 0.9, 1.05]"},          // 17
      {"force_residual", "0.02"},                   // 18
      {"finger_force_slope", "0.95"},               // 19
  };
  std::ostringstream out;
  out << "device: sim\n"                                                                // 1
      << "user: alice\n"                                                                // 2
      << "arms:\n"                                                                      // 3
      << "  left:\n";                                                                   // 4
  for (const auto& [key, value] : keys) out << "    " << key << ": " << value << "\n";  // 5..11
  if (with_right) {
    out << "  right:\n";  // 12
    for (auto [key, value] : keys) {
      bool drop = false;
      for (const auto& [k, v] : right) {
        if (k == key) {
          value = v;
          drop = v.empty();
        }
      }
      if (!drop) out << "    " << key << ": " << value << "\n";
    }
    out << extra_right_line;
  }
  return out.str();
}

std::filesystem::path Write(const std::filesystem::path& dir, const std::string& text) {
  const auto file = dir / "cal.yaml";
  std::ofstream(file) << text;
  return file;
}

std::string LoadError(const std::filesystem::path& file) {
  try {
    LoadCalibration(file);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST_CASE("a valid calibration file loads with every value") {
  const auto dir = test::ScratchDir("calibration-file-valid");
  const DeviceCalibration c = LoadCalibration(Write(dir, ValidFile()));
  CHECK(c.device == "sim");
  CHECK(c.user == "alice");
  CHECK(c.file == dir / "cal.yaml");
  for (const ArmCalibration& arm : c.arms) {
    CHECK(arm.tracker_scale == std::array<double, 3>{0.01, 0.0101, 0.0099});
    CHECK(arm.tracker_offset == std::array<double, 3>{0.01, -0.02, 0.005});
    for (int j = 0; j < kCalibrationGloveSensors; ++j) {
      CHECK(arm.glove_gain[j] == 0.005);
      CHECK(arm.glove_offset[j] == -0.1);
    }
    CHECK(arm.force_slope == std::array<double, 3>{1.1, 0.9, 1.05});
    CHECK(arm.force_residual == 0.02);
    CHECK(arm.finger_force_slope == 0.95);
  }
}

TEST_CASE("save then load gives back exactly the same calibration") {
  const auto dir = test::ScratchDir("calibration-file-roundtrip");
  DeviceCalibration c;
  c.device = "exo-2";
  c.user = "bob";
  // Values whose shortest decimal form needs all 17 digits, tiny and huge ones.
  double x = 1.0 / 3.0;
  for (int s = 0; s < 2; ++s) {
    ArmCalibration& arm = c.arms[s];
    for (int i = 0; i < 3; ++i) {
      arm.tracker_scale[i] = 0.01 * (1.0 + x / 7.0);
      arm.tracker_offset[i] = (0.1 + 0.2) * (i - 1) * x;
      arm.force_slope[i] = std::nextafter(1.0 + x, 2.0);
      x = std::fmod(x * 3.7 + 0.123456789, 1.0);
    }
    for (int j = 0; j < kCalibrationGloveSensors; ++j) {
      arm.glove_gain[j] = (j % 2 ? -1.0 : 1.0) * (0.004 + x * 1e-3);
      arm.glove_offset[j] = j == 5 ? 1e-300 : x - 0.7;
      x = std::fmod(x * 3.7 + 0.123456789, 1.0);
    }
    arm.force_residual = 1.0 / 7.0 * 1e-3;
    arm.finger_force_slope = 123456.789e-5;
  }
  const auto file = dir / "new" / "folders" / "cal.yaml";  // parents do not exist yet
  SaveCalibration(file, c);
  const DeviceCalibration back = LoadCalibration(file);
  CHECK(back.device == c.device);
  CHECK(back.user == c.user);
  for (int s = 0; s < 2; ++s) {
    CHECK(back.arms[s].tracker_scale == c.arms[s].tracker_scale);
    CHECK(back.arms[s].tracker_offset == c.arms[s].tracker_offset);
    CHECK(back.arms[s].glove_gain == c.arms[s].glove_gain);
    CHECK(back.arms[s].glove_offset == c.arms[s].glove_offset);
    CHECK(back.arms[s].force_slope == c.arms[s].force_slope);
    CHECK(back.arms[s].force_residual == c.arms[s].force_residual);
    CHECK(back.arms[s].finger_force_slope == c.arms[s].finger_force_slope);
  }
  // Saving what was loaded writes the same text.
  const auto again = dir / "again.yaml";
  SaveCalibration(again, back);
  std::stringstream a, b;
  a << std::ifstream(file).rdbuf();
  b << std::ifstream(again).rdbuf();
  CHECK(a.str() == b.str());
  CHECK(a.str().find("metres = tracker_scale * raw + tracker_offset") != std::string::npos);
}

TEST_CASE("SaveCalibration refuses values the loader would reject") {
  const auto dir = test::ScratchDir("calibration-file-save-invalid");
  DeviceCalibration c;
  c.device = "sim";
  c.arms[1].glove_gain[3] = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_WITH(SaveCalibration(dir / "x.yaml", c),
                    Catch::Contains("arms.right.glove_gain[3]"));
  c.arms[1].glove_gain[3] = 0.005;
  c.arms[0].tracker_scale[2] = 0.0;
  CHECK_THROWS_WITH(SaveCalibration(dir / "x.yaml", c),
                    Catch::Contains("arms.left.tracker_scale[2]"));
  CHECK_FALSE(std::filesystem::exists(dir / "x.yaml"));
}

TEST_CASE("bad calibration files name the file, the line and the key") {
  const auto dir = test::ScratchDir("calibration-file-bad");
  const std::string f = (dir / "cal.yaml").string();
  using Catch::Contains;

  SECTION("unknown key in an arm") {
    const std::string e = LoadError(Write(dir, ValidFile({}, "    colour: blue\n")));
    CHECK_THAT(e, Contains(f + ":20:5: key 'arms.right.colour': unknown key"));
  }
  SECTION("unknown key at the top") {
    const std::string e = LoadError(Write(dir, "version: 2\n" + ValidFile()));
    CHECK_THAT(e, Contains(f + ":1:1: key 'version': unknown key"));
  }
  SECTION("zero tracker scale") {
    const std::string e = LoadError(Write(dir, ValidFile({{"tracker_scale", "[0.01, 0, 0.01]"}})));
    CHECK_THAT(e, Contains(f + ":13:"));
    CHECK_THAT(e, Contains("key 'arms.right.tracker_scale[1]': expected a non-zero number"));
  }
  SECTION("zero glove gain") {
    std::string gains = Repeat("0.005", 21);
    gains.insert(1, "0, ");
    const std::string e = LoadError(Write(dir, ValidFile({{"glove_gain", gains}})));
    CHECK_THAT(e, Contains(f + ":15:"));
    CHECK_THAT(e, Contains("'arms.right.glove_gain[0]'"));
  }
  SECTION("NaN force slope") {
    const std::string e = LoadError(Write(dir, ValidFile({{"force_slope", "[1, .nan, 1]"}})));
    CHECK_THAT(e, Contains(f + ":17:"));
    CHECK_THAT(e, Contains("'arms.right.force_slope[1]'"));
    CHECK_THAT(e, Contains("got '.nan'"));
  }
  SECTION("infinite offset") {
    const std::string e = LoadError(Write(dir, ValidFile({{"tracker_offset", "[0, .inf, 0]"}})));
    CHECK_THAT(e, Contains(f + ":14:"));
    CHECK_THAT(e, Contains("'arms.right.tracker_offset[1]'"));
  }
  SECTION("wrong number of glove values") {
    const std::string e = LoadError(Write(dir, ValidFile({{"glove_gain", Repeat("0.005", 21)}})));
    CHECK_THAT(e, Contains(f + ":15:"));
    CHECK_THAT(e, Contains("key 'arms.right.glove_gain': expected a list of 22 non-zero numbers"));
  }
  SECTION("a list where a number belongs") {
    const std::string e = LoadError(Write(dir, ValidFile({{"force_residual", "[1]"}})));
    CHECK_THAT(e, Contains(f + ":18:"));
    CHECK_THAT(e, Contains("'arms.right.force_residual'"));
  }
  SECTION("negative residual") {
    const std::string e = LoadError(Write(dir, ValidFile({{"force_residual", "-0.1"}})));
    CHECK_THAT(e, Contains(f + ":18:"));
    CHECK_THAT(e, Contains("'arms.right.force_residual'"));
  }
  SECTION("zero finger slope") {
    const std::string e = LoadError(Write(dir, ValidFile({{"finger_force_slope", "0"}})));
    CHECK_THAT(e, Contains(f + ":19:"));
    CHECK_THAT(e, Contains("key 'arms.right.finger_force_slope': expected a positive number"));
  }
  SECTION("missing key in an arm") {
    const std::string e = LoadError(Write(dir, ValidFile({{"force_residual", ""}})));
    CHECK_THAT(e, Contains(f + ":13:5: key 'arms.right.force_residual'"));
    CHECK_THAT(e, Contains("missing"));
  }
  SECTION("missing arm") {
    const std::string e = LoadError(Write(dir, ValidFile({}, "", false)));
    CHECK_THAT(e, Contains(f + ":4:3: key 'arms.right'"));
    CHECK_THAT(e, Contains("missing"));
  }
  SECTION("missing device name") {
    std::string text = ValidFile();
    text.erase(0, text.find('\n') + 1);
    const std::string e = LoadError(Write(dir, text));
    CHECK_THAT(e, Contains(f + ":1:1: key 'device'"));
  }
  SECTION("not YAML") {
    const std::string e = LoadError(Write(dir, "arms: [unclosed\n"));
    CHECK_THAT(e, Contains(f + ":"));
    CHECK_THAT(e, Contains("not valid YAML"));
  }
  SECTION("no file") {
    CHECK_THAT(LoadError(dir / "absent.yaml"), Contains("absent.yaml: cannot open the file"));
  }
}
