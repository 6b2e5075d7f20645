// The predictive display: the ghost and path ahead projected into the camera
// picture with the vehicle file's camera, the map's geometry, and — drawn by
// the real renderer offscreen over the synthetic camera's picture — the
// ghost's colour where the projection puts it, the predicted pose on the
// map, and nothing of either with prediction off.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "../view/offscreen_gl.hpp"
#include "haptel/config/blimp_course.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/mediator/predictive_display.hpp"
#include "haptel/mediator/robot_predictor.hpp"
#include "haptel/video/camera_projection.hpp"
#include "haptel/video/synthetic_camera.hpp"
#include "haptel/view/renderer.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::mediator;
using haptel::video::LevelCamera;

namespace {

VehicleConfig SimRobot() { return LoadVehicle("config/vehicles/sim-robot.yaml"); }

/// A path straight along the heading from `from`, `step` metres apart.
std::vector<PredictedPose> Straight(const PredictedPose& from, int poses, double step) {
  std::vector<PredictedPose> path;
  for (int i = 0; i < poses; ++i) {
    path.push_back({from.t_s + 0.05 * i, from.x + i * step * std::cos(from.heading),
                    from.y + i * step * std::sin(from.heading), from.heading});
  }
  return path;
}

/// The picture's pixel of a world point at height z, seen from `camera`.
cv::Point2d PicturePixel(const LevelCamera& camera, double x, double y, double z) {
  double d = 0, l = 0;
  camera.ToCamera(Vec2(x, y), d, l);
  return {camera.U(d, l), camera.V(d, z)};
}

/// The ghost's colour, and colours it leaves magenta-ish through its
/// see-through body: red and blue well above green. Nothing in the
/// synthetic world or the room is.
bool Magenta(cv::Vec3b c) { return c[2] > 170 && c[0] > 170 && c[1] < 110; }
bool Tinted(cv::Vec3b c) { return c[2] - c[1] > 80 && c[0] - c[1] > 60; }
bool White(cv::Vec3b c) { return c[0] > 200 && c[1] > 200 && c[2] > 200; }

/// Whether `test` holds at `p` or one of its 8 neighbours (a line a few
/// pixels wide, sampled from a scaled texture).
template <typename Test>
bool Near(const cv::Mat& bgr, cv::Point p, Test test) {
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      if (test(test::At(bgr, p + cv::Point(dx, dy)))) return true;
    }
  }
  return false;
}

int CountMagenta(const cv::Mat& bgr) {
  int n = 0;
  for (int r = 0; r < bgr.rows; ++r) {
    for (int c = 0; c < bgr.cols; ++c) n += Magenta(bgr.at<cv::Vec3b>(r, c)) ? 1 : 0;
  }
  return n;
}

}  // namespace

