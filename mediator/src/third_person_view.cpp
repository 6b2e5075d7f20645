#include "haptel/mediator/third_person_view.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "haptel/config/vehicle_kinds.hpp"

namespace haptel::mediator {

namespace {

// The robot as the chase camera shows it (BGR): a dark blue body, a lighter
// top, a white nose; none of the track's colours (walls, red and green
// posts, orange obstacles, the white start line is on the floor).
const cv::Scalar kBody(120, 62, 28);
const cv::Scalar kTop(205, 150, 90);
const cv::Scalar kEdge(235, 235, 235);
constexpr int kShift = 4;  // sub-pixel bits for the drawing
constexpr double kOne = 1 << kShift;

cv::Point Fixed(double u, double v) {
  const auto fix = [](double c) {
    return static_cast<int>(std::lround(std::clamp(c - 0.5, -1e5, 1e5) * kOne));
  };
  return {fix(u), fix(v)};
}

/// The chase camera: the vehicle's camera's codec and rate are of no
/// matter here; its size, field of view and height are the chase view's.
CameraConfig ChaseCamera(const VehicleConfig& vehicle) {
  CameraConfig c = vehicle.camera;
  c.source = CameraSourceKind::kSynthetic;
  c.width = ThirdPersonView::kWidth;
  c.height = ThirdPersonView::kHeight;
  c.fov_deg = ThirdPersonView::kFovDeg;
  c.mount_height = ThirdPersonView::kHeightDiameters * 2.0 * vehicle.body.radius;
  return c;
}

}  // namespace

ThirdPersonView::ThirdPersonView(const Track& track, const VehicleConfig& vehicle)
    : chase_(ChaseCamera(vehicle)),
      radius_m_(vehicle.body.radius),
      // The body reaches up to the camera it carries.
      body_height_m_(std::max(vehicle.camera.mount_height, 0.5 * vehicle.body.radius)),
      renderer_(track, chase_) {
  pixels_.reserve(2 * BodySilhouette::kSides);
  for (auto& buffer : buffers_) {
    buffer = std::make_shared<Picture>();
    buffer->image.create(kHeight, kWidth, CV_8UC3);
  }
}

video::CameraPose ThirdPersonView::ChasePose(const PredictedPose& robot) const {
  const double back = kBackLengths * 2.0 * radius_m_;
  return {.x = robot.x - back * std::cos(robot.heading),
          .y = robot.y - back * std::sin(robot.heading),
          .heading = robot.heading,
          .z = chase_.mount_height};
}

video::LevelCamera ThirdPersonView::Lens(const PredictedPose& robot) const {
  const video::CameraPose pose = ChasePose(robot);
  return video::LevelCamera::At(chase_, pose.x, pose.y, pose.heading);
}

void ThirdPersonView::Render(const PredictedPose& robot, cv::Mat& image) {
  renderer_.Render(ChasePose(robot), image);
  if (!std::isfinite(robot.x) || !std::isfinite(robot.y) || !std::isfinite(robot.heading)) return;
  const video::LevelCamera lens = Lens(robot);
  const double w = chase_.width, h = chase_.height;
  // The body: its silhouette, then its top face (the clipped footprint at
  // its height) and its nose, so the heading shows when it turns.
  const int n = silhouette_.Make(lens, w, h, robot.x, robot.y, radius_m_, body_height_m_, outline_);
  if (n < 3) return;
  pixels_.clear();
  for (int i = 0; i < n; ++i) {
    const view::PicturePoint& p = outline_[static_cast<size_t>(i)];
    pixels_.push_back(Fixed(p.u * w, p.v * h));
  }
  cv::fillConvexPoly(image, pixels_.data(), n, kBody, cv::LINE_AA, kShift);
  const cv::Point* outline = pixels_.data();
  cv::polylines(image, &outline, &n, 1, true, kEdge, 1, cv::LINE_AA, kShift);
  pixels_.clear();
  for (const cv::Vec2d& p : silhouette_.footprint()) {
    pixels_.push_back(Fixed(lens.U(p[0], p[1]), lens.V(p[0], body_height_m_)));
  }
  if (pixels_.size() >= 3) {
    cv::fillConvexPoly(image, pixels_.data(), static_cast<int>(pixels_.size()), kTop, cv::LINE_AA,
                       kShift);
  }
  // The nose: a dot on the top face's front edge.
  double d = 0, l = 0;
  lens.ToCamera(Vec2(robot.x + 0.8 * radius_m_ * std::cos(robot.heading),
                     robot.y + 0.8 * radius_m_ * std::sin(robot.heading)),
                d, l);
  if (d > video::LevelCamera::kNear) {
    const int dot = static_cast<int>(std::max(2.0, 0.15 * radius_m_ * lens.f / d) * kOne);
    cv::circle(image, Fixed(lens.U(d, l), lens.V(d, body_height_m_)), dot, kEdge, cv::FILLED,
               cv::LINE_AA, kShift);
  }
}

bool ThirdPersonView::Update(const PredictedPose& robot) {
  for (const std::shared_ptr<Picture>& picture : buffers_) {
    // Acquire: pairs with the release in the handle's deleter, so whoever
    // read this picture last (the view) has finished before it is redrawn.
    // The latest is never free (latest_ holds a handle to it).
    if (!picture->free.load(std::memory_order_acquire)) continue;
    picture->free.store(false, std::memory_order_relaxed);
    Render(robot, picture->image);
    // The handle keeps its Picture alive, should the view outlive this.
    std::shared_ptr<const cv::Mat> handle(&picture->image, [picture](const cv::Mat*) {
      picture->free.store(true, std::memory_order_release);
    });
    std::lock_guard<std::mutex> lock(mutex_);
    latest_ = std::move(handle);
    ++id_;
    return true;
  }
  return false;
}

video::Frame ThirdPersonView::Latest() const {
  video::Frame image;
  std::lock_guard<std::mutex> lock(mutex_);
  image.image = latest_;
  image.id = id_;
  return image;
}

std::string ThirdPersonProblem(const VehicleConfig& vehicle) {
  const VehicleKindInfo* kind = FindVehicleKind(vehicle.kind);
  if (vehicle.family() == VehicleFamily::kRobot && kind != nullptr && kind->simulated) return "";
  std::string expected;
  for (const VehicleKindInfo& k : VehicleKinds()) {
    if (k.family == VehicleFamily::kRobot && k.simulated)
      expected += (expected.empty() ? "" : " or ") + k.name;
  }
  const std::string which =
      "vehicle '" + vehicle.name + "' (" + vehicle.file.string() + ", kind " + vehicle.kind + ")";
  const std::string why = vehicle.family() != VehicleFamily::kRobot
                              ? " flies a course, not a track"
                              : " is not simulated, so what is around it is not known here";
  return which + why + "; expected a simulated robot (kind " + expected + ")";
}

}  // namespace haptel::mediator
