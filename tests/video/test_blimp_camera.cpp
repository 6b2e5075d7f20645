// The blimp's pilot camera: a pinhole view of a blimp course from a 3-D pose.
// A 640x480 camera with a 90-degree horizontal field of view: focal length
// 320 px, principal point (320, 240). Cases look for colours at the pixels
// where the geometry projects.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <numbers>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <vector>

#include "haptel/config/blimp_course.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/testing/read_digit.hpp"
#include "haptel/video/blimp_camera.hpp"
#include "test_env.hpp"

using Catch::Matchers::Contains;
using haptel::BlimpBuildingSpec;
using haptel::BlimpCourseConfig;
using haptel::BlimpGateSpec;
using haptel::CameraConfig;
using haptel::CameraSourceKind;
using haptel::video::BlimpCourseCamera;
using haptel::video::CameraPose;
using haptel::video::MakeBlimpCameraSource;

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;
constexpr double kF = 320.0;  // focal length, px
constexpr int kW = 640;
constexpr int kH = 480;

CameraConfig Config() {
  CameraConfig c;
  c.width = kW;
  c.height = kH;
  c.fov_deg = 90.0;
  return c;
}

/// A course with nothing near the origin: start pad and landing zone far
/// behind a camera at the origin looking along +x or +y.
BlimpCourseConfig Empty() {
  BlimpCourseConfig c;
  c.name = "test";
  c.start.position = {-150.0, 30.0};
  c.landing.centre = {-150.0, -50.0};
  c.landing.radius = 8.0;
  return c;
}

BlimpBuildingSpec Building(double x, double y, double sx, double sy, double height) {
  BlimpBuildingSpec b;
  b.name = "b" + std::to_string(static_cast<int>(x)) + "_" + std::to_string(static_cast<int>(y));
  b.centre = {x, y};
  b.size = {sx, sy};
  b.height = height;
  return b;
}

BlimpGateSpec Gate(double x, double y, double z, double width, double height) {
  BlimpGateSpec g;
  g.name = "g";
  g.centre = {x, y, z};
  g.width = width;
  g.height = height;
  return g;
}

/// Level at 5 m, looking along +x, plus whatever the test changes.
CameraPose Level() {
  CameraPose p;
  p.z = 5.0;
  return p;
}

cv::Mat Render(const BlimpCourseCamera& camera, const CameraPose& pose) {
  cv::Mat image;
  camera.Render(pose, image);
  return image;
}

cv::Vec3b At(const cv::Mat& image, int row, int col) { return image.at<cv::Vec3b>(row, col); }

bool IsSky(const cv::Vec3b& p) { return p[0] > 150 && p[0] > p[2] + 15; }
bool IsGround(const cv::Vec3b& p) { return p[1] > p[0] + 15 && p[1] > p[2] + 15; }
bool IsGateColour(const cv::Vec3b& p) { return p[2] > p[1] + 40 && p[2] > p[0] + 60; }
bool IsWhite(const cv::Vec3b& p) { return p[0] > 200 && p[1] > 200 && p[2] > 200; }

int Distance(const cv::Vec3b& a, const cv::Vec3b& b) {
  return std::abs(a[0] - b[0]) + std::abs(a[1] - b[1]) + std::abs(a[2] - b[2]);
}

/// The first row from the top, in column `col`, that is not sky.
int HorizonRow(const cv::Mat& image, int col) {
  for (int r = 0; r < image.rows; ++r) {
    if (!IsSky(At(image, r, col))) return r;
  }
  return image.rows;
}

bool Identical(const cv::Mat& a, const cv::Mat& b) { return cv::norm(a, b, cv::NORM_INF) == 0; }

}  // namespace

