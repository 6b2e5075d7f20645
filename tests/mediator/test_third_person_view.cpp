// The third-person view (a practice lap; haptel run --third-person): the
// chase camera behind the robot's reported pose, the robot's body drawn into
// its picture by the predictive display's projection, the pictures handed to
// the view without allocating, and — drawn by the real renderer offscreen —
// the labelled inset with the robot in its lower middle, and nothing of it
// when the model has no third-person picture.
#include <atomic>
#include <catch2/catch.hpp>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <thread>

#include "../view/offscreen_gl.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/mediator/third_person_view.hpp"
#include "haptel/video/synthetic_camera.hpp"
#include "haptel/view/renderer.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::mediator;

namespace {

/// The robot's body colour as drawn (dark blue, BGR (120, 62, 28)), also
/// through the renderer's filtering: nothing on the track or in the room is
/// this blue with so little green.
bool Body(cv::Vec3b c) { return c[0] > 90 && c[0] - c[2] > 60 && c[1] < 90 && c[2] < 60; }
bool White(cv::Vec3b c) { return c[0] > 200 && c[1] > 200 && c[2] > 200; }

/// The body-coloured pixels of `bgr` inside `box`: how many, and their centroid.
struct Blob {
  int count = 0;
  double x = 0, y = 0;
};
Blob BodyIn(const cv::Mat& bgr, const cv::Rect& box) {
  Blob b;
  for (int r = box.y; r < box.y + box.height; ++r) {
    for (int c = box.x; c < box.x + box.width; ++c) {
      if (!Body(bgr.at<cv::Vec3b>(r, c))) continue;
      ++b.count;
      b.x += c;
      b.y += r;
    }
  }
  if (b.count > 0) {
    b.x /= b.count;
    b.y /= b.count;
  }
  return b;
}

int WhiteIn(const cv::Mat& bgr, const cv::Rect& box) {
  int n = 0;
  for (int r = box.y; r < box.y + box.height; ++r) {
    for (int c = box.x; c < box.x + box.width; ++c) n += White(bgr.at<cv::Vec3b>(r, c)) ? 1 : 0;
  }
  return n;
}

cv::Rect RectOf(const view::TileBox& b) { return {b.x, b.y, b.width, b.height}; }

}  // namespace

TEST_CASE("the chase camera stands behind the robot, which its picture shows in the lower middle") {
  const VehicleConfig vehicle = LoadVehicle("config/vehicles/sim-robot.yaml");
  const Track track(LoadTrack("config/tracks/test-short.yaml"));
  ThirdPersonView chase(track, vehicle);
  const PredictedPose robot{1.0, track.StartPosition().x(), track.StartPosition().y(),
                            track.StartHeading()};

  // Three body lengths behind it, looking along its heading, above the floor.
  const video::CameraPose pose = chase.ChasePose(robot);
  const double back = ThirdPersonView::kBackLengths * 2.0 * vehicle.body.radius;
  CHECK(pose.x == Approx(robot.x - back * std::cos(robot.heading)));
  CHECK(pose.y == Approx(robot.y - back * std::sin(robot.heading)));
  CHECK(pose.heading == robot.heading);
  CHECK(chase.camera().mount_height > chase.body_height_m());  // it looks down on the robot

  cv::Mat with;
  chase.Render(robot, with);
  REQUIRE(with.cols == ThirdPersonView::kWidth);
  REQUIRE(with.rows == ThirdPersonView::kHeight);
  // The same pose's picture of the track alone: the robot is drawn over it,
  // and nothing else differs.
  cv::Mat track_only;
  video::SyntheticCamera(track, chase.camera()).Render(pose, track_only);
  const Blob blob = BodyIn(with, {0, 0, with.cols, with.rows});
  INFO("robot at " << blob.x << ", " << blob.y << " (" << blob.count << " px)");
  CHECK(BodyIn(track_only, {0, 0, with.cols, with.rows}).count == 0);
  REQUIRE(blob.count > 200);
  CHECK(std::abs(blob.x - with.cols / 2.0) < 0.05 * with.cols);  // straight ahead
  CHECK(blob.y > 0.6 * with.rows);  // below the horizon, near the bottom
  CHECK(blob.y < 0.95 * with.rows);
  // Where the projection puts it: the body's centre at mid-height.
  const video::LevelCamera lens = chase.Lens(robot);
  double d = 0, l = 0;
  lens.ToCamera(Vec2(robot.x, robot.y), d, l);
  CHECK(std::abs(lens.U(d, l) - blob.x) < 3.0);
  CHECK(std::abs(lens.V(d, chase.body_height_m() / 2) - blob.y) < 0.1 * with.rows);
  cv::Mat diff;
  cv::absdiff(with, track_only, diff);
  cv::Mat changed;
  cv::cvtColor(diff, changed, cv::COLOR_BGR2GRAY);
  const cv::Rect drawn = cv::boundingRect(changed > 0);
  CHECK(drawn.y > with.rows / 2);  // the sky and the track ahead are untouched
  CHECK(drawn.width < with.cols / 3);

  // Turned left a quarter turn, the chase camera turns with it: the robot stays in the middle.
  const PredictedPose turned{2.0, robot.x, robot.y, robot.heading + 1.5707963};
  chase.Render(turned, with);
  CHECK(std::abs(BodyIn(with, {0, 0, with.cols, with.rows}).x - with.cols / 2.0) <
        0.05 * with.cols);
}

