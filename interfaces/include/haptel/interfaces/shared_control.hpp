#pragma once
/// @file Haptic shared control (Abbink, Mulder & Boer 2012; Flemisch's
/// "H-metaphor"): the interface looks along the motion the hand's command
/// would give, against what the vehicle's range sensors see, and pushes the
/// hand away from commands that would meet an obstacle within a horizon. The
/// operator keeps the authority: the push is bounded, and the command is
/// always the hand's own, so pushing through the force drives on.
///
/// Each session tick (not in the servo loop), SharedControl::Guide:
///  1. predicts, for the hand's command, the vehicle's path as an arc at the
///     commanded speeds (forward v, turn ω from the treads) and finds the time
///     to collision: the first time its body, grown by a clearance, reaches a
///     point a beam met — a point it is not already closer to than that, so
///     that driving along a wall is not a collision;
///  2. steers first: the danger of a command is judged on its path, not its
///     speed — every command is looked along at the hand's own speed, so the
///     look-ahead is horizon_s·v (it grows with speed) and slowing down does
///     not count as avoiding what the path still meets (a time horizon alone
///     makes "slower" look safe: the earlier law pushed mostly towards slower
///     and the vehicle drifted on into the wall). The danger's gradient in
///     hand space is then the steer away, and the safe commands' boundary is
///     found along it by bisection;
///  3. where no steer within reach clears it (a wall square ahead), slows
///     down: the time-to-collision danger, back towards the neutral point;
///  4. a guidance plane at that boundary: ForceField's guidance term, a spring
///     of `stiffness` N/m past the plane (a stiffness the hand must feel
///     against its own: the level of haptic authority, Abbink et al. 2012),
///     saturating at max_force, which the servo loop evaluates from the
///     hand's pose at 1 kHz (allocation-free, see haptics/force_field.hpp).
#include <algorithm>
#include <cmath>
#include <limits>

#include "haptel/config/gesture.hpp"
#include "haptel/core/range_scan.hpp"
#include "haptel/haptics/types.hpp"
#include "haptel/interfaces/interface.hpp"

namespace haptel::interfaces {

/// What of the vehicle the prediction needs (the vehicle file's drive and body).
struct VehicleGeometry {
  double max_speed = 0.3;     ///< m/s of a tread at command 1
  double track_width = 0.16;  ///< m between the treads
  double body_radius = 0.11;  ///< m
};

/// Seconds until the vehicle, driven by `command` from where it is now, meets
/// an obstacle `scan` sees (its body grown by `clearance`), looking no
/// further than `horizon_s`; +infinity when it meets none by then (or the
/// scan is empty).
double TimeToCollision(const RangeScan& scan, const TreadCommand& command,
                       const VehicleGeometry& vehicle, double clearance, double horizon_s);

/// A scan with the echoes that were not there a scan before left out: a
/// scanner's false echo (a speckle, a reflection) lasts one scan, and shared
/// control looking along the path would push the hand from an obstacle that
/// is not there, over and over (a `lab` reality's 2 % false echoes held the
/// cockpit-shared lap at its first gate). A beam's echo stands when the
/// previous distinct scan had one within `tolerance_m` on the same beam or a
/// neighbour (a turn shifts what a beam sees by up to a beam a scan); the
/// first scan is taken as it is. It costs one scan's delay on a new obstacle. Fixed capacity: no
/// allocation.
class PersistentEchoes {
 public:
  explicit PersistentEchoes(double tolerance_m = 0.05) : tolerance_m_(tolerance_m) {}

  /// `scan` with its unconfirmed echoes read as range_max; the same scan
  /// passed again (the interface steps faster than states arrive) is not a
  /// second look.
  const RangeScan& Filter(const RangeScan& scan);

 private:
  double tolerance_m_;
  RangeScan last_{}, before_{}, filtered_{};
  bool have_last_ = false, have_before_ = false;
};

class SharedControl {
 public:
  /// Validates `config` (SharedControlConfig::ValidateOrThrow: ConfigFieldError).
  SharedControl(const SharedControlConfig& config, const VehicleGeometry& vehicle);

  /// The guidance for a hand at `hand` (m, device frame) whose command is
  /// map(position), with commands at `neutral` safe (they stop the vehicle).
  template <typename Map>
  Guidance Guide(const RangeScan& scan, const haptics::Vec3d& hand, const haptics::Vec3d& neutral,
                 const Map& map) const;

  /// Sets `field`'s guidance term from `guidance` (off when inactive).
  void Apply(const Guidance& guidance, haptics::ForceField& field) const;

