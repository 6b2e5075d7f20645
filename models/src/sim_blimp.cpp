#include "haptel/models/sim_blimp.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "haptel/config/check.hpp"
#include "haptel/config/error.hpp"
#include "haptel/core/geometry2d.hpp"

namespace haptel::models {

namespace check = config_check;

namespace {

/// The hull's spheres: on its axis at these fractions of the half length,
/// each of the spheroid's local radius there (the end ones reach about
/// 2 % past the tips).
constexpr double kHullStations[] = {0.0, 0.33, -0.33, 0.62, -0.62, 0.85, -0.85};

/// m: the features this near an obstacle just before a contact began are
/// the ones whose closing speed the impact is (a step moves 5 cm at 10 m/s).
constexpr double kApproachGap = 0.5;

}  // namespace

void BlimpContactConfig::ValidateOrThrow() const {
  check::Number("stiffness", stiffness, 1.0, 1e7);
  check::Number("damping", damping, 0.0, 1e6);
  check::Number("friction", friction, 0.0, 5.0);
  check::Number("friction_damping", friction_damping, 0.0, 1e6);
  check::Number("gondola_below_cg", gondola_below_cg, 0.0, 50.0);
  check::Number("gondola_radius", gondola_radius, 0.0, 10.0);
  check::Number("release_distance", release_distance, 0.0, 1.0);
}

BlimpWorldContact::BlimpWorldContact(const AirshipConfig& airship, const BlimpCourseConfig& course,
                                     const BlimpContactConfig& config)
    : config_(Validated(config)) {
  const double a = airship.length / 2, b = airship.diameter / 2;
  for (double station : kHullStations) {
    ContactSphere s;
    s.centre_body = {station * a, 0.0, airship.cg_below_cb};
    s.radius = b * std::sqrt(1.0 - station * station);
    spheres_.push_back(s);
    lowest_below_cg_ = std::max(lowest_below_cg_, s.radius - airship.cg_below_cb);
  }
  ContactSphere gondola;
  gondola.centre_body = {0.0, 0.0, -config.gondola_below_cg + config.gondola_radius};
  gondola.radius = config.gondola_radius;
  spheres_.push_back(gondola);
  lowest_below_cg_ = std::max(lowest_below_cg_, config.gondola_below_cg);

  for (const BlimpBuildingSpec& building : course.buildings) {
    Box box;
    box.centre = {building.centre[0], building.centre[1]};
    box.cos_yaw = std::cos(Radians(building.yaw_deg));
    box.sin_yaw = std::sin(Radians(building.yaw_deg));
    box.half = {building.size[0] / 2, building.size[1] / 2, building.height / 2};
    box.reach = std::hypot(box.half.x(), box.half.y());
    boxes_.push_back(box);
  }
}

bool BlimpWorldContact::BoxTouch(const Box& box, const Eigen::Vector3d& centre, double radius,
                                 double max_gap, Eigen::Vector3d* normal, double* depth) const {
  const double dx = centre.x() - box.centre.x(), dy = centre.y() - box.centre.y();
  const double limit = box.reach + radius + max_gap;
  if (dx * dx + dy * dy > limit * limit) return false;
  // In the box's frame, from its centre (half its height up).
  const Eigen::Vector3d local(box.cos_yaw * dx + box.sin_yaw * dy,
                              -box.sin_yaw * dx + box.cos_yaw * dy, centre.z() - box.half.z());
  const Eigen::Vector3d closest = local.cwiseMax(-box.half).cwiseMin(box.half);
  const Eigen::Vector3d outside = local - closest;
  const double distance = outside.norm();
  Eigen::Vector3d n_local;
  if (distance > 1e-9) {
    if (distance - radius > max_gap) return false;
    n_local = outside / distance;
    *depth = radius - distance;
  } else {
    // The centre is inside (a deep hit): out through the nearest face, the
    // roof or a wall (never the floor: the ground is there).
    const double to_x = box.half.x() - std::abs(local.x());
    const double to_y = box.half.y() - std::abs(local.y());
    const double to_roof = box.half.z() - local.z();
    if (to_roof <= to_x && to_roof <= to_y) {
      n_local = Eigen::Vector3d::UnitZ();
      *depth = radius + to_roof;
    } else if (to_x <= to_y) {
      n_local = Eigen::Vector3d(local.x() >= 0 ? 1.0 : -1.0, 0.0, 0.0);
      *depth = radius + to_x;
    } else {
      n_local = Eigen::Vector3d(0.0, local.y() >= 0 ? 1.0 : -1.0, 0.0);
      *depth = radius + to_y;
    }
  }
  *normal = Eigen::Vector3d(box.cos_yaw * n_local.x() - box.sin_yaw * n_local.y(),
                            box.sin_yaw * n_local.x() + box.cos_yaw * n_local.y(), n_local.z());
  return true;
}

void BlimpWorldContact::Loads(const AirshipState& s, Eigen::Vector3d* force_body,
                              Eigen::Vector3d* moment_body) const {
  Eigen::Vector3d force = Eigen::Vector3d::Zero(), moment = Eigen::Vector3d::Zero();
  const BlimpContactConfig& k = config_;
  const Eigen::Matrix3d rotation = s.attitude.toRotationMatrix();
  const Eigen::Vector3d velocity_world = rotation * s.velocity;
  const Eigen::Vector3d rates_world = rotation * s.rates;
  ForEach(s, 0.0, [&](const Touch& t) {
    if (t.depth <= 0.0) return;
    // Normal: spring and damper, pushing only.
    const double normal_force = std::max(0.0, k.stiffness * t.depth + k.damping * t.closing_speed);
    if (normal_force <= 0.0) return;
    Eigen::Vector3d f = normal_force * t.normal;
    // Tangential: viscous below sliding, capped at Coulomb's μ·N.
    const Eigen::Vector3d r = t.point - s.position;
    const Eigen::Vector3d v = velocity_world + rates_world.cross(r);
    const Eigen::Vector3d slip = v - v.dot(t.normal) * t.normal;
    const double slip_speed = slip.norm();
    if (slip_speed > 1e-9) {
      f -= std::min(k.friction * normal_force, k.friction_damping * slip_speed) / slip_speed * slip;
    }
    force += f;
    moment += r.cross(f);
  });
  // To the body frame (the moment is about the centre of gravity).
  *force_body = rotation.transpose() * force;
  *moment_body = rotation.transpose() * moment;
}

SimBlimp::SimBlimp(const AirshipConfig& airship, const BlimpCourseConfig& course,
                   const BlimpContactConfig& contact)
    : contact_(std::make_unique<BlimpWorldContact>(Validated(airship), Validated(course), contact)),
      airship_(airship),
      touching_(static_cast<size_t>(contact_->obstacles()), 0),
      scratch_(touching_.size(), 0),
      closing_(touching_.size(), 0.0) {
  airship_.set_contact(contact_.get());
  RestOnGround(course.start.position[0], course.start.position[1],
               Radians(course.start.heading_deg));
}

void SimBlimp::RestOnGround(double x, double y, double heading) {
  const AirshipMassProperties& m = airship_.mass_properties();
  // Resting on the lowest feature, sunk in by the net weight (if any).
  const double sink = std::max(0.0, m.weight - m.buoyancy) / contact_->config().stiffness;
  AirshipState s;
  s.position = {x, y, contact_->lowest_below_cg() - sink};
  s.attitude = Eigen::Quaterniond(Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()));
  airship_.set_state(s);
  applied_ = BlimpCommand{};
  std::fill(touching_.begin(), touching_.end(), 0);
  touching_[0] = 1;  // resting: in contact, but no onset
}