TEST_CASE("the third-person pictures are reused, never one the view still holds") {
  const VehicleConfig vehicle = LoadVehicle("config/vehicles/sim-robot.yaml");
  const Track track(LoadTrack("config/tracks/test-short.yaml"));
  ThirdPersonView chase(track, vehicle);
  const PredictedPose robot{0.0, track.StartPosition().x(), track.StartPosition().y(),
                            track.StartHeading()};
  CHECK(chase.Latest().image == nullptr);  // nothing before the first pose

  // The view holds each picture it was given: four pictures, then none free.
  std::vector<video::Frame> held;
  for (int i = 0; i < 4; ++i) {
    REQUIRE(chase.Update(robot));
    held.push_back(chase.Latest());
    CHECK(held.back().id == static_cast<uint64_t>(i + 1));
  }
  CHECK_FALSE(chase.Update(robot));
  CHECK(chase.Latest().id == 4);  // the view keeps the one before
  // Let go of the first: the next picture is drawn into it, not a new one.
  const cv::Mat* first = held.front().image.get();
  held.erase(held.begin());
  REQUIRE(chase.Update(robot));
  CHECK(chase.Latest().image.get() == first);
  CHECK(chase.Latest().id == 5);
}

TEST_CASE("the view reads each third-person picture whole while the session draws the next ones",
          "[threads]") {
  const VehicleConfig vehicle = LoadVehicle("config/vehicles/sim-robot.yaml");
  const Track track(LoadTrack("config/tracks/test-short.yaml"));
  ThirdPersonView chase(track, vehicle);
  const PredictedPose robot{0.0, track.StartPosition().x(), track.StartPosition().y(),
                            track.StartHeading()};
  // Every picture is of the same pose: any picture read while it was being
  // redrawn (a buffer reused too soon) differs from this one.
  cv::Mat expected;
  chase.Render(robot, expected);
  // Read here, byte by byte, not by OpenCV (not built with ThreadSanitizer),
  // so that TSan sees the view's reads against the session's drawing.
  const auto bytes_sum = [](const cv::Mat& m) {
    uint64_t sum = 0;
    for (size_t i = 0; i < m.total() * m.elemSize(); ++i) sum += m.data[i];
    return sum;
  };
  const uint64_t expected_sum = bytes_sum(expected);

  // The view thread takes the latest picture and reads it whole, lets go
  // of it, then waits for the session to draw two more without taking the
  // view's lock meanwhile: only the picture's hand-back orders these reads
  // before the session draws into its buffer again.
  std::atomic<bool> done{false};
  std::atomic<int> drawn{0}, read{0}, torn{0};
  test::Thread view("view", [&] {
    while (!done.load()) {
      {
        const video::Frame image = chase.Latest();
        if (image.image != nullptr) {
          if (bytes_sum(*image.image) != expected_sum) ++torn;
          ++read;
        }
      }
      const int seen = drawn.load();
      while (!done.load() && drawn.load() < seen + 2) std::this_thread::yield();
    }
  });
  test::Deadline deadline(120.0);
  while ((drawn.load() < 200 || read.load() < 20) && !deadline.passed()) {
    if (chase.Update(robot)) ++drawn;
  }
  done = true;
  view.Join();
  CHECK(read.load() >= 20);
  CHECK(torn.load() == 0);
}

