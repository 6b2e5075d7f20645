#include "haptel/config/physics.hpp"

#include <string>

#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;

namespace {
PhysicsMaterial ReadMaterial(YamlMap map, const PhysicsMaterial& fallback) {
  PhysicsMaterial m;
  m.friction = map.Number("friction", fallback.friction, 0.0, 10.0);
  m.restitution = map.Number("restitution", fallback.restitution, 0.0, 1.0);
  m.rolling_friction = map.Number("rolling_friction", fallback.rolling_friction, 0.0, 0.05);
  m.spinning_friction = map.Number("spinning_friction", fallback.spinning_friction, 0.0, 0.05);
  if (m.spinning_friction > 0.0 && !(m.rolling_friction > 0.0)) {
    // Bullet adds the spinning-friction row only next to the rolling ones.
    if (map.Has("spinning_friction")) {
      map.Fail("spinning_friction", "0 unless rolling_friction > 0 (Bullet ignores it otherwise)");
    }
    map.Fail("rolling_friction", "> 0 while spinning_friction (default " +
                                     std::to_string(m.spinning_friction) + " m) is > 0");
  }
  map.Finish();
  return m;
}
}  // namespace

PhysicsConfig LoadPhysics(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  PhysicsConfig c;
  c.file = file;
  c.step_s = root.Number("step_s", c.step_s, 1e-4, 0.01);
  c.solver_iterations = root.Integer("solver_iterations", c.solver_iterations, 1, 1000);
  c.gravity = root.Vec3("gravity", c.gravity, -100.0, 100.0);
  c.realtime_priority = root.Integer("realtime_priority", c.realtime_priority, 0, 99);

  YamlMap hand = root.Map("hand");
  ProxyHandConfig& h = c.hand;
  h.palm_mass = hand.Number("palm_mass", h.palm_mass, 0.01, 10.0);
  h.palm_half_extents = hand.Vec3("palm_half_extents", h.palm_half_extents, 0.002, 0.5);
  h.phalanx_mass = hand.Vec3("phalanx_mass", h.phalanx_mass, 0.001, 1.0);
  h.phalanx_length = hand.Vec3("phalanx_length", h.phalanx_length, 0.005, 0.2);
  h.phalanx_radius = hand.Number("phalanx_radius", h.phalanx_radius, 0.001, 0.05);
  h.joint_stiffness = hand.Number("joint_stiffness", h.joint_stiffness, 1e-4, 1e4);
  h.joint_damping = hand.Number("joint_damping", h.joint_damping, 0.0, 1e3);
  h.coupling_linear_stiffness =
      hand.Number("coupling_linear_stiffness", h.coupling_linear_stiffness, 1.0, 1e7);
  h.coupling_linear_damping =
      hand.Number("coupling_linear_damping", h.coupling_linear_damping, 0.0, 1e5);
  h.coupling_angular_stiffness =
      hand.Number("coupling_angular_stiffness", h.coupling_angular_stiffness, 1e-3, 1e5);
  h.coupling_angular_damping =
      hand.Number("coupling_angular_damping", h.coupling_angular_damping, 0.0, 1e3);
  h.feedback_stiffness = hand.Number("feedback_stiffness", h.feedback_stiffness, 0.0, 1e5);
  h.feedback_damping = hand.Number("feedback_damping", h.feedback_damping, 0.0, 1e3);
  h.finger_feedback_stiffness =
      hand.Number("finger_feedback_stiffness", h.finger_feedback_stiffness, 0.0, 1e5);
  h.gravity = hand.Bool("gravity", h.gravity);
  h.material = ReadMaterial(hand.Map("material"), h.material);
  hand.Finish();
  for (double length : h.phalanx_length) {
    if (length < 2.0 * h.phalanx_radius) {
      root.Fail("hand", "every phalanx_length >= 2 * phalanx_radius (capsules joint to joint)");
    }
  }
  root.Finish();
  return c;
}

}  // namespace haptel