TEST_CASE(
    "the ghost straight ahead stands on the centre column, from the floor it stands on up to its "
    "top") {
  const VehicleConfig vehicle = SimRobot();
  const CameraConfig& cam = vehicle.camera;
  PredictiveDisplay display(cam, vehicle.body.radius);
  const PredictedPose camera{0.0, 1.0, 2.0, 0.3};
  const double ahead = 0.6;  // m: the whole ghost in the picture
  const PredictedPose now{0.0, 1.0 + ahead * std::cos(0.3), 2.0 + ahead * std::sin(0.3), 0.3};
  view::Prediction p;
  display.Make(camera, Straight(now, 21, 0.015), 0.2, p);
  REQUIRE(p.shown);
  REQUIRE(p.outline_count >= 3);
  const double f = (cam.width / 2.0) / std::tan(cam.fov_deg * std::numbers::pi / 360.0);
  const double r = vehicle.body.radius, h = cam.mount_height, top = display.ghost_height_m();
  // As tall as a ghost with no lead can be and stay below the picture, less a margin.
  CHECK(top == Approx(PredictiveDisplay::kHeightMargin * (h - cam.height / 2.0 / f * r)));
  CHECK(top < h);
  double u0 = 1e9, u1 = -1e9, v0 = 1e9, v1 = -1e9;
  for (int i = 0; i < p.outline_count; ++i) {
    const auto& q = p.outline[static_cast<size_t>(i)];
    u0 = std::min<double>(u0, q.u * cam.width);
    u1 = std::max<double>(u1, q.u * cam.width);
    v0 = std::min<double>(v0, q.v * cam.height);
    v1 = std::max<double>(v1, q.v * cam.height);
  }
  // Centred on the centre column; lowest at its nearest floor point, highest
  // at its top's farthest edge (the corners are 15° apart: within a pixel or two).
  CHECK((u0 + u1) / 2 == Approx(cam.width / 2.0).margin(0.5));
  CHECK(v1 == Approx(cam.height / 2.0 + f * h / (ahead - r)).margin(0.5));
  CHECK(v0 == Approx(cam.height / 2.0 + f * (h - top) / (ahead + r)).margin(1.0));
  // As wide as the body seen from the camera: its tangents are asin(r/d) either side.
  CHECK((u1 - u0) == Approx(2 * f * r / std::sqrt(ahead * ahead - r * r)).epsilon(0.02));
  // The path runs on along the centre column, each point f*h/d below the horizon.
  REQUIRE(p.path_count == 20);
  for (int i = 0; i < p.path_count; ++i) {
    const auto& s = p.path[static_cast<size_t>(i)];
    const double d = ahead + 0.015 * (i + 1);
    CHECK(s.b.u * cam.width == Approx(cam.width / 2.0).margin(1e-3));
    CHECK(s.b.v * cam.height == Approx(cam.height / 2.0 + f * h / d).epsilon(1e-5));
  }
  // The map: the camera as reported, the ghost now, the path from it.
  CHECK(p.reported.x == Approx(1.0));
  CHECK(p.reported.y == Approx(2.0));
  CHECK(p.predicted.x == Approx(now.x));
  CHECK(p.predicted.heading == Approx(0.3));
  CHECK(p.map_path_count == 21);
  CHECK(p.map_path[20].x == Approx(now.x + 0.3 * std::cos(0.3)));
  CHECK(p.one_way_delay_s == Approx(0.2));
}

TEST_CASE(
    "a ghost to the left is drawn left of the centre; one behind the camera, and its path, not at "
    "all") {
  const VehicleConfig vehicle = SimRobot();
  PredictiveDisplay display(vehicle.camera, vehicle.body.radius);
  const PredictedPose camera{0.0, 0.0, 0.0, 0.0};  // looking east: left is +y
  view::Prediction p;
  display.Make(camera, Straight({0.0, 0.8, 0.25, 0.0}, 5, 0.02), 0.1, p);
  REQUIRE(p.outline_count >= 3);
  for (int i = 0; i < p.outline_count; ++i) CHECK(p.outline[static_cast<size_t>(i)].u < 0.5);
  for (int i = 0; i < p.path_count; ++i) CHECK(p.path[static_cast<size_t>(i)].a.u < 0.5);

  display.Make(camera, Straight({0.0, -0.8, 0.0, std::numbers::pi}, 21, 0.02), 0.1,
               p);  // behind, driving away
  CHECK(p.shown);   // on the map it is still shown
  CHECK(p.outline_count == 0);
  CHECK(p.path_count == 0);
  CHECK(p.map_path_count == 21);
}

TEST_CASE(
    "a ghost where the camera is (no lead) stays below the picture, as the robot's own body does") {
  for (const char* file : {"config/vehicles/sim-robot.yaml", "config/vehicles/ros2-robot.yaml"}) {
    const VehicleConfig vehicle = LoadVehicle(file);
    PredictiveDisplay display(vehicle.camera, vehicle.body.radius);
    const PredictedPose camera{0.0, 0.3, -0.2, 1.0};
    view::Prediction p;
    display.Make(camera, {camera}, 0.0, p);
    INFO(file);
    for (int i = 0; i < p.outline_count; ++i) CHECK(p.outline[static_cast<size_t>(i)].v > 1.0f);
    // 3 cm ahead of its picture (0.1 s at full speed): it shows at the bottom.
    display.Make(
        camera,
        Straight({0.0, 0.3 + 0.03 * std::cos(1.0), -0.2 + 0.03 * std::sin(1.0), 1.0}, 1, 0.0), 0.0,
        p);
    REQUIRE(p.outline_count >= 3);
    float highest = 2.0f;
    for (int i = 0; i < p.outline_count; ++i)
      highest = std::min(highest, p.outline[static_cast<size_t>(i)].v);
    CHECK(highest < 0.99f);
    CHECK(highest > 0.5f);  // below the horizon: it is lower than the camera
  }
}

