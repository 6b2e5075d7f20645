#include "haptel/mediator/world_shapes.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace haptel::mediator {
namespace {

const view::Rgba kSkin{0.93f, 0.76f, 0.64f, 1.0f};
const view::Rgba kSkinLeft{0.86f, 0.70f, 0.60f, 1.0f};
const view::Rgba kPressed{1.0f, 0.55f, 0.1f, 1.0f};
const view::Rgba kRim{0.15f, 0.15f, 0.17f, 1.0f};
const view::Rgba kHeld{0.2f, 0.55f, 0.95f, 1.0f};
const view::Rgba kShaking{0.85f, 0.12f, 0.1f, 1.0f};
const view::Rgba kMetal{0.6f, 0.62f, 0.65f, 1.0f};
const view::Rgba kGhostHeld{0.25f, 0.55f, 1.0f, 0.4f};
const view::Rgba kGhostFree{0.6f, 0.6f, 0.65f, 0.3f};
const view::Rgba kBend{0.25f, 0.55f, 1.0f, 0.7f};
const view::Rgba kForce{1.0f, 0.45f, 0.05f, 1.0f};

/// A capsule from `a` to `b` (its axis is its local x).
view::Shape Segment(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius,
                    const view::Rgba& color);

Eigen::Quaterniond Q(const std::array<double, 4>& q) {
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized();
}
std::array<double, 4> A(const Eigen::Quaterniond& q) { return {q.w(), q.x(), q.y(), q.z()}; }
std::array<double, 3> A(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
Eigen::Vector3d V(const std::array<double, 3>& v) { return {v[0], v[1], v[2]}; }

view::Shape Make(view::ShapeKind kind, const Eigen::Vector3d& p, const Eigen::Quaterniond& q,
                 const std::array<double, 3>& size, const view::Rgba& color) {
  view::Shape s;
  s.kind = kind;
  s.position = A(p);
  s.orientation = A(q);
  s.size = size;
  s.color = color;
  return s;
}

/// The palm box of a hand whose wrist is at (p, q).
view::Shape Palm(const Eigen::Vector3d& wrist, const Eigen::Quaterniond& q,
                 const ProxyHandConfig& hand, const view::Rgba& color) {
  const auto& he = hand.palm_half_extents;
  return Make(view::ShapeKind::kBox, wrist + q * Eigen::Vector3d(he[0], 0, 0), q, he, color);
}

}  // namespace

void AppendProxyHand(std::vector<view::Shape>& shapes, const physics::HandPoses& poses,
                     const ProxyHandConfig& hand, haptics::Side side) {
  const view::Rgba& skin = side == haptics::Side::kLeft ? kSkinLeft : kSkin;
  shapes.push_back(
      Palm(V(poses.proxy_wrist.position), Q(poses.proxy_wrist.orientation), hand, skin));
  const double r = hand.phalanx_radius;
  for (int f = 0; f < physics::kFingers; ++f) {
    const bool pressed = poses.finger_forces[static_cast<size_t>(f)] > 0.5;
    for (int p = 0; p < physics::kPhalanges; ++p) {
      const physics::Pose& pose = poses.phalanges[static_cast<size_t>(f)][static_cast<size_t>(p)];
      // btCapsuleShapeX(r, length − 2r): the cylinder part's half length.
      const double half =
          std::max(hand.phalanx_length[static_cast<size_t>(p)] - 2.0 * r, 1e-4) / 2.0;
      shapes.push_back(Make(view::ShapeKind::kCapsule, V(pose.position), Q(pose.orientation),
                            {r, half, 0},
                            pressed && p == physics::kPhalanges - 1 ? kPressed : skin));
    }
  }
}

void AppendTrackedHand(std::vector<view::Shape>& shapes, const haptics::HandSample& sample,
                       const ProxyHandConfig& hand) {
  shapes.push_back(Palm(V(sample.position), Q(sample.orientation), hand, kSkin));
}

void AppendCockpit(std::vector<view::Shape>& shapes, const CockpitConfig& cockpit,
                   const physics::ControlsBodyConfig& bodies,
                   const interfaces::CockpitControls& controls, bool contact) {
  const Eigen::Vector3d hub = V(cockpit.wheel_hub);
  // Positive angle turns the top of the rim to the left (+y): a rotation
  // about the axis pointing at the driver (−x).
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(controls.wheel_angle, -Eigen::Vector3d::UnitX()));
  const view::Rgba& rim = contact ? kShaking : (controls.wheel_held ? kHeld : kRim);
  const int n = std::max(bodies.rim_segments, 6);
  const double r = cockpit.wheel_radius;
  const double half_angle = M_PI / n;
  const double chord = 2.0 * r * std::sin(half_angle);
  for (int i = 0; i < n; ++i) {
    // As CockpitControlsBody builds the rim: capsules along the chords, in the
    // wheel's y–z plane; a capsule's axis is its local x.
    const double a = (2 * i + 1) * half_angle;
    const Eigen::Quaterniond at(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()));
    const Eigen::Vector3d centre = turn * (at * Eigen::Vector3d(0, 0, r * std::cos(half_angle)));
    const Eigen::Quaterniond along =
        turn * at *
        Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY());
    shapes.push_back(Make(view::ShapeKind::kCapsule, hub + centre, along,
                          {bodies.rim_radius, chord / 2, 0}, rim));
  }
  for (int k = 0; k < 3; ++k) {  // spokes at 90°, 210°, 330°, so one points down when straight
    const double a = M_PI / 2 + k * 2 * M_PI / 3;
    const Eigen::Vector3d dir = turn * Eigen::Vector3d(0, std::cos(a), -std::sin(a));
    const Eigen::Quaterniond along =
        Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitX(), dir);
    shapes.push_back(
        Make(view::ShapeKind::kCylinder, hub + dir * (r / 2), along, {0.006, r / 2, 0}, kMetal));
  }
  shapes.push_back(Make(view::ShapeKind::kCylinder, hub + Eigen::Vector3d(0.06, 0, 0),
                        Eigen::Quaterniond::Identity(), {0.012, 0.06, 0},
                        kMetal));  // the column, forward of the hub

  const Eigen::Vector3d centre = V(cockpit.throttle_centre);
  const auto& he = bodies.knob_half_extents;
  shapes.push_back(Make(view::ShapeKind::kBox, centre - Eigen::Vector3d(0, 0, he[2] + 0.006),
                        Eigen::Quaterniond::Identity(),
                        {cockpit.throttle_travel + he[0], he[1] * 0.6, 0.005},
                        kMetal));  // the rail
  shapes.push_back(Make(view::ShapeKind::kBox, centre + Eigen::Vector3d(controls.throttle, 0, 0),
                        Eigen::Quaterniond::Identity(), he, controls.throttle_held ? kHeld : kRim));
}

