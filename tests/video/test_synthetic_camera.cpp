#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <numbers>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "haptel/config/error.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/video/synthetic_camera.hpp"

using haptel::CameraConfig;
using haptel::LoadTrack;
using haptel::Track;
using haptel::Vec2;
using haptel::video::CameraPose;
using haptel::video::SyntheticCamera;

namespace {

// grand-prix: the first straight runs along +x from (0,0) to (3.4,0), corridor
// 1 m wide (walls at y = +-0.5); gate 1 at x = 1.7 has its left post at
// (1.7, 0.3) and its right post at (1.7, -0.3).
const Track& GrandPrix() {
  static const Track track(LoadTrack("config/tracks/grand-prix.yaml"));
  return track;
}

bool IsRed(const cv::Vec3b& p) { return p[2] > 80 && p[2] > 2 * p[1] && p[2] > 2 * p[0]; }
bool IsGreen(const cv::Vec3b& p) { return p[1] > 80 && p[1] > 2 * p[2] && p[1] > 2 * p[0]; }

struct Run {
  int begin = 0;  // first column
  int end = 0;    // one past the last
  double centre() const { return (begin + end) / 2.0; }
  int width() const { return end - begin; }
};

/// The widest run of consecutive columns in `row` whose pixel passes `test`.
template <typename Test>
Run WidestRun(const cv::Mat& image, int row, Test test) {
  Run best;
  int start = -1;
  for (int c = 0; c <= image.cols; ++c) {
    const bool hit = c < image.cols && test(image.at<cv::Vec3b>(row, c));
    if (hit && start < 0) start = c;
    if (!hit && start >= 0) {
      if (c - start > best.width()) best = {start, c};
      start = -1;
    }
  }
  return best;
}

double ColourDistance(const cv::Vec3b& a, const cv::Vec3b& b) {
  return std::abs(a[0] - b[0]) + std::abs(a[1] - b[1]) + std::abs(a[2] - b[2]);
}

/// Focal length in pixels: half the width over the tangent of half the FOV.
double FocalPx(const CameraConfig& config) {
  return (config.width / 2.0) / std::tan(config.fov_deg * std::numbers::pi / 360.0);
}

cv::Mat Render(const SyntheticCamera& camera, CameraPose pose) {
  cv::Mat image;
  camera.Render(pose, image);
  return image;
}

}  // namespace

TEST_CASE("synthetic camera renders a BGR image of the configured size") {
  CameraConfig config;
  config.width = 160;
  config.height = 90;
  const SyntheticCamera camera(GrandPrix(), config);
  CHECK(camera.width() == 160);
  CHECK(camera.height() == 90);
  const Vec2 start = GrandPrix().StartPosition();
  const cv::Mat image = Render(camera, {start.x(), start.y(), GrandPrix().StartHeading()});
  CHECK(image.cols == 160);
  CHECK(image.rows == 90);
  CHECK(image.type() == CV_8UC3);
}

TEST_CASE("synthetic camera reuses the output buffer and resizes a wrong one") {
  const CameraConfig config;
  const SyntheticCamera camera(GrandPrix(), config);
  cv::Mat image(config.height, config.width, CV_8UC3, cv::Scalar::all(0));
  const uchar* data = image.data;
  camera.Render({0.5, 0.0, 0.0}, image);
  CHECK(image.data == data);
  camera.Render({1.5, 0.1, 0.3}, image);
  CHECK(image.data == data);

  cv::Mat wrong(10, 10, CV_8UC1);
  camera.Render({0.5, 0.0, 0.0}, wrong);
  CHECK(wrong.cols == config.width);
  CHECK(wrong.rows == config.height);
  CHECK(wrong.type() == CV_8UC3);
}

TEST_CASE("synthetic camera shows sky above the horizon and floor below it") {
  const CameraConfig config;
  const SyntheticCamera camera(GrandPrix(), config);
  // Down the first straight: nothing near in the centre column.
  const cv::Mat image = Render(camera, {-0.6, 0.0, 0.0});
  const int centre = config.width / 2;
  const cv::Vec3b sky = image.at<cv::Vec3b>(10, centre);
  const cv::Vec3b floor = image.at<cv::Vec3b>(config.height - 10, centre);
  INFO("sky " << sky << " floor " << floor);
  CHECK(sky[0] > sky[2] + 20);  // blue
  CHECK(floor[2] >= floor[0]);  // grey/brown, not blue
  CHECK(ColourDistance(sky, floor) > 100);
  // Every row of the top tenth is sky-blue, every row of the bottom tenth is not.
  for (int r = 0; r < config.height / 10; ++r) {
    const cv::Vec3b top = image.at<cv::Vec3b>(r, centre);
    const cv::Vec3b bottom = image.at<cv::Vec3b>(config.height - 1 - r, centre);
    CHECK(top[0] > top[2] + 20);
    CHECK(bottom[0] <= bottom[2]);
  }
}

