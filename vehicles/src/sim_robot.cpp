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

/// The drive the reality's treads follow: its gains, lag and effective width.
TreadDriveConfig TrueDrive(const TreadDriveConfig& file, const DrawnReality& r) {
  TreadDriveConfig d = file;
  d.left_gain = r.left_gain;
  d.right_gain = r.right_gain;
  d.track_width = r.effective_track_width;
  d.motor_time_constant = r.motor_time_constant;
  return d;
}

RangeSensorConfig RealRangeSensors(RangeSensorConfig c, const DrawnReality& r) {
  c.noise_sd = r.range_noise_sd;
  return c;
}
}  // namespace

SimRobot::SimRobot(const Track& track, const VehicleConfig& config)
    : SimRobot(track, config, VehicleReality(Validated(config), &track)) {}

SimRobot::SimRobot(const Track& track, const VehicleConfig& config, const DrawnReality& reality)
    : track_(track),
      drive_(Validated(config).drive),
      true_drive_(TrueDrive(config.drive, reality)),
      reality_(reality),
      body_(config.body),
      range_sensors_(RealRangeSensors(config.range_sensors, reality)),
      range_noise_(reality.range_noise_seed),
      range_faults_{reality.range_spurious_fraction, reality.range_dropout_fraction},
      echoes_(reality.seed * 0xD1B54A32D192ED03ULL + 0x8CB92BA72F3D8DD7ULL),
      // Its own stream: the encoders' and gyro's noise never shift the ranges'.
      noise_(reality.seed * 0x9E3779B97F4A7C15ULL + 0x632BE59BD9B4E019ULL) {
  const Vec2 start = track.StartPosition();
  Place(start.x(), start.y(), track.StartHeading());
}

void SimRobot::Place(double x, double y, double heading) {
  state_ = AdapterState{};
  state_.pose_valid = true;
  state_.x = x;
  state_.y = y;
  state_.heading = heading;
  truth_ = models::TreadState{x, y, heading, 0.0, 0.0};
  odometry_ = truth_;
  true_speed_ = true_yaw_rate_ = measured_speed_ = measured_yaw_rate_ = 0.0;
  measured_next_ = measured_count_ = 0;
  v_left_ = v_right_ = 0.0;
  levels_ = {};
  pending_due_s_ = -1.0;
  state_.ranges = Scan();
}

RangeScan SimRobot::Scan() {
  return ScanTrack(TrueWalls(reality_, track_), TruePosts(reality_, track_), truth_.x, truth_.y,
                   truth_.heading, range_sensors_, range_noise_, range_faults_, echoes_);
}

void SimRobot::SetMotors(const models::MotorLevels& levels) {
  const models::MotorLevels clamped{
      std::clamp(levels.left, -drive_.speed_levels, drive_.speed_levels),
      std::clamp(levels.right, -drive_.speed_levels, drive_.speed_levels)};
  use_treads_ = false;
  if (!(reality_.command_jitter_s > 0.0)) {
    levels_ = clamped;
    state_.applied = levels_;
    return;
  }
  // The brick takes a new command at its own loop's next turn: after a
  // delay drawn per command (the same command again changes nothing).
  const models::MotorLevels& latest = pending_due_s_ >= 0.0 ? pending_ : levels_;
  if (clamped.left == latest.left && clamped.right == latest.right) return;
  pending_ = clamped;
  pending_due_s_ =
      time_s_ + std::uniform_real_distribution<double>(0.0, reality_.command_jitter_s)(noise_);
}

void SimRobot::SetTreadTargets(double left, double right) {
  use_treads_ = true;
  tread_left_ = std::isfinite(left) ? left : 0.0;
  tread_right_ = std::isfinite(right) ? right : 0.0;
}

double SimRobot::TractionAt(double x, double y) const {
  double traction = 1.0;
  for (const FloorPatch& p : reality_.floor_patches) {
    const double dx = x - p.x, dy = y - p.y;
    if (dx * dx + dy * dy <= p.radius * p.radius) traction = std::min(traction, p.traction);
  }
  return traction;
}

double SimRobot::StepBody(double target_left, double target_right, double dt) {
  models::TreadState treads{truth_.x, truth_.y, truth_.heading, v_left_, v_right_};
  const double traction = TractionAt(truth_.x, truth_.y);
  double omega = models::StepTreads(true_drive_, target_left, target_right, dt, treads);
  v_left_ = treads.v_left;
  v_right_ = treads.v_right;
  if (traction == 1.0 && reality_.lateral_slip_s == 0.0) {
    truth_.x = treads.x;
    truth_.y = treads.y;
    truth_.heading = treads.heading;
    return omega;
  }
  // The treads turn as ever; on a patch the body moves by only part of it,
  // and skidding it slides outward of the turn (Mandow et al. 2007: the
  // instantaneous centres of the treads lie outside them).
  const double v = traction * 0.5 * (v_left_ + v_right_);
  omega *= traction;
  const double mid = truth_.heading + 0.5 * omega * dt;
  models::MoveOnArc(v, omega, dt, truth_);
  const double sideways = -reality_.lateral_slip_s * v * omega;  // body y is to the left
  truth_.x -= sideways * dt * std::sin(mid);
  truth_.y += sideways * dt * std::cos(mid);
  return omega;
}