void SimBlimp::Place(const AirshipState& state, const BlimpCommand& applied) {
  airship_.set_state(state);
  applied_ = Clamped(applied);
  std::fill(touching_.begin(), touching_.end(), 0);
  contact_->ForEach(state, 0.0, [&](const BlimpWorldContact::Touch& t) {
    if (t.depth > 0.0) touching_[static_cast<size_t>(t.obstacle)] = 1;
  });
}

bool SimBlimp::in_contact() const {
  return std::any_of(touching_.begin(), touching_.end(), [](char c) { return c != 0; });
}

void SimBlimp::Step(double dt, const BlimpCommand& command) {
  applied_ = Clamped(command);
  AirshipControls controls;
  controls.elevator = applied_.elevator;
  controls.rudder = applied_.rudder;
  controls.power = applied_.power;
  controls.helix = applied_.helix;
  controls.tail_rotor = applied_.tail_rotor;
  if (!(dt > 0.0)) return;
  const double step = airship_.config().step_s;
  const int steps = std::max(1, static_cast<int>(std::ceil(dt / step - 1e-9)));
  const double h = dt / steps;
  for (int i = 0; i < steps; ++i) {
    previous_ = airship_.state();
    airship_.Step(h, controls);
    TrackContacts();
  }
}

void SimBlimp::TrackContacts() {
  // Per obstacle: touching now (any feature in), or still near enough to
  // be the same contact (within the release distance).
  std::fill(scratch_.begin(), scratch_.end(), 0);
  std::fill(closing_.begin(), closing_.end(), 0.0);
  const double release = contact_->config().release_distance;
  contact_->ForEach(airship_.state(), release, [&](const BlimpWorldContact::Touch& t) {
    const auto j = static_cast<size_t>(t.obstacle);
    if (t.depth > 0.0) {
      scratch_[j] = 2;  // in
      closing_[j] = std::max(closing_[j], t.closing_speed);
    } else if (scratch_[j] == 0) {
      scratch_[j] = 1;  // near
    }
  });
  for (size_t j = 0; j < touching_.size(); ++j) {
    if (touching_[j] == 0 && scratch_[j] == 2) {
      touching_[j] = 1;
      ++contacts_;
      // The closing speed just before the contact (within the step that
      // began it the contact's own damper has already slowed it).
      double before = -1.0;
      contact_->ForEach(previous_, kApproachGap, [&](const BlimpWorldContact::Touch& t) {
        if (static_cast<size_t>(t.obstacle) == j) before = std::max(before, t.closing_speed);
      });
      last_impact_speed_ = std::max(0.0, before >= 0.0 ? before : closing_[j]);
      last_obstacle_ = static_cast<int>(j);
    } else if (touching_[j] != 0 && scratch_[j] == 0) {
      touching_[j] = 0;
    }
  }
}

}  // namespace haptel::models