TEST_CASE("synthetic camera shows a wall filling the view when facing it closely") {
  const CameraConfig config;
  const SyntheticCamera camera(GrandPrix(), config);
  const int centre = config.width / 2;
  // 0.3 m from the left wall of the first straight (y = 0.5), facing it.
  const cv::Mat wall = Render(camera, {1.0, 0.2, std::numbers::pi / 2});
  const cv::Mat open = Render(camera, {-0.6, 0.0, 0.0});
  const cv::Vec3b wall_centre = wall.at<cv::Vec3b>(config.height / 2, centre);
  int same = 0;
  for (int r = 0; r < config.height; ++r) {
    if (ColourDistance(wall.at<cv::Vec3b>(r, centre), wall_centre) < 30) ++same;
  }
  // The panel is 0.25 m tall and the camera 0.12 m up: it covers the whole column.
  CHECK(same >= config.height * 95 / 100);
  // ... which then looks like neither sky nor floor.
  CHECK(ColourDistance(wall.at<cv::Vec3b>(10, centre), open.at<cv::Vec3b>(10, centre)) > 40);
  CHECK(ColourDistance(wall.at<cv::Vec3b>(config.height - 10, centre),
                       open.at<cv::Vec3b>(config.height - 10, centre)) > 40);
}

TEST_CASE("synthetic camera: a wall far away is a band across the horizon") {
  const CameraConfig config;
  const SyntheticCamera camera(GrandPrix(), config);
  const int centre = config.width / 2;
  // Facing the right wall (y = -0.5) from the left one: 0.9 m away.
  const cv::Mat near = Render(camera, {1.0, 0.4, -std::numbers::pi / 2});
  const cv::Mat open = Render(camera, {-0.6, 0.0, 0.0});
  const cv::Vec3b at_horizon = near.at<cv::Vec3b>(config.height / 2, centre);
  CHECK(ColourDistance(near.at<cv::Vec3b>(5, centre), at_horizon) > 40);  // sky above
  CHECK(ColourDistance(near.at<cv::Vec3b>(config.height - 5, centre), at_horizon) > 40);
  // ... and the band is not sky.
  CHECK(ColourDistance(at_horizon, open.at<cv::Vec3b>(config.height / 2 - 30, centre)) > 40);
}

TEST_CASE("synthetic camera shows gate posts red on the left and green on the right") {
  const CameraConfig config;
  const SyntheticCamera camera(GrandPrix(), config);
  const int row = config.height / 2 + 5;
  const int centre = config.width / 2;
  const double f = FocalPx(config);  // 307 px at 320 wide and 55 deg

  SECTION("straight ahead the left post is in the centre column") {
    const cv::Mat image = Render(camera, {0.7, 0.3, 0.0});  // 1 m before it
    const Run red = WidestRun(image, row, IsRed);
    REQUIRE(red.width() > 0);
    CHECK(std::abs(red.centre() - centre) <= 2.0);
  }

  SECTION("from the gate's centre line the red post is left, the green one right") {
    const cv::Mat image = Render(camera, {0.7, 0.0, 0.0});
    const Run red = WidestRun(image, row, IsRed);
    const Run green = WidestRun(image, row, IsGreen);
    REQUIRE(red.width() > 0);
    REQUIRE(green.width() > 0);
    // The posts are 0.3 m either side, 1 m ahead: f * 0.3 px off centre.
    CHECK(red.centre() < centre - 0.13 * f);
    CHECK(green.centre() > centre + 0.13 * f);
    // Symmetric view, symmetric posts.
    CHECK(std::abs((centre - red.centre()) - (green.centre() - centre)) <= 2.0);
    CHECK(std::abs(red.width() - green.width()) <= 1);
  }

  SECTION("yawing right moves the post left in the image") {
    const Run ahead = WidestRun(Render(camera, {0.7, 0.3, 0.0}), row, IsRed);
    const Run yawed = WidestRun(Render(camera, {0.7, 0.3, -0.1}), row, IsRed);
    REQUIRE(ahead.width() > 0);
    REQUIRE(yawed.width() > 0);
    // The post moves by f * tan(0.1) px (31 px at 320 wide).
    const double shift = f * std::tan(0.1);
    CHECK(yawed.centre() < ahead.centre() - 0.8 * shift);
    CHECK(yawed.centre() > ahead.centre() - 1.2 * shift);
    const Run left_yaw = WidestRun(Render(camera, {0.7, 0.3, 0.1}), row, IsRed);
    CHECK(left_yaw.centre() > ahead.centre() + 0.8 * shift);
  }

  SECTION("a nearer post looks wider") {
    const Run near = WidestRun(Render(camera, {0.7, 0.3, 0.0}), row, IsRed);  // 1 m
    const Run far = WidestRun(Render(camera, {-0.3, 0.3, 0.0}), row, IsRed);  // 2 m
    REQUIRE(far.width() > 0);
    CHECK(near.width() > far.width());
    // 8 cm post: about 2 * f * 0.04 / d px.
    CHECK(near.width() == Approx(2 * f * 0.04 / 1.0).margin(3));
    CHECK(far.width() == Approx(2 * f * 0.04 / 2.0).margin(3));
  }

  SECTION("a nearer post stands taller") {
    const auto height = [&](const cv::Mat& image) {
      int rows = 0;
      for (int r = 0; r < image.rows; ++r) rows += IsRed(image.at<cv::Vec3b>(r, centre)) ? 1 : 0;
      return rows;
    };
    CHECK(height(Render(camera, {0.7, 0.3, 0.0})) > height(Render(camera, {-0.3, 0.3, 0.0})));
  }
}