void SimRobot::StepOdometry(double yaw_rate, double dt) {
  // What the brick knows: its encoders (the treads' speeds, slip or not)
  // and its gyro (the body's true turn, with a bias).
  const double left = v_left_ * (1.0 + reality_.encoder_noise * Gaussian());
  const double right = v_right_ * (1.0 + reality_.encoder_noise * Gaussian());
  measured_speed_ = 0.5 * (left + right);
  measured_yaw_rate_ = yaw_rate + reality_.gyro_bias + reality_.gyro_noise * Gaussian();
  const double mid = odometry_.heading + 0.5 * measured_yaw_rate_ * dt;
  odometry_.x += measured_speed_ * dt * std::cos(mid);
  odometry_.y += measured_speed_ * dt * std::sin(mid);
  odometry_.heading = WrapAngle(odometry_.heading + measured_yaw_rate_ * dt);
}

void SimRobot::Update(double dt) {
  if (!(dt > 0.0)) return;
  // A late control tick's time in pieces the body's explicit steps and
  // contacts take (a tick is 5 ms; a starved thread's up to a second).
  const int pieces = static_cast<int>(std::ceil(dt / kMaxStep_s - 1e-9));
  for (int i = 0; i < pieces; ++i) Step(dt / pieces);
}

void SimRobot::Step(double dt) {
  time_s_ += dt;
  if (pending_due_s_ >= 0.0 && time_s_ >= pending_due_s_) {
    levels_ = pending_;
    pending_due_s_ = -1.0;
  }
  state_.applied = levels_;
  double target_left = use_treads_ ? tread_left_ : models::LevelSpeed(drive_, levels_.left);
  double target_right = use_treads_ ? tread_right_ : models::LevelSpeed(drive_, levels_.right);
  if (reality_.battery_fade_per_min > 0.0) {
    const double battery = std::max(0.5, 1.0 - reality_.battery_fade_per_min * time_s_ / 60.0);
    target_left *= battery;
    target_right *= battery;
  }
  const Vec2 before(truth_.x, truth_.y);
  const double omega = StepBody(target_left, target_right, dt);
  ResolveContacts();
  const Vec2 after(truth_.x, truth_.y);
  const Vec2 forward(std::cos(truth_.heading), std::sin(truth_.heading));
  true_speed_ = (after - before).dot(forward) / dt;  // blocked robots move 0
  true_yaw_rate_ = omega;
  // The range sensors see the world from where the robot truly is.
  state_.ranges = Scan();

  Measured now{time_s_, truth_.x, truth_.y, truth_.heading, true_speed_, true_yaw_rate_};
  if (reality_.odometry != 0.0) {
    StepOdometry(omega, dt);
    now = {time_s_,           odometry_.x,     odometry_.y,
           odometry_.heading, measured_speed_, measured_yaw_rate_};
  }
  measured_[measured_next_] = now;
  measured_next_ = (measured_next_ + 1) % measured_.size();
  measured_count_ = std::min(measured_count_ + 1, measured_.size());
  if (reality_.state_jitter_s > 0.0) {
    // The state carries a measurement up to state_jitter_s old.
    const double age = std::uniform_real_distribution<double>(0.0, reality_.state_jitter_s)(noise_);
    for (size_t k = 1; k <= measured_count_; ++k) {
      const Measured& m = measured_[(measured_next_ + measured_.size() - k) % measured_.size()];
      now = m;
      if (m.t_s <= time_s_ - age) break;
    }
  }
  state_.x = now.x;
  state_.y = now.y;
  state_.heading = now.heading;
  state_.speed = now.speed;
  state_.yaw_rate = now.yaw_rate;
  state_.measured_age_s = time_s_ - now.t_s;
}

bool SimRobot::Truth(TruthRow* row) const {
  row->x = truth_.x;
  row->y = truth_.y;
  row->z = 0.0;
  row->heading = truth_.heading;
  row->speed = true_speed_;
  row->yaw_rate = true_yaw_rate_;
  return true;
}

void SimRobot::Contact(const Vec2& point) {
  const double bearing =
      WrapAngle(std::atan2(point.y() - truth_.y, point.x() - truth_.x) - truth_.heading);
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
    Vec2 p(truth_.x, truth_.y);
    for (const Segment2& wall : TrueWalls(reality_, track_)) {
      const Vec2 q = ClosestPointOnSegment(wall, p);
      const Vec2 d = p - q;
      const double dist = d.norm();
      if (dist < r + kTouchTolerance) {
        if (pass == 0) Contact(q);
        if (dist < r && dist > 1e-12) p = q + d * (r / dist);
      }
    }
    for (const CircleObstacle& c : TruePosts(reality_, track_)) {
      const Vec2 d = p - c.center;
      const double dist = d.norm();
      const double reach = r + c.radius;
      if (dist < reach + kTouchTolerance) {
        if (pass == 0) Contact(c.center + d.normalized() * c.radius);
        if (dist < reach && dist > 1e-12) p = c.center + d * (reach / dist);
      }
    }
    truth_.x = p.x();
    truth_.y = p.y();
  }
}

}  // namespace haptel::vehicles