void AppendWall(std::vector<view::Shape>& shapes, const haptics::ForceField& field) {
  Eigen::Vector3d n = V(field.wall_normal);
  if (n.norm() < 1e-9) return;
  n.normalize();
  const Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitX(), n);
  // Just beyond the plane, so a hand pressing into it stays in front.
  shapes.push_back(Make(view::ShapeKind::kBox, V(field.wall_point) + n * 0.003, q,
                        {0.003, 0.15, 0.15}, {0.9f, 0.15f, 0.1f, 0.55f}));
}

namespace {
view::Shape Segment(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius,
                    const view::Rgba& color) {
  const Eigen::Vector3d d = b - a;
  const Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitX(), d);
  return Make(view::ShapeKind::kCapsule, 0.5 * (a + b), q, {radius, 0.5 * d.norm(), 0}, color);
}
}  // namespace

void AppendPseudoHaptics(std::vector<view::Shape>& shapes,
                         const haptics::PseudoHapticReport& report) {
  const Eigen::Vector3d target = V(report.target);
  const Eigen::Vector3d hand = V(report.hand);
  shapes.push_back(Make(view::ShapeKind::kSphere, target, Eigen::Quaterniond::Identity(),
                        {0.012, 0, 0}, report.held ? kGhostHeld : kGhostFree));
  if ((hand - target).norm() > 0.005) shapes.push_back(Segment(target, hand, 0.002, kBend));
}

void AppendForceArrow(std::vector<view::Shape>& shapes, const haptics::Vec3d& at,
                      const haptics::Vec3d& force) {
  const Eigen::Vector3d f = V(force);
  const double n = f.norm();
  if (n < 0.05) return;
  const Eigen::Vector3d from = V(at);
  const Eigen::Vector3d to = from + f / n * std::min(0.01 * n, 0.15);
  shapes.push_back(Segment(from, to, 0.003, kForce));
  shapes.push_back(
      Make(view::ShapeKind::kSphere, to, Eigen::Quaterniond::Identity(), {0.007, 0, 0}, kForce));
}

void ShiftShapes(std::vector<view::Shape>& shapes, size_t first, const haptics::Vec3d& offset) {
  for (size_t i = first; i < shapes.size(); ++i) {
    for (int k = 0; k < 3; ++k) shapes[i].position[static_cast<size_t>(k)] += offset[k];
  }
}

}  // namespace haptel::mediator