TEST_CASE("synthetic camera draws nearer things over farther ones") {
  const CameraConfig config;
  const SyntheticCamera camera(GrandPrix(), config);
  // Behind the right post of gate 1, looking at it along the straight
  // towards the far wall: the post covers the wall behind it.
  const cv::Mat image = Render(camera, {1.2, -0.3, 0.0});
  const int centre = config.width / 2;
  CHECK(IsGreen(image.at<cv::Vec3b>(config.height / 2, centre)));
  CHECK(IsGreen(image.at<cv::Vec3b>(config.height / 2 - 10, centre)));
  // From outside the track, 1 m behind the right wall (y = -0.5): the wall
  // hides the post (1.2 m away) but for its top, which stands 5 cm higher.
  const cv::Mat outside = Render(camera, {1.7, -1.5, std::numbers::pi / 2});
  const int wall_top = static_cast<int>(config.height / 2 - FocalPx(config) * (0.25 - 0.12) / 1.0);
  int above = 0;
  int below = 0;
  for (int r = 0; r < config.height; ++r) {
    for (int c = 0; c < config.width; ++c) {
      if (IsGreen(outside.at<cv::Vec3b>(r, c))) ++(r < wall_top ? above : below);
    }
  }
  CHECK(above > 0);
  CHECK(below == 0);
}

TEST_CASE("synthetic camera shows round obstacles in orange") {
  const CameraConfig config;
  const SyntheticCamera camera(GrandPrix(), config);
  // Obstacle at (2.6, -0.36), looked at from 0.7 m.
  const cv::Mat image = Render(camera, {1.9, -0.36, 0.0});
  const cv::Vec3b p = image.at<cv::Vec3b>(config.height / 2, config.width / 2);
  INFO("pixel " << p);
  CHECK(p[2] > 150);
  CHECK(p[1] > 60);
  CHECK(p[1] < p[2]);
  CHECK(p[0] < 40);
}

TEST_CASE("synthetic camera: moving forward changes the floor") {
  const CameraConfig config;
  const SyntheticCamera camera(GrandPrix(), config);
  const cv::Mat a = Render(camera, {0.0, 0.0, 0.0});
  const cv::Mat b = Render(camera, {0.1, 0.0, 0.0});
  // The bottom sixth of the image: floor within half a metre.
  const cv::Rect bottom(0, config.height * 5 / 6, config.width, config.height / 6);
  CHECK(cv::norm(a(bottom), b(bottom), cv::NORM_L1) > 0);
}

TEST_CASE("synthetic camera rendering is deterministic") {
  const SyntheticCamera camera(GrandPrix(), CameraConfig{});
  const Vec2 start = GrandPrix().StartPosition();
  const CameraPose pose{start.x(), start.y(), GrandPrix().StartHeading()};
  const cv::Mat a = Render(camera, pose);
  cv::Mat b;
  camera.Render({2.0, 1.0, 1.0}, b);  // something else first, same buffer after
  camera.Render(pose, b);
  REQUIRE(a.size() == b.size());
  CHECK(cv::norm(a, b, cv::NORM_INF) == 0);
}