TEST_CASE("blimp camera renders a BGR image of the configured size into the same buffer") {
  const BlimpCourseCamera camera(Empty(), Config());
  CHECK(camera.width() == kW);
  CHECK(camera.height() == kH);
  cv::Mat image(kH, kW, CV_8UC3, cv::Scalar::all(0));
  const uchar* data = image.data;
  camera.Render(Level(), image);
  CHECK(image.data == data);
  CameraPose p = Level();
  p.x = 12.0;
  p.roll = 0.3;
  camera.Render(p, image);
  CHECK(image.data == data);

  cv::Mat wrong(10, 10, CV_8UC1);
  camera.Render(Level(), wrong);
  CHECK(wrong.size() == cv::Size(kW, kH));
  CHECK(wrong.type() == CV_8UC3);
}

TEST_CASE("blimp camera level at 5 m: sky in the top rows, ground in the bottom rows") {
  const BlimpCourseCamera camera(Empty(), Config());
  const cv::Mat image = Render(camera, Level());
  for (const int col : {0, 100, kW / 2, 500, kW - 1}) {
    for (int r = 0; r < kH / 10; ++r) {
      INFO("column " << col << " row " << r);
      CHECK(IsSky(At(image, r, col)));
      CHECK(IsGround(At(image, kH - 1 - r, col)));
    }
    // The true horizon is the middle of the picture.
    INFO("column " << col);
    CHECK(std::abs(HorizonRow(image, col) - kH / 2) <= 1);
  }
}

TEST_CASE("blimp camera: the ground shows motion and height") {
  const BlimpCourseCamera camera(Empty(), Config());
  CameraPose p = Level();
  const cv::Mat here = Render(camera, p);
  p.x += 2.0;
  const cv::Mat ahead = Render(camera, p);
  p = Level();
  p.z = 12.0;
  const cv::Mat higher = Render(camera, p);
  const cv::Rect ground(0, kH / 2 + 20, kW, kH / 2 - 20);
  CHECK(cv::norm(here(ground), ahead(ground), cv::NORM_L1) > 1000);
  CHECK(cv::norm(here(ground), higher(ground), cv::NORM_L1) > 1000);
}

TEST_CASE("blimp camera: looking up, by the head or the body, moves the horizon down") {
  const BlimpCourseCamera camera(Empty(), Config());
  const int col = kW / 2;
  const double down = kH / 2.0 + kF * std::tan(10 * kDeg);  // 296.4
  const double up = kH / 2.0 - kF * std::tan(10 * kDeg);    // 183.6
  CameraPose p = Level();
  p.tilt = 10 * kDeg;
  const int tilted = HorizonRow(Render(camera, p), col);
  CHECK(std::abs(tilted - down) <= 2);
  p.tilt = 0.0;
  p.pitch = 10 * kDeg;
  CHECK(std::abs(HorizonRow(Render(camera, p), col) - down) <= 2);
  p.pitch = 5 * kDeg;
  p.tilt = 5 * kDeg;  // head and body add up
  CHECK(std::abs(HorizonRow(Render(camera, p), col) - tilted) <= 1);
  p.pitch = 0.0;
  p.tilt = -10 * kDeg;
  CHECK(std::abs(HorizonRow(Render(camera, p), col) - up) <= 2);
  p.tilt = 0.0;
  p.pitch = -10 * kDeg;
  CHECK(std::abs(HorizonRow(Render(camera, p), col) - up) <= 2);
}

TEST_CASE("blimp camera: rolling right (right side down) raises the horizon on the right") {
  const BlimpCourseCamera camera(Empty(), Config());
  // Horizon row at column u: cy + (cx - u) * tan(roll).
  const int left = 20;
  const int right = kW - 20;
  const double slope = std::tan(10 * kDeg);
  CameraPose p = Level();
  p.roll = 10 * kDeg;
  const cv::Mat rolled = Render(camera, p);
  const int at_left = HorizonRow(rolled, left);
  const int at_right = HorizonRow(rolled, right);
  CHECK(at_right < at_left - 80);
  CHECK(std::abs(at_left - (kH / 2.0 + (kW / 2.0 - left - 0.5) * slope)) <= 2);
  CHECK(std::abs(at_right - (kH / 2.0 + (kW / 2.0 - right - 0.5) * slope)) <= 2);
  p.roll = -10 * kDeg;
  const cv::Mat other = Render(camera, p);
  CHECK(HorizonRow(other, left) < HorizonRow(other, right) - 80);
  // The head's pan keeps the horizon level for a level body.
  p = Level();
  p.pan = 30 * kDeg;
  const cv::Mat panned = Render(camera, p);
  CHECK(HorizonRow(panned, left) == HorizonRow(panned, right));
}

