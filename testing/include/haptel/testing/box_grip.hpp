#pragma once
/// @file The two-palm grasp scene shared by the physics tests and the
/// physics and stability benchmarks: a 0.5 kg, 12 cm box on the floor plane
/// z = 0 between two proxy palms that face it from ±y, their centres over the
/// box's centre.
#include <array>
#include <cmath>

#include "haptel/physics/world.hpp"
#include "haptel/testing/vec_math.hpp"

namespace haptel::physics {

struct BoxGrip {
  static constexpr double kHalf = 0.06;  ///< m, the box's half size
  static constexpr double kMass = 0.5;   ///< kg

  PhysicsWorld& world;
  BodyId box;

  /// Adds the floor, the box at rest on it and both hands to `world`.
  explicit BoxGrip(PhysicsWorld& w)
      : world(w),
        box((w.AddStaticPlane({0, 0, 1}, 0.0),
             w.AddDynamicBox({0, 0, kHalf}, {kHalf, kHalf, kHalf}, kMass))) {
    w.AddHand(haptics::Side::kLeft);
    w.AddHand(haptics::Side::kRight);
  }

  /// Sets the tracked palms `depth` (m) inside the box's faces (negative: a
  /// gap), wrists at height `z`, around a box centre at y = `y0`. Palms face
  /// the box: the left hand's −z turned to +y, the right's to −y.
  void Track(double depth, double z, double y0 = 0.0) const {
    const auto& hc = world.config().hand;
    const double x = -hc.palm_half_extents[0];
    const double y = kHalf + hc.palm_half_extents[2] - depth;
    static const std::array<double, 4> q_left = haptics::AxisAngle({1, 0, 0}, M_PI / 2);
    static const std::array<double, 4> q_right = haptics::AxisAngle({1, 0, 0}, -M_PI / 2);
    world.hand(haptics::Side::kLeft)->SetTracked(haptics::TrackedHand({x, y0 - y, z}, q_left));
    world.hand(haptics::Side::kRight)->SetTracked(haptics::TrackedHand({x, y0 + y, z}, q_right));
  }
};

}  // namespace haptel::physics
