#include "haptel/sdl_ff/ff_model.hpp"

#include <algorithm>
#include <cmath>

namespace haptel::haptics::sdl_ff {

namespace {

constexpr double kDegToRad = M_PI / 180.0;

double AxisAt(const Axes& axes, int axis) {
  return axis >= 0 && axis < kMaxAxes ? axes[static_cast<size_t>(axis)] : 0.0;
}

/// An axis' deflection from its rest: [−1, 1] from the centre, [0, 1] from an end.
double FromRest(double a, SdlFfAxisRest rest) {
  a = std::clamp(a, -1.0, 1.0);
  switch (rest) {
    case SdlFfAxisRest::kLow:
      return 0.5 * (a + 1.0);
    case SdlFfAxisRest::kHigh:
      return 0.5 * (1.0 - a);
    case SdlFfAxisRest::kCentre:
      break;
  }
  return a;
}

double RestRate(SdlFfAxisRest rest) {
  return rest == SdlFfAxisRest::kCentre ? 1.0 : rest == SdlFfAxisRest::kLow ? 0.5 : -0.5;
}

/// How a reverse axis rests: as the main one does, low beside a stick.
SdlFfAxisRest ReverseRest(const SdlFfAxisMap& map) {
  return map.rest == SdlFfAxisRest::kCentre ? SdlFfAxisRest::kLow : map.rest;
}

/// d(deflection)/d(a_axis) of one coordinate's map.
double DeflectionRate(const SdlFfAxisMap& map, int axis) {
  double rate = 0.0;
  if (map.axis == axis) rate += RestRate(map.rest);
  if (map.reverse_axis == axis) rate -= RestRate(ReverseRest(map));
  return rate;
}

/// Hamilton product a ⊗ b of (w, x, y, z) quaternions.
std::array<double, 4> Multiply(const std::array<double, 4>& a, const std::array<double, 4>& b) {
  return {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
          a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
          a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
          a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
}

/// Roll, pitch, yaw (deg, about x, y, z; applied z, then y, then x) as a quaternion.
std::array<double, 4> FromRollPitchYaw(const std::array<double, 3>& deg) {
  const double r = 0.5 * deg[0] * kDegToRad, p = 0.5 * deg[1] * kDegToRad,
               y = 0.5 * deg[2] * kDegToRad;
  const std::array<double, 4> qx{std::cos(r), std::sin(r), 0, 0};
  const std::array<double, 4> qy{std::cos(p), 0, std::sin(p), 0};
  const std::array<double, 4> qz{std::cos(y), 0, 0, std::sin(y)};
  return Multiply(qz, Multiply(qy, qx));
}

double Dot(const Vec3d& a, const Vec3d& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

}  // namespace

double AxisFromSdl(int16_t raw) { return std::max(-1.0, static_cast<double>(raw) / 32767.0); }

double Deflection(const SdlFfAxisMap& map, const Axes& axes) {
  if (map.axis < 0 && map.reverse_axis < 0) return 0.0;
  double d = 0.0;
  if (map.axis >= 0) d = FromRest(AxisAt(axes, map.axis), map.rest);
  if (map.reverse_axis >= 0) d -= FromRest(AxisAt(axes, map.reverse_axis), ReverseRest(map));
  return d;
}

HandPose HandFromAxes(const SdlFfHandMap& hand, const Axes& axes) {
  HandPose pose;
  const std::array<const SdlFfAxisMap*, 3> maps{&hand.x, &hand.y, &hand.z};
  for (int c = 0; c < 3; ++c)
    pose.position[c] = hand.centre[c] + maps[c]->span * Deflection(*maps[c], axes);
  pose.orientation = FromRollPitchYaw(hand.orientation_deg);
  if (hand.rim.axis >= 0) {
    // The cockpit's wheel: the grip at the rim's top turned about −x by θ
    // (+ = left): (y, z) = r·(sin θ, cos θ) about the hub.
    const double theta =
        hand.rim.angle_deg * kDegToRad * std::clamp(AxisAt(axes, hand.rim.axis), -1.0, 1.0);
    pose.position[1] += hand.rim.radius * std::sin(theta);
    pose.position[2] += hand.rim.radius * std::cos(theta);
    pose.orientation =
        Multiply({std::cos(0.5 * theta), -std::sin(0.5 * theta), 0.0, 0.0}, pose.orientation);
  }
  return pose;
}

Vec3d HandLever(const SdlFfHandMap& hand, const Axes& axes, int axis) {
  Vec3d lever{hand.x.span * DeflectionRate(hand.x, axis),
              hand.y.span * DeflectionRate(hand.y, axis),
              hand.z.span * DeflectionRate(hand.z, axis)};
  if (hand.rim.axis >= 0 && hand.rim.axis == axis) {
    const double span = hand.rim.angle_deg * kDegToRad;
    const double theta = span * std::clamp(AxisAt(axes, axis), -1.0, 1.0);
    lever[1] += hand.rim.radius * span * std::cos(theta);
    lever[2] -= hand.rim.radius * span * std::sin(theta);
  }
  return lever;
}

bool DeadmanHeld(const SdlFfDeadman& deadman, const Axes& axes, uint64_t buttons) {
  if (deadman.button >= 0) return deadman.button < 64 && ((buttons >> deadman.button) & 1U) != 0;
  const SdlFfAxisRest rest = deadman.rest_high ? SdlFfAxisRest::kHigh : SdlFfAxisRest::kLow;
  return deadman.axis >= 0 && FromRest(AxisAt(axes, deadman.axis), rest) >= deadman.threshold;
}

std::array<double, kGloveJoints> GlovePosture(const std::array<double, 3>& flexion, bool closed) {
  std::array<double, kGloveJoints> sensors{};
  if (!closed) return sensors;
  // Glove layout (haptics/types.hpp): four thumb joints, then MCP, PIP, DIP
  // of index, middle, ring and pinky; the thumb stays open, as the cockpit's grip.
  for (int f = 0; f < 4; ++f) {
    for (int j = 0; j < 3; ++j)
      sensors[static_cast<size_t>(4 + 3 * f + j)] = flexion[static_cast<size_t>(j)];
  }
  return sensors;
}

FfPlan PlanEffects(const SdlFfDeviceConfig& config, const std::array<FfSide, kSides>& sides,
                   const Axes& axes, int ff_axes, bool spring, double force_limit) {
  FfPlan plan;
  const std::array<const SdlFfHandMap*, kSides> hands{&config.left, &config.right};
  std::array<Vec3d, kSides> rest{};  // what the spring does not render, N
  std::array<Vec3d, kSides> position{};
  for (int s = 0; s < kSides; ++s) {
    if (!sides[s].used || !sides[s].fresh) continue;
    rest[s] = sides[s].force;
    position[s] = HandFromAxes(*hands[s], axes).position;
  }
  const int n = std::clamp(ff_axes, 0, kFfAxes);
  for (int j = 0; j < n; ++j) {
    // The spring on axis j: the first fresh hand coordinate it moves alone and linearly.
    for (int s = 0; s < kSides && spring && !plan.spring[j].active; ++s) {
      const FfSide& side = sides[s];
      if (!side.used || !side.fresh || !side.field.enabled || !(side.field.stiffness > 0.0))
        continue;
      const std::array<const SdlFfAxisMap*, 3> maps{&hands[s]->x, &hands[s]->y, &hands[s]->z};
      for (int c = 0; c < 3; ++c) {
        const SdlFfAxisMap& m = *maps[c];
        if (m.axis != j || m.reverse_axis >= 0 || m.span == 0.0) continue;
        const double lever = m.span * RestRate(m.rest);
        // The axis value that puts the coordinate at the neutral.
        const double d = (side.field.neutral[c] - hands[s]->centre[c]) / m.span;
        const double centre = m.rest == SdlFfAxisRest::kCentre ? d
                              : m.rest == SdlFfAxisRest::kLow  ? 2.0 * d - 1.0
                                                               : 1.0 - 2.0 * d;
        SpringAxis& sp = plan.spring[j];
        sp.active = true;
        sp.centre = std::clamp(centre, -1.0, 1.0);
        sp.coefficient = std::clamp(side.field.stiffness * std::abs(lever) / force_limit, 0.0, 1.0);
        // The spring's own force at the hand, which the constant need not add.
        const double own = -sp.coefficient * force_limit * std::copysign(1.0, lever) *
                           (std::clamp(AxisAt(axes, j), -1.0, 1.0) - sp.centre);
        rest[s][c] -= own;
        break;
      }
    }
  }
  for (int j = 0; j < n; ++j) {
    double along = 0.0, lever2 = 0.0;
    for (int s = 0; s < kSides; ++s) {
      if (!sides[s].used) continue;
      const Vec3d lever = HandLever(*hands[s], axes, j);
      along += Dot(rest[s], lever);
      lever2 += Dot(lever, lever);
    }
    plan.constant[j] =
        lever2 > 0.0 ? std::clamp(along / (std::sqrt(lever2) * force_limit), -1.0, 1.0) : 0.0;
  }
  for (int s = 0; s < kSides; ++s) {
    const FfSide& side = sides[s];
    if (!side.used || !side.fresh || !side.field.enabled || !side.field.wall_active) continue;
    Vec3d into{};
    for (int c = 0; c < 3; ++c) into[c] = position[s][c] - side.field.wall_point[c];
    const double depth = Dot(into, side.field.wall_normal);
    if (depth > 0.0) {
      plan.wall_press =
          std::max(plan.wall_press, std::min(1.0, side.field.wall_stiffness * depth / force_limit));
    }
  }
  return plan;
}

bool ShakeTrigger::Step(double t_s, const std::array<FfSide, kSides>& sides) {
  uint64_t contacts = contacts_;
  for (const FfSide& side : sides) {
    if (side.used) contacts = std::max(contacts, side.contacts);
  }
  const bool contact = contacts > contacts_;
  contacts_ = contacts;
  if (!contact || t_s < until_s_) return false;
  until_s_ = t_s + shake_s_;
  return true;
}

}  // namespace haptel::haptics::sdl_ff