TEST_CASE("blimp camera: a building ahead fills the centre, one behind the camera is not drawn") {
  const cv::Mat empty = Render(BlimpCourseCamera(Empty(), Config()), Level());
  BlimpCourseConfig ahead = Empty();
  ahead.buildings.push_back(Building(30.0, 0.0, 10.0, 10.0, 20.0));
  const cv::Mat image = Render(BlimpCourseCamera(ahead, Config()), Level());
  const cv::Vec3b centre = At(image, kH / 2, kW / 2);
  INFO("centre " << centre);
  CHECK_FALSE(IsSky(centre));
  CHECK_FALSE(IsGround(centre));
  CHECK(Distance(centre, At(empty, kH / 2, kW / 2)) > 60);
  // Its front face (x = 25, y in [-5, 5], z up to 20) spans columns 256 to 384
  // and reaches row 240 - 320 * 15 / 25 = 48 above the horizon.
  CHECK(Distance(At(image, 60, kW / 2), centre) < 10);
  CHECK(Distance(At(image, kH / 2, 265), centre) < 10);
  CHECK(IsSky(At(image, 30, kW / 2)));
  CHECK(IsSky(At(image, kH / 2 - 20, 240)));

  BlimpCourseConfig behind = Empty();
  behind.buildings.push_back(Building(-30.0, 0.0, 10.0, 10.0, 20.0));
  CHECK(Identical(Render(BlimpCourseCamera(behind, Config()), Level()), empty));
}

TEST_CASE("blimp camera: a gate ahead shows its frame, the sky through it, and its number") {
  BlimpCourseConfig course = Empty();
  course.gates.push_back(Gate(20.0, 0.0, 5.0, 6.0, 4.0));
  const cv::Mat image = Render(BlimpCourseCamera(course, Config()), Level());
  // Bars 0.32 m thick around the 6 x 4 m opening, front faces at x = 19.84:
  // the left post spans y in [3, 3.32] (columns 266.5 to 271.6), the top bar
  // z in [7, 7.32] (rows 201.7 to 207.7).
  const double d = 20.0 - 0.16;
  const int post_col = static_cast<int>(kW / 2.0 - kF * 3.16 / d);
  const int top_row = static_cast<int>(kH / 2.0 - kF * 2.16 / d);
  INFO("post " << At(image, kH / 2, post_col) << " top " << At(image, top_row, kW / 2));
  CHECK(IsGateColour(At(image, kH / 2 - 10, post_col)));
  CHECK(IsGateColour(At(image, kH / 2 + 10, kW - post_col)));
  CHECK(IsGateColour(At(image, top_row, kW / 2)));
  CHECK(IsGateColour(At(image, kH - top_row, kW / 2)));
  // Sky through the opening above the horizon, ground below it.
  CHECK(IsSky(At(image, kH / 2 - 15, kW / 2)));
  CHECK(IsSky(At(image, kH / 2 - 15, post_col + 10)));
  CHECK(IsGround(At(image, kH / 2 + 15, kW / 2)));
  // Its number, white, just above the top bar (1.2 m high text: ~19 px).
  int white = 0;
  for (int r = top_row - 35; r < top_row - 2; ++r) {
    for (int c = kW / 2 - 20; c < kW / 2 + 20; ++c) white += IsWhite(At(image, r, c)) ? 1 : 0;
  }
  CHECK(white > 10);
}

