// The robot camera's projection (camera_projection.hpp), which the synthetic
// camera draws with and the predictive display projects its ghost with.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <opencv2/core.hpp>
#include <vector>

#include "haptel/config/vehicle.hpp"
#include "haptel/video/camera_projection.hpp"

using haptel::CameraConfig;
using haptel::Vec2;
using haptel::video::LevelCamera;

namespace {

CameraConfig Webcam() {
  CameraConfig c;
  c.width = 640;
  c.height = 480;
  c.fov_deg = 55.0;
  c.mount_height = 0.12;
  return c;
}

}  // namespace

TEST_CASE("a floor point straight ahead lands on the centre column, f*h/d below the horizon") {
  const CameraConfig config = Webcam();
  const double f = 320.0 / std::tan(27.5 * std::numbers::pi / 180.0);
  // The camera at (1, 2) looking north: ahead is +y.
  const LevelCamera cam = LevelCamera::At(config, 1.0, 2.0, std::numbers::pi / 2);
  CHECK(cam.f == Approx(f));
  CHECK(cam.cx == 320.0);
  CHECK(cam.cy == 240.0);
  for (const double d : {0.3, 0.5, 1.0, 4.0}) {
    double depth = 0, lateral = 0;
    cam.ToCamera(Vec2(1.0, 2.0 + d), depth, lateral);
    CHECK(depth == Approx(d));
    CHECK(lateral == Approx(0.0).margin(1e-12));
    CHECK(cam.U(depth, lateral) == Approx(320.0));
    CHECK(cam.V(depth, 0.0) == Approx(240.0 + f * 0.12 / d));
    CHECK(cam.V(depth, 0.12) == Approx(240.0));  // at the camera's height: the horizon
  }
}

TEST_CASE("a point to the left lands left of the centre column, one to the right right of it") {
  const LevelCamera cam = LevelCamera::At(Webcam(), 0.0, 0.0, 0.0);  // looking east: left is +y
  double d = 0, l = 0;
  cam.ToCamera(Vec2(1.0, 0.2), d, l);
  CHECK(l == Approx(0.2));
  CHECK(cam.U(d, l) == Approx(320.0 - cam.f * 0.2));
  CHECK(cam.U(d, l) < 320.0);
  cam.ToCamera(Vec2(1.0, -0.2), d, l);
  CHECK(cam.U(d, l) > 320.0);
}

TEST_CASE("a point behind the camera is not drawn: clipping leaves nothing of it") {
  const LevelCamera cam = LevelCamera::At(Webcam(), 0.0, 0.0, 0.0);
  cv::Vec2d a, b;
  cam.ToCamera(Vec2(-1.0, 0.0), a[0], a[1]);
  cam.ToCamera(Vec2(-0.5, 0.1), b[0], b[1]);
  CHECK(a[0] < 0);
  CHECK_FALSE(cam.ClipSegment(a, b));
  // A segment from behind to ahead keeps only its part in front of the near plane.
  cam.ToCamera(Vec2(-1.0, 0.0), a[0], a[1]);
  cam.ToCamera(Vec2(1.0, 0.0), b[0], b[1]);
  REQUIRE(cam.ClipSegment(a, b));
  CHECK(a[0] == Approx(LevelCamera::kNear));
  CHECK(b[0] == Approx(1.0));
  // A polygon behind: nothing left; one straddling the camera: only its front.
  std::vector<cv::Vec2d> poly{{-1.0, -0.1}, {-0.8, -0.1}, {-0.8, 0.1}, {-1.0, 0.1}};
  std::vector<cv::Vec2d> scratch;
  cam.ClipPolygon(poly, scratch);
  CHECK(poly.empty());
  poly = {{-0.1, -0.1}, {0.1, -0.1}, {0.1, 0.1}, {-0.1, 0.1}};
  cam.ClipPolygon(poly, scratch);
  REQUIRE(poly.size() >= 3);
  for (const cv::Vec2d& p : poly) CHECK(p[0] >= LevelCamera::kNear - 1e-12);
  // Outside the horizontal field of view (far to the left, ahead): nothing.
  cam.ToCamera(Vec2(1.0, 2.0), a[0], a[1]);
  cam.ToCamera(Vec2(1.2, 2.0), b[0], b[1]);
  CHECK_FALSE(cam.ClipSegment(a, b));
}
