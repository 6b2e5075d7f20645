// Configurations that cannot work are refused by their loaders, with one line
// naming the file, the key and what was expected: tracks whose corridor meets
// itself, DDS addresses and names DDS cannot use, files too big to be one.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "haptel/config/error.hpp"
#include "haptel/config/run.hpp"
#include "haptel/config/scene.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "test_env.hpp"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using haptel::ConfigError;

namespace {

/// This process's scratch folder, removed when the tests end.
const fs::path& Scratch() {
  struct Dir {
    fs::path path;
    Dir() {
      const char* env = std::getenv("HAPTEL_TEST_TMP");
      const fs::path base =
          env != nullptr && *env != '\0' ? fs::path(env) : fs::temp_directory_path();
      path = base / ("test_impossible_config-" + std::to_string(::getpid()));
      fs::create_directories(path);
    }
    ~Dir() {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  };
  static const Dir dir;
  return dir.path;
}

fs::path Write(const std::string& name, const std::string& text) {
  return haptel::test::WriteFile(Scratch() / name, text);
}

template <typename F>
std::string ErrorOf(F&& f) {
  return haptel::test::WhatOf<ConfigError>(std::forward<F>(f));
}

/// The message is one line and names the file.
void CheckOneLine(const std::string& message, const fs::path& file) {
  CHECK_THAT(message, Contains(file.string()));
  CHECK(message.find('\n') == std::string::npos);
}

std::string Track(const std::string& centerline, const std::string& gates,
                  const std::string& width = "0.6") {
  return "name: fixture\ncorridor_width: " + width + "\ngate_width: 0.3\npost_radius: 0.03\n" +
         "centerline:\n" + centerline + "gates:\n" + gates;
}

}  // namespace

TEST_CASE("A track whose centre line crosses itself is refused", "[config][bad][track]") {
  SECTION("a figure 8: the two loops meet at the first point") {
    const std::string text = Track(
        "  - [0, 0]\n  - [2, 2]\n  - [4, 2]\n  - [5, 0]\n  - [4, -2]\n  - [2, -2]\n"
        "  - [-2, 2]\n  - [-4, 2]\n  - [-5, 0]\n  - [-4, -2]\n  - [-2, -2]\n",
        "  - {along: 1.0}\n");
    const fs::path file = Write("figure-8.yaml", text);
    const std::string msg = ErrorOf([&] { haptel::LoadTrack(file); });
    CheckOneLine(msg, file);
    CHECK_THAT(msg, Contains("key 'centerline[5]'"));  // the segment that meets the first
    CHECK_THAT(msg, Contains("does not cross itself"));
  }
  SECTION("a loop with one side cut across by another") {
    // (3, 4) -> (3, -2) crosses (0, 0) -> (6, 0) at (3, 0); every turn is 90 degrees.
    const std::string text =
        Track("  - [0, 0]\n  - [6, 0]\n  - [6, 4]\n  - [3, 4]\n  - [3, -2]\n  - [0, -2]\n",
              "  - {along: 1.0}\n");
    const fs::path file = Write("self-crossing.yaml", text);
    const std::string msg = ErrorOf([&] { haptel::LoadTrack(file); });
    CheckOneLine(msg, file);
    CHECK_THAT(msg, Contains("key 'centerline[3]'"));
    CHECK_THAT(msg, Contains("(3, 0)"));
    CHECK_THAT(msg, Contains(":9:"));  // the line of point 3, where the crossing segment starts
  }
  SECTION("the same loop without the cut loads") {
    const std::string text =
        Track("  - [0, 0]\n  - [6, 0]\n  - [6, 4]\n  - [0, 4]\n", "  - {along: 1.0}\n");
    CHECK(haptel::LoadTrack(Write("loop.yaml", text)).centerline.size() == 4);
  }
}

TEST_CASE("A track whose corridor overlaps itself is refused", "[config][bad][track]") {
  SECTION("two sides of the loop closer than the corridor is wide") {
    // Centre lines 0.8 m apart, corridor 1.0 m: the two lanes overlap.
    const std::string text =
        Track("  - [0, 0]\n  - [4, 0]\n  - [4, 0.8]\n  - [0, 0.8]\n", "  - {along: 1.0}\n", "1.0");
    const fs::path file = Write("overlap.yaml", text);
    const std::string msg = ErrorOf([&] { haptel::LoadTrack(file); });
    CheckOneLine(msg, file);
    CHECK_THAT(msg, Contains("key 'corridor_width'"));
    CHECK_THAT(msg, Contains(":2:"));  // the corridor_width line
  }
  SECTION("the same loop with a narrower corridor loads") {
    const std::string text =
        Track("  - [0, 0]\n  - [4, 0]\n  - [4, 0.8]\n  - [0, 0.8]\n", "  - {along: 1.0}\n", "0.5");
    CHECK(haptel::LoadTrack(Write("narrow.yaml", text)).gates.size() == 1);
  }
}

TEST_CASE("A gate whose line does not cross the corridor is refused", "[config][bad][track]") {
  SECTION("a gate on a corner: its line misses the inner wall") {
    const std::string text = Track("  - [0, 0]\n  - [4, 0]\n  - [4, 3]\n  - [0, 3]\n",
                                   "  - {along: 1.0}\n  - {along: 4.0}\n");
    const fs::path file = Write("gate-corner.yaml", text);
    const std::string msg = ErrorOf([&] { haptel::LoadTrack(file); });
    CheckOneLine(msg, file);
    CHECK_THAT(msg, Contains("key 'gates[1].along'"));
    CHECK_THAT(msg, Contains("does not reach the left wall"));
  }
  SECTION("a gate whose line reaches into the next part of the track") {
    // The lanes' walls are 5 cm apart: the gate's line, a little longer than
    // the corridor is wide, would also cross the other lane.
    const std::string text = Track("  - [0, 0]\n  - [4, 0]\n  - [4, 1.05]\n  - [0, 1.05]\n",
                                   "  - {along: 2.0}\n", "1.0");
    const fs::path file = Write("gate-reach.yaml", text);
    const std::string msg = ErrorOf([&] { haptel::LoadTrack(file); });
    CheckOneLine(msg, file);
    CHECK_THAT(msg, Contains("key 'gates[0].along'"));
    CHECK_THAT(msg, Contains("another part of the track"));
  }
}

TEST_CASE("A link address that is not IPv4 is refused where it is written", "[config][bad][link]") {
  SECTION("a run configuration's link.interfaces") {
    const fs::path file = Write("bad-interface.yaml",
                                "track: t.yaml\nvehicle: v.yaml\n"
                                "link:\n  interfaces: [127.0.0.1, 10.0.0.300]\n");
    const std::string msg = ErrorOf([&] { haptel::LoadRun(file); });
    CheckOneLine(msg, file);
    CHECK_THAT(msg, Contains("key 'link.interfaces[1]'"));
    CHECK_THAT(msg, Contains("IPv4 address"));
    CHECK_THAT(msg, Contains("'10.0.0.300'"));
  }
  SECTION("a vehicle's link.peers") {
    const fs::path file =
        Write("bad-peer.yaml", "name: robot1\nlink:\n  peers:\n    - localhost\n");
    const std::string msg = ErrorOf([&] { haptel::LoadVehicle(file); });
    CheckOneLine(msg, file);
    CHECK_THAT(msg, Contains("key 'link.peers[0]'"));
    CHECK_THAT(msg, Contains(":4:"));
  }
  SECTION("dotted addresses load") {
    const haptel::VehicleConfig v = haptel::LoadVehicle(Write(
        "good-link.yaml", "name: robot1\nlink: {interfaces: [192.168.1.20], peers: [10.0.0.2]}\n"));
    CHECK(v.link.peers.at(0) == "10.0.0.2");
  }
}

TEST_CASE("A vehicle name too long for DDS topic names is refused", "[config][bad][link]") {
  const std::string longest(haptel::kMaxVehicleNameLength, 'a');
  CHECK(haptel::VehicleNameProblem(longest).empty());
  CHECK(haptel::LoadVehicle(Write("name-240.yaml", "name: " + longest + "\n")).name == longest);

  const std::string too_long = longest + "b";
  CHECK_THAT(haptel::VehicleNameProblem(too_long), Contains("241"));
  const fs::path file = Write("name-241.yaml", "name: " + too_long + "\n");
  const std::string msg = ErrorOf([&] { haptel::LoadVehicle(file); });
  CheckOneLine(msg, file);
  CHECK_THAT(msg, Contains("key 'name'"));
  CHECK_THAT(msg, Contains("1 to 240 characters"));

  CHECK_FALSE(haptel::VehicleNameProblem("").empty());
  CHECK_FALSE(haptel::VehicleNameProblem("robot/1").empty());
}

TEST_CASE("A file too big to be a configuration is refused by its size before parsing",
          "[config][bad]") {
  // A valid track grown to 64 MB (a sparse file: no disk is written), and a
  // scene just over the limit: both refused with their size, not parsed.
  const fs::path track =
      Write("huge-track.yaml",
            Track("  - [0, 0]\n  - [4, 0]\n  - [4, 3]\n  - [0, 3]\n", "  - {along: 1.0}\n"));
  fs::resize_file(track, std::uintmax_t{64} << 20);
  const std::string msg = ErrorOf([&] { haptel::LoadTrack(track); });
  CheckOneLine(msg, track);
  CHECK_THAT(msg, Contains("67108864 bytes (64 MB)"));
  CHECK_THAT(msg, Contains("at most 4 MB"));

  const fs::path scene = Write("huge-scene.yaml", "objects:\n");
  fs::resize_file(scene, (std::uintmax_t{4} << 20) + 1);
  CHECK_THAT(ErrorOf([&] { haptel::LoadScene(scene); }), Contains("at most 4 MB"));

  const fs::path run = Write("huge-run.yaml", "track: t.yaml\nvehicle: v.yaml\n");
  fs::resize_file(run, std::uintmax_t{5} << 20);
  CHECK_THAT(ErrorOf([&] { haptel::LoadRun(run); }), Contains("5 MB"));
}