TEST_CASE("blimp camera: gates all have the same colour") {
  BlimpCourseConfig course = Empty();
  course.gates.push_back(Gate(20.0, 6.0, 5.0, 6.0, 4.0));
  course.gates.push_back(Gate(20.0, -6.0, 5.0, 6.0, 4.0));
  const cv::Mat image = Render(BlimpCourseCamera(course, Config()), Level());
  // Their top bars' middles, at y = +-6.
  const int row = static_cast<int>(kH / 2.0 - kF * 2.16 / 19.84);
  const cv::Vec3b left = At(image, row, static_cast<int>(kW / 2.0 - kF * 6.0 / 19.84));
  const cv::Vec3b right = At(image, row, static_cast<int>(kW / 2.0 + kF * 6.0 / 19.84));
  INFO(left << " " << right);
  CHECK(IsGateColour(left));
  CHECK(Distance(left, right) <= 3);
}

TEST_CASE("blimp camera: panning left by 90 degrees brings a building on the left into view") {
  BlimpCourseConfig course = Empty();
  course.buildings.push_back(Building(0.0, 30.0, 10.0, 10.0, 20.0));
  const BlimpCourseCamera camera(course, Config());
  const cv::Mat empty = Render(BlimpCourseCamera(Empty(), Config()), Level());
  CHECK(Identical(Render(camera, Level()), empty));  // 78 degrees left at least: out of view
  CameraPose p = Level();
  p.pan = kPi / 2;
  const cv::Vec3b centre = At(Render(camera, p), kH / 2, kW / 2);
  INFO("centre " << centre);
  CHECK_FALSE(IsSky(centre));
  CHECK_FALSE(IsGround(centre));
  // The same view with the body turned instead of the head.
  p = Level();
  p.heading = kPi / 2;
  CHECK(Distance(At(Render(camera, p), kH / 2, kW / 2), centre) == 0);
}

TEST_CASE("blimp camera clips a building beside the camera at the near plane") {
  // A wall along the camera's left, from 10 m behind it to 10 m ahead, 6 m
  // away: it covers the left part of the view only, up to column
  // 320 - 320 * 6 / 10 = 128.
  BlimpCourseConfig course = Empty();
  course.buildings.push_back(Building(0.0, 8.0, 20.0, 4.0, 20.0));
  const cv::Mat image = Render(BlimpCourseCamera(course, Config()), Level());
  const cv::Mat empty = Render(BlimpCourseCamera(Empty(), Config()), Level());
  const cv::Rect right_part(140, 0, kW - 140, kH);
  CHECK(Identical(image(right_part), empty(right_part)));
  for (const int row : {5, kH / 2, kH - 5}) {
    const cv::Vec3b p = At(image, row, 3);
    INFO("row " << row << ": " << p);
    CHECK_FALSE(IsSky(p));
    CHECK_FALSE(IsGround(p));
  }
}