TEST_CASE(
    "the map of a track: its walls, the start line across the corridor, each gate post to post") {
  const Track track(LoadTrack("config/tracks/test-short.yaml"));
  const view::TrackMap map = TrackMapOf(track);
  CHECK(map.walls.size() == track.walls().size());
  REQUIRE(map.gates.size() == 2);
  CHECK(map.gates[0].ax == Approx(track.gates()[0].left_post.x()));
  CHECK(map.gates[0].by == Approx(track.gates()[0].right_post.y()));
  CHECK(std::hypot(map.start.bx - map.start.ax, map.start.by - map.start.ay) ==
        Approx(track.config().corridor_width));
  int left = 0, right = 0;
  for (const auto& post : map.posts) {
    left += post.kind == view::TrackMap::PostKind::kLeft ? 1 : 0;
    right += post.kind == view::TrackMap::PostKind::kRight ? 1 : 0;
  }
  CHECK(left == 2);
  CHECK(right == 2);
}

TEST_CASE(
    "drawn over the camera's picture: the ghost's colour where the projection puts it, the "
    "predicted pose "
    "on the map; with prediction off neither") {
  constexpr int kWidth = 1024, kHeight = 576;  // the view's default size
  const VehicleConfig vehicle = SimRobot();
  const auto track = std::make_shared<const Track>(LoadTrack("config/tracks/test-short.yaml"));
  // The predictor: 0.4 s each way, full ahead all along; the newest state was
  // sampled 0.4 s ago at the start, going at full speed.
  RobotPredictor predictor(vehicle.drive, vehicle.watchdog_timeout_s);
  for (int i = 0; i < 15; ++i) predictor.OnRoundTrip(0.8);
  for (int i = 0; i <= 100; ++i) predictor.OnCommand(0.01 * i, 1.0, 1.0);
  const double speed =
      (vehicle.drive.left_gain + vehicle.drive.right_gain) / 2 * vehicle.drive.max_speed;
  const double yaw = (vehicle.drive.right_gain - vehicle.drive.left_gain) *
                     vehicle.drive.max_speed / vehicle.drive.track_width;
  const PredictedPose reported{1.0, track->StartPosition().x(), track->StartPosition().y(),
                               track->StartHeading()};
  RobotStateSample state{1.0, reported.x, reported.y, reported.heading, speed, yaw, 8, 8};
  predictor.OnState(state);
  REQUIRE(predictor.ready());
  std::vector<PredictedPose> path;
  predictor.PathAhead(1.0, 1.0, 1.0, 1.0, path, 0.05);
  const PredictedPose now = path.front();
  REQUIRE(std::hypot(now.x - reported.x, now.y - reported.y) == Approx(0.4 * speed).epsilon(0.1));

  PredictiveDisplay display(vehicle.camera, vehicle.body.radius);
  view::ViewModel model;
  display.Make(reported, path, predictor.one_way_delay_s(), model.prediction);
  model.map = std::make_shared<const view::TrackMap>(TrackMapOf(*track));
  // The picture the camera took from the reported pose.
  const video::SyntheticCamera camera(*track, vehicle.camera);
  auto picture = std::make_shared<cv::Mat>();
  camera.Render({.x = reported.x, .y = reported.y, .heading = reported.heading}, *picture);
  model.video.image = picture;
  model.video.id = 1;

  test::OffscreenGl gl(kWidth, kHeight);
  view::Renderer renderer(kWidth, kHeight);
  cv::Mat on, off, none;
  renderer.Draw(model, 0.0);
  renderer.ReadPixels(on);
  // On the predicted pose's disc, beside its heading tick.
  const double beside_x = now.x - 0.5 * vehicle.body.radius * std::sin(now.heading);
  const double beside_y = now.y + 0.5 * vehicle.body.radius * std::cos(now.heading);
  double map_x = 0, map_y = 0;
  REQUIRE(renderer.MapPoint(beside_x, beside_y, map_x, map_y));
  double reported_x = 0, reported_y = 0;
  REQUIRE(renderer.MapPoint(reported.x - vehicle.body.radius * std::cos(reported.heading),
                            reported.y - vehicle.body.radius * std::sin(reported.heading),
                            reported_x, reported_y));
  view::ViewModel plain = model;
  plain.prediction.shown = false;  // prediction off: what the session publishes then
  renderer.Draw(plain, 0.0);
  renderer.ReadPixels(off);
  double unused_x = 0, unused_y = 0;
  CHECK_FALSE(renderer.MapPoint(beside_x, beside_y, unused_x, unused_y));  // no map drawn
  plain.map = nullptr;
  plain.prediction = {};
  renderer.Draw(plain, 0.0);
  renderer.ReadPixels(none);

  // Where the projection puts the ghost: a point inside its body near its
  // top front edge, and a point of the path ahead past it.
  const LevelCamera lens =
      LevelCamera::At(vehicle.camera, reported.x, reported.y, reported.heading);
  const double r = vehicle.body.radius;
  const cv::Point2d body =
      PicturePixel(lens, now.x + 0.8 * r * std::cos(now.heading),
                   now.y + 0.8 * r * std::sin(now.heading), 0.8 * display.ghost_height_m());
  const PredictedPose& far = path.back();  // 0.3 m further: past the ghost, on the floor it hides
  const cv::Point2d floor = PicturePixel(lens, far.x, far.y, 0.0);
  const double w = vehicle.camera.width, h = vehicle.camera.height;
  INFO("ghost body at picture pixel " << body << ", path end at " << floor);
  REQUIRE(body.y < 0.97 * h);  // in the picture
  REQUIRE(floor.y < 0.97 * h);
  const cv::Point body_px = test::ScreenPoint(renderer, body.x / w, body.y / h);
  const cv::Point floor_px = test::ScreenPoint(renderer, floor.x / w, floor.y / h);
  CHECK(Tinted(test::At(on, body_px)));
  CHECK_FALSE(Tinted(test::At(off, body_px)));
  CHECK(Near(on, floor_px, Magenta));
  CHECK_FALSE(Near(off, floor_px, Magenta));
  // Above the horizon the picture is as it was: nothing drawn there.
  const cv::Point sky = test::ScreenPoint(renderer, 0.5, 0.25);
  CHECK(test::At(on, sky) == test::At(off, sky));
  // The map: the predicted pose a magenta disc, the reported one a white ring behind it.
  const cv::Point map_now(static_cast<int>(map_x), static_cast<int>(map_y));
  CHECK(Magenta(test::At(on, map_now)));
  CHECK_FALSE(Magenta(test::At(off, map_now)));
  CHECK(Near(on, cv::Point(static_cast<int>(reported_x), static_cast<int>(reported_y)), White));
  // Prediction off draws nothing extra: not a pixel differs from a view
  // that never heard of prediction, and nothing anywhere is magenta.
  cv::Mat diff;
  cv::absdiff(off, none, diff);
  CHECK(cv::countNonZero(diff.reshape(1)) == 0);
  CHECK(CountMagenta(off) == 0);
  CHECK(CountMagenta(on) > 100);
  cv::imwrite((test::ScratchDir("predictive-display") / "view.png").string(), on);  // to look at
}