  const SharedControlConfig& config() const { return config_; }
  const VehicleGeometry& vehicle() const { return vehicle_; }

 private:
  /// The danger of `command`: 0 beyond the horizon, 1 at collision now.
  double Danger(const RangeScan& scan, const TreadCommand& command) const {
    const double ttc =
        TimeToCollision(scan, command, vehicle_, config_.clearance, config_.horizon_s);
    return std::isfinite(ttc) ? std::clamp(1.0 - ttc / config_.horizon_s, 0.0, 1.0) : 0.0;
  }
  /// The danger of the path of the command a hand at `p` gives, driven at
  /// forward command `forward` (the hand's own): the same arc (the treads'
  /// ratio kept), so that only where it leads counts, not how fast.
  template <typename Map>
  double PathDangerAt(const RangeScan& scan, const haptics::Vec3d& p, double forward,
                      const Map& map) const {
    const TreadCommand c = map(p);
    const double own = 0.5 * (c.left + c.right);
    if (std::abs(own) < 1e-6 || (own > 0.0) != (forward > 0.0)) return Danger(scan, c);
    const double scale = forward / own;
    return Danger(scan, TreadCommand{c.left * scale, c.right * scale});
  }

  SharedControlConfig config_;
  VehicleGeometry vehicle_;
};

template <typename Map>
Guidance SharedControl::Guide(const RangeScan& scan, const haptics::Vec3d& hand,
                              const haptics::Vec3d& neutral, const Map& map) const {
  Guidance g;
  g.max_force = config_.max_force;
  if (scan.count == 0) return g;
  g.time_to_collision_s =
      TimeToCollision(scan, map(hand), vehicle_, config_.clearance, config_.horizon_s);
  if (!std::isfinite(g.time_to_collision_s)) return g;
  g.danger = std::clamp(1.0 - g.time_to_collision_s / config_.horizon_s, 0.0, 1.0);

  // Hand space is the horizontal plane (x forward, y left): the gesture's axes.
  constexpr double kStep = 0.003;  // m: finite differences, below the command's resolution
  auto at = [&](double dx, double dy) {
    haptics::Vec3d p = hand;
    p[0] += dx;
    p[1] += dy;
    return p;
  };
  // Steering first: the path's danger at the hand's own speed.
  const TreadCommand own = map(hand);
  const double forward = 0.5 * (own.left + own.right);
  auto path_danger = [&](const haptics::Vec3d& p) { return PathDangerAt(scan, p, forward, map); };
  auto time_danger = [&](const haptics::Vec3d& p) { return Danger(scan, map(p)); };
  const double gx = (path_danger(at(kStep, 0)) - path_danger(at(-kStep, 0))) / (2 * kStep);
  const double gy = (path_danger(at(0, kStep)) - path_danger(at(0, -kStep))) / (2 * kStep);
  const double to_neutral_x = neutral[0] - hand[0];
  const double to_neutral_y = neutral[1] - hand[1];
  const double reach = std::hypot(to_neutral_x, to_neutral_y);
  if (reach < 1e-6) return g;  // at neutral the vehicle stops: nothing to push away from

  // Where along `-(ux, uy)` from the hand `danger` ends, or < 0 if not within `limit`.
  auto safe_after = [&](const auto& danger, double ux, double uy, double limit) {
    if (danger(at(-ux * limit, -uy * limit)) > 0.0) return -1.0;
    double inside = 0.0, outside = limit;
    for (int i = 0; i < 12; ++i) {
      const double mid = 0.5 * (inside + outside);
      (danger(at(-ux * mid, -uy * mid)) > 0.0 ? inside : outside) = mid;
    }
    return outside;
  };
  double nx = 0.0, ny = 0.0, depth = -1.0;
  const double gradient = std::hypot(gx, gy);
  if (gradient > 1e-9) {
    nx = gx / gradient;
    ny = gy / gradient;
    depth = safe_after(path_danger, nx, ny, reach);
  }
  if (depth < 0.0) {  // no steer clears it: slow down, back towards stopping
    nx = -to_neutral_x / reach;
    ny = -to_neutral_y / reach;
    depth = safe_after(time_danger, nx, ny, reach);
    if (depth < 0.0) depth = reach;
  }
  g.active = true;
  g.normal = {nx, ny, 0.0};
  g.point = at(-nx * depth, -ny * depth);
  const double push = std::min(config_.stiffness * depth, config_.max_force);
  g.force = {-push * nx, -push * ny, 0.0};
  return g;
}

}  // namespace haptel::interfaces