TEST_CASE("blimp camera survives poses inside, against and around buildings and gates") {
  BlimpCourseConfig course = Empty();
  course.buildings.push_back(Building(0.0, 0.0, 10.0, 10.0, 20.0));
  course.gates.push_back(Gate(30.0, 0.0, 5.0, 6.0, 4.0));
  const BlimpCourseCamera camera(course, Config());

  SECTION("facing a wall 0.5 m away: the wall fills the view") {
    CameraPose p = Level();
    p.x = -5.5;
    const cv::Mat image = Render(camera, p);
    const cv::Vec3b centre = At(image, kH / 2, kW / 2);
    CHECK_FALSE(IsSky(centre));
    int off = 0;
    for (int r = 0; r < kH; ++r) {
      for (int c = 0; c < kW; ++c) off += Distance(At(image, r, c), centre) > 3 ? 1 : 0;
    }
    CHECK(off == 0);
  }

  SECTION("poses inside, on the faces, edges and corners, and in the gate's bars") {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> angle(-kPi, kPi);
    const std::vector<std::array<double, 3>> places = {
        {0.0, 0.0, 5.0},  {-5.0, 0.0, 5.0},  {-5.0, -5.0, 5.0}, {5.0, 5.0, 20.0},
        {-5.0, 0.0, 0.0}, {0.0, 0.0, 20.0},  {30.0, 3.1, 5.0},  {30.0, 0.0, 7.1},
        {30.0, 0.0, 0.0}, {-5.03, 2.0, 0.01}};
    cv::Mat image;
    for (const auto& at : places) {
      for (int i = 0; i < 40; ++i) {
        CameraPose p;
        p.x = at[0];
        p.y = at[1];
        p.z = at[2];
        p.heading = angle(rng);
        p.pitch = angle(rng) / 2;
        p.roll = angle(rng);
        p.pan = angle(rng);
        p.tilt = angle(rng) / 2;
        camera.Render(p, image);
        REQUIRE(image.size() == cv::Size(kW, kH));
        REQUIRE(image.type() == CV_8UC3);
        // Deterministic: the same pose draws the same picture.
        CHECK(Identical(Render(camera, p), image));
      }
    }
  }

  SECTION("straight up, straight down, upside down") {
    for (const double tilt : {kPi / 2, -kPi / 2}) {
      CameraPose p = Level();
      p.x = -20.0;
      p.tilt = tilt;
      const cv::Mat image = Render(camera, p);
      const bool up = tilt > 0;
      INFO("tilt " << tilt);
      CHECK((up ? IsSky(At(image, 5, 5)) : IsGround(At(image, 5, 5))));
      CHECK((up ? IsSky(At(image, kH - 5, kW - 5)) : IsGround(At(image, kH - 5, kW - 5))));
    }
    CameraPose p = Level();
    p.x = -20.0;
    p.pan = kPi;  // looking away from the building
    p.roll = kPi;
    const cv::Mat image = Render(camera, p);
    CHECK(IsGround(At(image, 5, kW / 2)));
    CHECK(IsSky(At(image, kH - 5, kW / 2)));
  }

  SECTION("a meaningless pose is a uniform grey image") {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (const CameraPose& p :
         {CameraPose{nan, 0.0, 0.0, 5.0}, CameraPose{0.0, 0.0, 0.0, 1e9},
          CameraPose{0.0, 0.0, 0.0, 5.0, 0.0, 0.0, 0.0, std::numeric_limits<double>::infinity()}}) {
      const cv::Mat image = Render(camera, p);
      REQUIRE(image.size() == cv::Size(kW, kH));
      double lo = 0, hi = 0;
      cv::minMaxLoc(image.reshape(1), &lo, &hi);
      CHECK(lo == hi);
      CHECK(lo > 0.0);    // grey: not black,
      CHECK(hi < 255.0);  // not white
    }
  }
}

TEST_CASE("blimp camera source: synthetic renders the course; device and file open as usual") {
  const std::string config_file = "config/vehicles/sim-blimp.yaml";
  BlimpCourseConfig course = Empty();
  course.buildings.push_back(Building(30.0, 0.0, 10.0, 10.0, 20.0));
  CameraConfig c = Config();
  c.width = 96;
  c.height = 72;
  const auto source = MakeBlimpCameraSource(c, course, config_file);
  CHECK(source->RendersAtGrab());
  CHECK(source->Describe() == "synthetic");
  cv::Mat a, b;
  REQUIRE(source->Grab(Level(), a));
  CameraPose p = Level();
  p.pan = kPi;
  REQUIRE(source->Grab(p, b));
  CHECK(a.size() == cv::Size(96, 72));
  CHECK(cv::norm(a, b, cv::NORM_L1) > 0);
  CHECK_FALSE(source->Ended());

  c.source = CameraSourceKind::kFile;
  c.file = haptel::test::ScratchDir("test_blimp_camera") / "missing.avi";
  const std::string msg = haptel::test::WhatOf<haptel::ConfigError>(
      [&] { MakeBlimpCameraSource(c, course, config_file); });
  CHECK_THAT(msg, Contains(config_file));
  CHECK_THAT(msg, Contains("'camera.file'"));
  CHECK_THAT(msg, Contains("no such file"));
}