TEST_CASE(
    "the blimp's course map: gates across their openings labelled with their heights, buildings, "
    "the landing") {
  const BlimpCourseConfig course = LoadBlimpCourse("config/tracks/blimp-course.yaml");
  const view::TrackMap map = CourseMapOf(course);
  REQUIRE(map.gates.size() == course.gates.size());
  REQUIRE(map.labels.size() == course.gates.size());
  CHECK(map.walls.size() == 4 * course.buildings.size());
  for (size_t i = 0; i < course.gates.size(); ++i) {
    const BlimpGateSpec& g = course.gates[i];
    const view::TrackMap::Line& l = map.gates[i];
    // From post to post: the opening's width, centred on the gate, across its heading.
    CHECK(std::hypot(l.bx - l.ax, l.by - l.ay) == Approx(g.width));
    CHECK((l.ax + l.bx) / 2 == Approx(g.centre[0]).margin(1e-9));
    CHECK((l.ay + l.by) / 2 == Approx(g.centre[1]).margin(1e-9));
    const double along = (l.bx - l.ax) * std::cos(g.heading_deg * std::numbers::pi / 180) +
                         (l.by - l.ay) * std::sin(g.heading_deg * std::numbers::pi / 180);
    CHECK(along == Approx(0.0).margin(1e-9));
    char heights[48];
    std::snprintf(heights, sizeof heights, "%.1f-%.1f m", g.centre[2] - g.height / 2,
                  g.centre[2] + g.height / 2);
    CHECK(map.labels[i].text == heights);
  }
  const auto landing = std::find_if(
      map.posts.begin(), map.posts.end(),
      [](const view::TrackMap::Post& p) { return p.kind == view::TrackMap::PostKind::kLanding; });
  REQUIRE(landing != map.posts.end());
  CHECK(landing->radius == course.landing.radius);
}

