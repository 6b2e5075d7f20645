#include "haptel/vehicles/sim_robot.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "haptel/config/error.hpp"
#include "haptel/vehicles/range_sensors.hpp"

namespace haptel::vehicles {

namespace {
constexpr double kDegToRad = std::numbers::pi / 180.0;
/// A body this close to an obstacle is touching it (switch stays closed while
/// the robot rests against it).
constexpr double kTouchTolerance = 0.002;
}  // namespace

SimRobot::SimRobot(const Track& track, const VehicleConfig& config)
    : track_(track),
      drive_(Validated(config).drive),
      body_(config.body),
      range_sensors_(config.range_sensors),
      range_noise_(config.range_sensors.seed) {
  const Vec2 start = track.StartPosition();
  Place(start.x(), start.y(), track.StartHeading());
}

void SimRobot::Place(double x, double y, double heading) {
  state_ = AdapterState{};
  state_.pose_valid = true;
  state_.x = x;
  state_.y = y;
  state_.heading = heading;
  v_left_ = v_right_ = 0.0;
  levels_ = {};
  state_.ranges = ScanTrack(track_, x, y, heading, range_sensors_, range_noise_);
}

void SimRobot::SetMotors(const models::MotorLevels& levels) {
  levels_.left = std::clamp(levels.left, -drive_.speed_levels, drive_.speed_levels);
  levels_.right = std::clamp(levels.right, -drive_.speed_levels, drive_.speed_levels);
  state_.applied = levels_;
  use_treads_ = false;
}

void SimRobot::SetTreadTargets(double left, double right) {
  use_treads_ = true;
  tread_left_ = std::isfinite(left) ? left : 0.0;
  tread_right_ = std::isfinite(right) ? right : 0.0;
}

void SimRobot::Update(double dt) {
  if (!(dt > 0.0)) return;
  const double target_left = use_treads_ ? tread_left_ : models::LevelSpeed(drive_, levels_.left);
  const double target_right =
      use_treads_ ? tread_right_ : models::LevelSpeed(drive_, levels_.right);
  const Vec2 before(state_.x, state_.y);
  models::TreadState treads{state_.x, state_.y, state_.heading, v_left_, v_right_};
  const double omega = models::StepTreads(drive_, target_left, target_right, dt, treads);
  state_.x = treads.x;
  state_.y = treads.y;
  state_.heading = treads.heading;
  v_left_ = treads.v_left;
  v_right_ = treads.v_right;
  ResolveContacts();
  const Vec2 after(state_.x, state_.y);
  const Vec2 forward(std::cos(state_.heading), std::sin(state_.heading));
  state_.speed = (after - before).dot(forward) / dt;  // blocked robots report 0
  state_.yaw_rate = omega;
  state_.ranges =
      ScanTrack(track_, state_.x, state_.y, state_.heading, range_sensors_, range_noise_);
}

void SimRobot::Contact(const Vec2& point) {
  const double bearing =
      WrapAngle(std::atan2(point.y() - state_.y, point.x() - state_.x) - state_.heading);
  if (std::abs(bearing) > body_.bumper_half_angle_deg * kDegToRad) return;  // no rear bumper
  if (std::abs(bearing) <= body_.bumper_both_deg * kDegToRad) {
    state_.bumper_left = state_.bumper_right = true;
  } else if (bearing > 0) {
    state_.bumper_left = true;
  } else {
    state_.bumper_right = true;
  }
}

void SimRobot::ResolveContacts() {
  state_.bumper_left = state_.bumper_right = false;
  const double r = body_.radius;
  // A few passes settle corners where two walls push at once.
  for (int pass = 0; pass < 3; ++pass) {
    Vec2 p(state_.x, state_.y);
    for (const Segment2& wall : track_.walls()) {
      const Vec2 q = ClosestPointOnSegment(wall, p);
      const Vec2 d = p - q;
      const double dist = d.norm();
      if (dist < r + kTouchTolerance) {
        if (pass == 0) Contact(q);
        if (dist < r && dist > 1e-12) p = q + d * (r / dist);
      }
    }
    for (const CircleObstacle& c : track_.round_obstacles()) {
      const Vec2 d = p - c.center;
      const double dist = d.norm();
      const double reach = r + c.radius;
      if (dist < reach + kTouchTolerance) {
        if (pass == 0) Contact(c.center + d.normalized() * c.radius);
        if (dist < reach && dist > 1e-12) p = c.center + d * (reach / dist);
      }
    }
    state_.x = p.x();
    state_.y = p.y();
  }
}

}  // namespace haptel::vehicles