TEST_CASE(
    "the view draws the third-person picture as a labelled inset with the robot in its lower "
    "middle; "
    "without one, nothing") {
  constexpr int kWidth = 1024, kHeight = 576;  // the view's default size
  const VehicleConfig vehicle = LoadVehicle("config/vehicles/sim-robot.yaml");
  const Track track(LoadTrack("config/tracks/test-short.yaml"));
  const PredictedPose robot{1.0, track.StartPosition().x(), track.StartPosition().y(),
                            track.StartHeading()};
  // The robot's camera picture, filling the view as in a practice lap.
  view::ViewModel model;
  auto picture = std::make_shared<cv::Mat>();
  video::SyntheticCamera(track, vehicle.camera)
      .Render({.x = robot.x, .y = robot.y, .heading = robot.heading}, *picture);
  model.video.image = picture;
  model.video.id = 1;
  ThirdPersonView chase(track, vehicle);
  REQUIRE(chase.Update(robot));
  view::ViewModel practice = model;
  practice.third_person = chase.Latest();

  test::OffscreenGl gl(kWidth, kHeight);
  view::Renderer renderer(kWidth, kHeight, view::DirectViewScreen());
  cv::Mat on, off;
  renderer.Draw(practice, 0.0);
  renderer.ReadPixels(on);
  renderer.Draw(model, 0.0);
  renderer.ReadPixels(off);
  cv::imwrite((test::ScratchDir("third-person-view") / "view.png").string(), on);  // to look at

  const cv::Rect inset = RectOf(view::ThirdPersonRect(kWidth, kHeight));
  const cv::Rect label = RectOf(view::ThirdPersonLabelRect(kWidth, kHeight));
  REQUIRE(inset.width > 0.25 * kWidth);
  REQUIRE(inset.y + inset.height < kHeight - 50);  // above the message line
  // The robot in the inset's lower middle, where the chase picture has it.
  const Blob blob = BodyIn(on, inset);
  INFO("robot at " << blob.x << ", " << blob.y << " in the inset " << inset);
  REQUIRE(blob.count > 100);
  CHECK(std::abs(blob.x - (inset.x + inset.width / 2.0)) < 0.06 * inset.width);
  CHECK(blob.y > inset.y + 0.6 * inset.height);
  CHECK(blob.y < inset.y + 0.95 * inset.height);
  // Nowhere else: the robot's own camera does not see itself.
  CHECK(BodyIn(on, {0, 0, kWidth, kHeight}).count == blob.count);
  // Its label, white on black, above it.
  CHECK(WhiteIn(on, label) > 30);
  CHECK(WhiteIn(off, label) == 0);
  // Without a third-person picture nothing of it is drawn.
  CHECK(BodyIn(off, {0, 0, kWidth, kHeight}).count == 0);
  cv::Mat diff;
  cv::absdiff(on(inset), off(inset), diff);
  CHECK(cv::countNonZero(diff.reshape(1)) > inset.area() / 2);
  // Outside the inset and its label the frames are the same.
  const cv::Rect frame(label.x - 3, label.y, label.width + 6, label.height + inset.height + 3);
  cv::Mat outside_on = on.clone(), outside_off = off.clone();
  outside_on(frame).setTo(0);
  outside_off(frame).setTo(0);
  cv::absdiff(outside_on, outside_off, diff);
  CHECK(cv::countNonZero(diff.reshape(1)) == 0);
}

TEST_CASE("--third-person is for simulated robots only: others are refused with why") {
  CHECK(ThirdPersonProblem(LoadVehicle("config/vehicles/sim-robot.yaml")).empty());
  CHECK(ThirdPersonProblem(LoadVehicle("config/vehicles/can-robot-sim.yaml")).empty());
  const std::string real = ThirdPersonProblem(LoadVehicle("config/vehicles/can-robot.yaml"));
  CHECK(real.find("is not simulated") != std::string::npos);
  CHECK(real.find("can-robot.yaml") != std::string::npos);
  CHECK(real.find("expected a simulated robot (kind sim-robot or can-robot-sim)") !=
        std::string::npos);
  CHECK(
      ThirdPersonProblem(LoadVehicle("config/vehicles/ros2-robot.yaml")).find("is not simulated") !=
      std::string::npos);
  CHECK(ThirdPersonProblem(LoadVehicle("config/vehicles/sim-blimp.yaml")).find("flies a course") !=
        std::string::npos);
}