TEST_CASE("blimp camera renders the shipped course: the first gate ahead of the start") {
  const BlimpCourseConfig course = haptel::LoadBlimpCourse("config/tracks/blimp-course.yaml");
  REQUIRE_FALSE(course.gates.empty());
  const BlimpCourseCamera camera(course, Config());
  CameraPose p;
  p.x = course.start.position[0];
  p.y = course.start.position[1];
  p.z = 2.0;
  const auto& gate = course.gates.front();
  p.heading = std::atan2(gate.centre[1] - p.y, gate.centre[0] - p.x);
  p.tilt = std::atan2(gate.centre[2] - p.z, std::hypot(gate.centre[0] - p.x, gate.centre[1] - p.y));
  const cv::Mat image = Render(camera, p);
  int gate_pixels = 0;
  for (int r = 0; r < kH; ++r) {
    for (int c = 0; c < kW; ++c) gate_pixels += IsGateColour(At(image, r, c)) ? 1 : 0;
  }
  CHECK(gate_pixels > 100);
  // The opening's centre is at the centre of the picture: sky or ground, not frame.
  CHECK_FALSE(IsGateColour(At(image, kH / 2, kW / 2)));
}

// The gate number's reader, shared with the control room's window test.
using haptel::testing::ReadDigit;
using haptel::testing::WhiteMask;
using Reading = haptel::testing::DigitReading;

TEST_CASE(
    "the surveillance camera zoomed in reads a gate's number 200 m off that its wide view cannot; "
    "the picture says its zoom") {
  BlimpCourseConfig course = Empty();
  // Gates 1 and 2 behind the camera; gate 3, the thesis's size, 200 m ahead.
  course.gates.push_back(Gate(-60.0, 0.0, 5.0, 12.0, 7.0));
  course.gates.push_back(Gate(-60.0, 40.0, 5.0, 12.0, 7.0));
  course.gates.push_back(Gate(200.0, 0.0, 5.0, 12.0, 7.0));
  CameraConfig config = Config();
  config.name = "surveillance";
  config.fov_deg = 60.0;
  config.zoom_max = 10.0;
  const BlimpCourseCamera camera(course, config);
  CameraPose pose = Level();
  const cv::Mat wide = Render(camera, pose);
  pose.zoom = 10.0;
  const cv::Mat zoomed = Render(camera, pose);

  // The zoom line at the bottom left is left out of the reading.
  const cv::Rect above_zoom_line(0, 0, kW, kH - 40);
  const Reading far = ReadDigit(WhiteMask(wide)(above_zoom_line));
  const Reading near = ReadDigit(WhiteMask(zoomed)(above_zoom_line));
  INFO("wide: " << far.digit << " (" << far.score << "), zoomed: " << near.digit << " ("
                << near.score << ")");
  CHECK(near.digit == 3);
  CHECK(near.score > 0.6);
  CHECK(far.score < 0.3);  // nothing there to read

  // "SURV 1.0x" and "SURV 10.0x": yellow text in the bottom left corner,
  // different at the two zooms; nothing of it elsewhere.
  const auto zoom_line = [](const cv::Mat& image) {
    cv::Mat yellow;
    cv::inRange(image(cv::Rect(0, kH - 40, 200, 40)), cv::Scalar(0, 200, 200),
                cv::Scalar(140, 255, 255), yellow);
    return yellow;
  };
  CHECK(cv::countNonZero(zoom_line(wide)) > 30);
  CHECK(cv::countNonZero(zoom_line(zoomed)) > cv::countNonZero(zoom_line(wide)));
  // The pilot's camera (no zoom) has no such line.
  const cv::Mat pilot = Render(BlimpCourseCamera(course, Config()), Level());
  cv::Mat yellow;
  cv::inRange(pilot, cv::Scalar(0, 200, 200), cv::Scalar(140, 255, 255), yellow);
  CHECK(cv::countNonZero(yellow) == 0);
}