TEST_CASE("synthetic camera survives any pose") {
  const CameraConfig config;
  const SyntheticCamera camera(GrandPrix(), config);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();

  SECTION("NaN or infinite pose: a uniform image") {
    for (const CameraPose& pose :
         {CameraPose{nan, 0, 0}, CameraPose{0, nan, 0}, CameraPose{0, 0, nan},
          CameraPose{inf, 0, 0}, CameraPose{0, -inf, 0}, CameraPose{1e300, 1e300, 0}}) {
      cv::Mat image;
      REQUIRE_NOTHROW(camera.Render(pose, image));
      REQUIRE(image.size() == cv::Size(config.width, config.height));
      REQUIRE(image.type() == CV_8UC3);
      double lo = 0, hi = 0;
      cv::minMaxLoc(image.reshape(1), &lo, &hi);
      CHECK(lo == hi);
    }
  }

  SECTION("poses on walls, on wall corners, on posts, outside the track") {
    const Track& track = GrandPrix();
    std::vector<CameraPose> poses;
    for (const auto& wall : track.walls()) {
      const Vec2 mid = (wall.a + wall.b) / 2;
      const Vec2 d = wall.b - wall.a;
      const double along = std::atan2(d.y(), d.x());
      for (double h :
           {along, along + std::numbers::pi / 2, along + 0.3, along + std::numbers::pi}) {
        poses.push_back({wall.a.x(), wall.a.y(), h});
        poses.push_back({mid.x(), mid.y(), h});
      }
    }
    for (const auto& c : track.round_obstacles()) {
      poses.push_back({c.center.x(), c.center.y(), 0.0});
      poses.push_back({c.center.x() + c.radius, c.center.y(), std::numbers::pi});
      poses.push_back({c.center.x() - c.radius - 0.021, c.center.y(), 0.0});
    }
    poses.push_back({50.0, -30.0, 2.0});
    poses.push_back({-1e5, 1e5, -0.7});
    poses.push_back({1.0, 0.0, 1e9});
    cv::Mat image;
    for (const CameraPose& pose : poses) {
      REQUIRE_NOTHROW(camera.Render(pose, image));
      REQUIRE(image.size() == cv::Size(config.width, config.height));
    }
  }

  SECTION("random poses on both shipped tracks") {
    const Track short_track(LoadTrack("config/tracks/test-short.yaml"));
    CameraConfig small = config;
    small.width = 96;
    small.height = 72;
    small.fov_deg = 120.0;
    const SyntheticCamera wide(short_track, small);
    std::mt19937 rng(42);
    std::uniform_real_distribution<double> x(-2.0, 5.5), y(-1.5, 4.0), h(-10.0, 10.0);
    cv::Mat a, b;
    for (int i = 0; i < 500; ++i) {
      const CameraPose pose{x(rng), y(rng), h(rng)};
      REQUIRE_NOTHROW(camera.Render(pose, a));
      REQUIRE_NOTHROW(wide.Render({pose.x * 0.3, pose.y * 0.3, pose.heading}, b));
    }
    CHECK(b.size() == cv::Size(96, 72));
  }
}

TEST_CASE("synthetic camera rejects a meaningless camera configuration") {
  CameraConfig bad;
  bad.width = 0;
  CHECK_THROWS_AS(SyntheticCamera(GrandPrix(), bad), std::invalid_argument);
  bad = CameraConfig{};
  bad.fov_deg = 180.0;
  CHECK_THROWS_AS(SyntheticCamera(GrandPrix(), bad), std::invalid_argument);
  bad = CameraConfig{};
  bad.mount_height = 0.0;
  CHECK_THROWS_AS(SyntheticCamera(GrandPrix(), bad), std::invalid_argument);
}

TEST_CASE("synthetic camera: the refusal names the key CameraConfig::ValidateOrThrow found") {
  CameraConfig bad;
  bad.height = 8;
  CHECK_THROWS_WITH(SyntheticCamera(GrandPrix(), bad),
                    Catch::Contains("height: expected a whole number in [16, 4096]"));
  bad = CameraConfig{};
  bad.fov_deg = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_AS(SyntheticCamera(GrandPrix(), bad), haptel::ConfigFieldError);
}
