// Tests for the run's picture: what is drawn where (gates by outcome, the path
// by speed against the legend, contacts), the picture's size, and write errors
// that name the file.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string>

#include "haptel/config/blimp_course.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/track.hpp"
#include "haptel/record/run_picture.hpp"

namespace fs = std::filesystem;
using haptel::LoadTrack;
using haptel::ShippedFile;
using haptel::Track;
using haptel::TrackConfig;
using haptel::Vec2;
using haptel::record::DrawRunPicture;
using haptel::record::RenderRunPicture;
using haptel::record::RunPicture;
using haptel::record::RunPicturePath;
using haptel::record::RunRecord;

namespace {

fs::path ScratchDir(const std::string& name) {
  const char* env = std::getenv("HAPTEL_TEST_TMP");
  const fs::path base =
      (env != nullptr && *env != '\0') ? fs::path(env) : fs::temp_directory_path();
  const fs::path dir = base / (name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

/// The pixel at a world point.
cv::Vec3b At(const RunPicture& picture, const Vec2& world) {
  const cv::Point2d p = picture.ToPixel(world.x(), world.y());
  const int col = static_cast<int>(std::lround(p.x));
  const int row = static_cast<int>(std::lround(p.y));
  REQUIRE(col >= 0);
  REQUIRE(row >= 0);
  REQUIRE(col < picture.image.cols);
  REQUIRE(row < picture.image.rows);
  return picture.image.at<cv::Vec3b>(row, col);
}

// BGR channels.
int Blue(const cv::Vec3b& c) { return c[0]; }
int Green(const cv::Vec3b& c) { return c[1]; }
int Red(const cv::Vec3b& c) { return c[2]; }

bool GreenDominant(const cv::Vec3b& c) {
  return Green(c) > 120 && Green(c) > Red(c) + 80 && Green(c) > Blue(c) + 80;
}
bool RedDominant(const cv::Vec3b& c) {
  return Red(c) > 150 && Red(c) > Green(c) + 100 && Red(c) > Blue(c) + 100;
}
bool Near(const cv::Vec3b& a, const cv::Vec3b& b, int tolerance) {
  for (int i = 0; i < 3; ++i) {
    if (std::abs(a[i] - b[i]) > tolerance) return false;
  }
  return true;
}

/// Along the centre line of `track`: standing (0 m/s, as if pushed) for the
/// first metre, fast (0.8 m/s) after 1.5 m, a ramp between; a contact at 1.2 m.
RunRecord LapOn(const Track& track) {
  RunRecord run;
  run.id = 7;
  run.config_name = "picture test";
  run.track = track.config().name;
  run.interface = "gesture";
  run.operator_kind = "auto";
  run.outcome = "completed";
  run.lap_time_s = 12.5;
  run.gates_total = static_cast<int>(track.gates().size());
  run.gates_passed = 1;
  run.gates_missed = 1;
  run.obstacles_touched = 1;
  for (double s = 0.0; s < track.length(); s += 0.01) {
    const double speed = s < 1.0 ? 0.0 : s > 1.5 ? 0.8 : 0.8 * (s - 1.0) / 0.5;
    const Vec2 p = track.PointAt(s);
    run.path.push_back({s, p.x(), p.y(), speed});
  }
  const Vec2 c = track.PointAt(1.2);
  run.contacts.push_back({6.0, c.x(), c.y()});
  run.splits = {{0, true, 1.5}, {1, false, 9.0}};  // gate 1 passed, gate 2 crossed outside
  return run;
}

}  // namespace

TEST_CASE("The run picture shows gates by outcome, the path by speed and the contacts",
          "[run_picture]") {
  const TrackConfig config = LoadTrack(ShippedFile("config/tracks/test-short.yaml"));
  const Track track(config);
  REQUIRE(track.gates().size() == 2);
  const RunRecord run = LapOn(track);
  const RunPicture picture = RenderRunPicture(run, config);

  REQUIRE(picture.image.type() == CV_8UC3);
  // test-short is taller (with the title and legend bands) than wide.
  CHECK(picture.image.rows == RunPicture::kLongSide);
  CHECK(picture.image.cols < RunPicture::kLongSide);
  CHECK(picture.px_per_m > 300.0);

  SECTION("a passed gate's posts are green, a missed gate's red") {
    for (const Vec2& post : {track.gates()[0].left_post, track.gates()[0].right_post}) {
      const cv::Vec3b c = At(picture, post);
      INFO("passed gate post BGR " << c);
      CHECK(GreenDominant(c));
    }
    for (const Vec2& post : {track.gates()[1].left_post, track.gates()[1].right_post}) {
      const cv::Vec3b c = At(picture, post);
      INFO("missed gate post BGR " << c);
      CHECK(RedDominant(c));
    }
  }

  SECTION("slow and fast stretches of the path have the legend's end colours") {
    CHECK(picture.max_speed_mps == Approx(0.8));
    const cv::Rect legend = picture.speed_legend;
    const int row = legend.y + legend.height / 2;
    const cv::Vec3b zero = picture.image.at<cv::Vec3b>(row, legend.x);
    const cv::Vec3b top = picture.image.at<cv::Vec3b>(row, legend.x + legend.width - 1);
    const cv::Vec3b slow = At(picture, track.PointAt(0.6));
    const cv::Vec3b fast = At(picture, track.PointAt(2.4));
    INFO("legend 0 " << zero << ", legend top " << top << ", slow " << slow << ", fast " << fast);
    CHECK_FALSE(Near(zero, top, 60));
    CHECK(Near(slow, zero, 12));
    CHECK(Near(fast, top, 12));
    CHECK_FALSE(Near(slow, fast, 60));
  }

  SECTION("a contact is a red cross") {
    const Vec2 c(run.contacts[0].x, run.contacts[0].y);
    const cv::Vec3b centre = At(picture, c);
    INFO("contact BGR " << centre);
    CHECK(RedDominant(centre));
    // An arm of the cross, 5 px along a diagonal.
    const cv::Point2d p = picture.ToPixel(c.x(), c.y());
    const cv::Vec3b arm = picture.image.at<cv::Vec3b>(static_cast<int>(std::lround(p.y)) + 5,
                                                      static_cast<int>(std::lround(p.x)) + 5);
    INFO("arm BGR " << arm);
    CHECK(RedDominant(arm));
  }

  SECTION("a gate the run never reached is neither green nor red") {
    RunRecord cut = run;
    cut.splits[1] = {1, false, -1.0};
    const RunPicture short_run = RenderRunPicture(cut, config);
    const cv::Vec3b c = At(short_run, track.gates()[1].left_post);
    INFO("unreached gate post BGR " << c);
    CHECK_FALSE(GreenDominant(c));
    CHECK_FALSE(RedDominant(c));
  }
}

TEST_CASE("The run picture is kLongSide wide for a wide track, and to scale", "[run_picture]") {
  TrackConfig config;
  config.name = "wide";
  config.centerline = {Vec2(0, 0), Vec2(4, 0), Vec2(4, 1), Vec2(0, 1)};
  config.corridor_width = 0.4;
  config.gates = {{1.0, 0.3}, {5.5, 0.3}};
  config.obstacles = {{Vec2(2.0, 0.5), 0.1}};
  const RunRecord run;  // nothing driven: the track alone
  const RunPicture picture = RenderRunPicture(run, config);
  CHECK(picture.image.cols == RunPicture::kLongSide);
  CHECK(picture.image.rows < RunPicture::kLongSide);
  // The outer walls span 4.4 m (with the posts inside them) across the map.
  CHECK(picture.px_per_m * 4.4 == Approx(RunPicture::kLongSide - 2 * 28).margin(1.0));
  // Gates never reached; the obstacle is drawn where it is (grey).
  const cv::Vec3b o = At(picture, Vec2(2.0, 0.5));
  CHECK(Blue(o) == Green(o));
  CHECK(Green(o) == Red(o));
  CHECK(Green(o) < 200);
}

TEST_CASE("DrawRunPicture writes a PNG and names the file it cannot write", "[run_picture]") {
  const fs::path dir = ScratchDir("haptel-run-picture");
  const TrackConfig config = LoadTrack(ShippedFile("config/tracks/test-short.yaml"));
  const RunRecord run = LapOn(Track(config));

  CHECK(RunPicturePath("/data/study/runs.db", 12) ==
        fs::path("/data/study/pictures/runs-run-12.png"));
  const fs::path png = RunPicturePath(dir / "runs.db", 7);
  DrawRunPicture(run, config, png);  // creates pictures/
  const cv::Mat read = cv::imread(png.string());
  REQUIRE_FALSE(read.empty());
  CHECK(read.rows == RunPicture::kLongSide);
  CHECK(fs::directory_iterator(png.parent_path()) != fs::directory_iterator());
  CHECK_FALSE(fs::exists(fs::path(png.string() + ".partial")));

  const fs::path blocker = dir / "blocker";
  std::ofstream(blocker) << "a file, not a folder\n";
  const fs::path bad = blocker / "run-7.png";
  try {
    DrawRunPicture(run, config, bad);
    FAIL("expected std::runtime_error naming " << bad);
  } catch (const std::runtime_error& e) {
    INFO("message: " << e.what());
    CHECK(std::string(e.what()).find(bad.string()) != std::string::npos);
  }
  fs::remove_all(dir);
}

TEST_CASE("Two databases in one folder never share a picture's name", "[run_picture]") {
  const fs::path dir = ScratchDir("haptel-run-picture-two");
  const TrackConfig config = LoadTrack(ShippedFile("config/tracks/test-short.yaml"));
  const RunRecord run = LapOn(Track(config));
  // Run 1 of each: a picture each, neither overwriting the other.
  const fs::path first = RunPicturePath(dir / "pilot.db", 1);
  const fs::path second = RunPicturePath(dir / "study.db", 1);
  CHECK(first != second);
  CHECK(first.parent_path() == second.parent_path());
  DrawRunPicture(run, config, first);
  DrawRunPicture(run, config, second);
  CHECK(fs::exists(first));
  CHECK(fs::exists(second));
  CHECK(first.filename() == "pilot-run-1.png");
  CHECK(second.filename() == "study-run-1.png");
  fs::remove_all(dir);
}

TEST_CASE("The blimp's flight picture: the whole course to scale, gates by outcome, the flown path",
          "[run_picture]") {
  const haptel::BlimpCourseConfig course =
      haptel::LoadBlimpCourse(ShippedFile("config/tracks/blimp-hop.yaml"));
  REQUIRE(course.gates.size() == 1);
  REQUIRE(course.buildings.size() == 1);
  RunRecord run;
  run.config_name = "blimp";
  run.track = course.name;
  run.outcome = "completed";
  run.gates_total = 1;
  // A straight flight from the start along y = 0, through the gate, and on.
  for (int i = 0; i <= 60; ++i) run.path.push_back({0.5 * i, 1.0 * i, 0.0, 3.0});
  run.splits.push_back({0, true, 12.0});
  const RunPicture picture = haptel::record::RenderBlimpRunPicture(run, course);

  // The building is in the picture although the path never comes near it:
  // its outline at a corner, in the wall's grey.
  const auto& shed = course.buildings[0];
  const cv::Vec3b corner =
      At(picture, Vec2(shed.centre[0] + shed.size[0] / 2, shed.centre[1] + shed.size[1] / 2));
  CHECK(Red(corner) < 140);
  CHECK(std::abs(Red(corner) - Green(corner)) < 20);
  // The passed gate is a green bar across its opening, off the path too.
  const auto& gate = course.gates[0];
  CHECK(GreenDominant(At(picture, Vec2(gate.centre[0], gate.centre[1] + gate.width / 2 - 0.5))));
  // The landing circle's rim is black; the path is drawn where it flew.
  const cv::Vec3b rim =
      At(picture, Vec2(course.landing.centre[0] + course.landing.radius, course.landing.centre[1]));
  CHECK(Red(rim) < 90);
  CHECK(Green(rim) < 90);
  CHECK(At(picture, Vec2(20.0, 0.0)) != cv::Vec3b(255, 255, 255));
  // Not reached: the same gate grey.
  run.splits[0] = {0, false, -1.0};
  const RunPicture unreached = haptel::record::RenderBlimpRunPicture(run, course);
  CHECK_FALSE(
      GreenDominant(At(unreached, Vec2(gate.centre[0], gate.centre[1] + gate.width / 2 - 0.5))));
}
