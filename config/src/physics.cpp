#include "haptel/config/physics.hpp"

#include <string>

#include "haptel/config/check.hpp"
#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

void PhysicsMaterial::ValidateOrThrow() const {
  check::Number("friction", friction, 0.0, 10.0);
  check::Number("restitution", restitution, 0.0, 1.0);
  check::Number("rolling_friction", rolling_friction, 0.0, 0.05);
  check::Number("spinning_friction", spinning_friction, 0.0, 0.05);
  if (spinning_friction > 0.0 && !(rolling_friction > 0.0)) {
    // Bullet adds the spinning-friction row only next to the rolling ones.
    check::Fail("spinning_friction",
                "spinning_friction 0 unless rolling_friction > 0 (Bullet ignores spinning "
                "friction without rolling friction)",
                {"rolling_friction"});
  }
}

void ProxyHandConfig::ValidateOrThrow() const {
  check::Number("palm_mass", palm_mass, 0.01, 10.0);
  check::Vec3("palm_half_extents", palm_half_extents, 0.002, 0.5);
  check::Vec3("phalanx_mass", phalanx_mass, 0.001, 1.0);
  check::Vec3("phalanx_length", phalanx_length, 0.005, 0.2);
  check::Number("phalanx_radius", phalanx_radius, 0.001, 0.05);
  check::Number("joint_stiffness", joint_stiffness, 1e-4, 1e4);
  check::Number("joint_damping", joint_damping, 0.0, 1e3);
  // Up to 1e8: the stability benchmark sweeps past 1e7 to find where it breaks.
  check::Number("coupling_linear_stiffness", coupling_linear_stiffness, 1.0, 1e8);
  check::Number("coupling_linear_damping", coupling_linear_damping, 0.0, 1e5);
  check::Number("coupling_angular_stiffness", coupling_angular_stiffness, 1e-3, 1e5);
  check::Number("coupling_angular_damping", coupling_angular_damping, 0.0, 1e3);
  check::Number("feedback_stiffness", feedback_stiffness, 0.0, 1e5);
  check::Number("feedback_damping", feedback_damping, 0.0, 1e3);
  check::Number("finger_feedback_stiffness", finger_feedback_stiffness, 0.0, 1e5);
  check::Nested("material", material);
  for (double length : phalanx_length) {
    if (length < 2.0 * phalanx_radius) {
      check::Fail("phalanx_length",
                  "every phalanx_length >= 2 * phalanx_radius (capsules joint to joint)",
                  {"phalanx_radius"});
    }
  }
}

void PhysicsConfig::ValidateOrThrow() const {
  // A thread's step from a user's file; a reference run (stepped by its
  // caller, never a thread) may go finer to serve as the ground truth.
  check::Number("step_s", step_s, reference ? kMinReferenceStepS : kMinStepS, kMaxStepS);
  check::Whole("solver_iterations", solver_iterations, 1, 1000);
  check::Vec3("gravity", gravity, -100.0, 100.0);
  check::Whole("realtime_priority", realtime_priority, 0, 99);
  check::Nested("hand", hand);
}

namespace {
PhysicsMaterial ReadMaterial(YamlMap map, const PhysicsMaterial& fallback) {
  PhysicsMaterial m;
  m.friction = map.Number("friction", fallback.friction);
  m.restitution = map.Number("restitution", fallback.restitution);
  m.rolling_friction = map.Number("rolling_friction", fallback.rolling_friction);
  m.spinning_friction = map.Number("spinning_friction", fallback.spinning_friction);
  map.Finish();
  return m;
}
}  // namespace

PhysicsConfig LoadPhysics(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  PhysicsConfig c;
  c.file = file;
  c.step_s = root.Number("step_s", c.step_s);
  c.solver_iterations = root.Integer("solver_iterations", c.solver_iterations);
  c.gravity = root.Vec3("gravity", c.gravity);
  c.realtime_priority = root.Integer("realtime_priority", c.realtime_priority);

  YamlMap hand = root.Map("hand");
  ProxyHandConfig& h = c.hand;
  h.palm_mass = hand.Number("palm_mass", h.palm_mass);
  h.palm_half_extents = hand.Vec3("palm_half_extents", h.palm_half_extents);
  h.phalanx_mass = hand.Vec3("phalanx_mass", h.phalanx_mass);
  h.phalanx_length = hand.Vec3("phalanx_length", h.phalanx_length);
  h.phalanx_radius = hand.Number("phalanx_radius", h.phalanx_radius);
  h.joint_stiffness = hand.Number("joint_stiffness", h.joint_stiffness);
  h.joint_damping = hand.Number("joint_damping", h.joint_damping);
  h.coupling_linear_stiffness =
      hand.Number("coupling_linear_stiffness", h.coupling_linear_stiffness);
  h.coupling_linear_damping = hand.Number("coupling_linear_damping", h.coupling_linear_damping);
  h.coupling_angular_stiffness =
      hand.Number("coupling_angular_stiffness", h.coupling_angular_stiffness);
  h.coupling_angular_damping = hand.Number("coupling_angular_damping", h.coupling_angular_damping);
  h.feedback_stiffness = hand.Number("feedback_stiffness", h.feedback_stiffness);
  h.feedback_damping = hand.Number("feedback_damping", h.feedback_damping);
  h.finger_feedback_stiffness =
      hand.Number("finger_feedback_stiffness", h.finger_feedback_stiffness);
  h.gravity = hand.Bool("gravity", h.gravity);
  h.material = ReadMaterial(hand.Map("material"), h.material);
  hand.Finish();
  root.Finish();
  config_detail::ValidateIn(root, c);
  return c;
}

}  // namespace haptel