TEST_CASE(
    "the blimp's prediction is drawn on the course map with its heights, and not in the picture") {
  constexpr int kWidth = 1024, kHeight = 576;
  const BlimpCourseConfig course = LoadBlimpCourse("config/tracks/blimp-course.yaml");
  const auto map = std::make_shared<const view::TrackMap>(CourseMapOf(course));
  // Reported at the first gate's height, the ghost 2 m ahead and 0.5 m higher, climbing on.
  BlimpPredictedPose reported;
  reported.position = Eigen::Vector3d(course.start.position[0], course.start.position[1], 1.2);
  reported.yaw = course.start.heading_deg * std::numbers::pi / 180;
  std::vector<BlimpPredictedPose> path;
  for (int i = 0; i < 21; ++i) {
    BlimpPredictedPose p = reported;
    p.t_s = 0.05 * i;
    p.position +=
        Eigen::Vector3d(std::cos(reported.yaw), std::sin(reported.yaw), 0.0) * (2.0 + 0.1 * i);
    p.position.z() = 1.7 + 0.02 * i;
    path.push_back(p);
  }
  view::ViewModel model;
  MakeBlimpPrediction(reported, path, 6.75, 0.4, model.prediction);
  CHECK(model.prediction.shown);
  CHECK(model.prediction.heights);
  CHECK(model.prediction.outline_count == 0);  // nothing in the picture
  CHECK(model.prediction.path_count == 0);
  CHECK(model.prediction.map_path_count == 21);
  CHECK(model.prediction.reported.z == Approx(1.2));
  CHECK(model.prediction.predicted.z == Approx(1.7));
  CHECK(model.prediction.map_path[20].z == Approx(2.1));
  CHECK(model.prediction.body_radius == Approx(6.75 / 2));
  model.map = map;

  test::OffscreenGl gl(kWidth, kHeight);
  view::Renderer renderer(kWidth, kHeight);
  cv::Mat on, higher, off;
  renderer.Draw(model, 0.0);
  renderer.ReadPixels(on);
  const BlimpPredictedPose& now = path.front();
  // The ghost: a magenta disc around where the map puts the blimp now
  // (a large course on a small map: the hull is a few pixels across).
  double map_x = 0, map_y = 0;
  REQUIRE(renderer.MapPoint(now.position.x(), now.position.y(), map_x, map_y));
  const cv::Rect around(static_cast<int>(map_x) - 8, static_cast<int>(map_y) - 8, 17, 17);
  INFO("the ghost around " << map_x << ", " << map_y);
  CHECK(CountMagenta(on(around)) >= 10);
  // The heights line says the heights: another height, another line; the
  // map above it unchanged.
  view::ViewModel climbing = model;
  climbing.prediction.predicted.z = 3.4f;
  renderer.Draw(climbing, 0.0);
  renderer.ReadPixels(higher);
  cv::Mat diff;
  cv::absdiff(on, higher, diff);
  cv::Mat changed;
  cv::cvtColor(diff, changed, cv::COLOR_BGR2GRAY);
  const cv::Rect where = cv::boundingRect(changed > 0);
  INFO("changed " << where);
  CHECK(where.area() > 0);
  CHECK(where.y > map_y);  // below the map: the heights line
  // Without a prediction nothing of it is drawn.
  view::ViewModel plain = model;
  plain.prediction.shown = false;
  renderer.Draw(plain, 0.0);
  renderer.ReadPixels(off);
  CHECK(CountMagenta(off) == 0);
  CHECK(CountMagenta(on) > 100);
  CHECK(CountMagenta(off(around)) == 0);
  cv::imwrite((test::ScratchDir("predictive-display") / "blimp-map.png").string(),
              on);  // to look at
}
