#include "haptel/interfaces/shared_control.hpp"

#include <algorithm>

#include "haptel/config/error.hpp"

namespace haptel::interfaces {

namespace {

/// The vehicle's centre at time t of an arc at forward speed v and turn rate
/// omega, from the origin heading +x (its own frame at the scan).
void ArcPosition(double v, double omega, double t, double& x, double& y) {
  if (std::abs(omega) < 1e-9) {
    x = v * t;
    y = 0.0;
    return;
  }
  x = v / omega * std::sin(omega * t);
  y = v / omega * (1.0 - std::cos(omega * t));
}

}  // namespace

double TimeToCollision(const RangeScan& scan, const TreadCommand& command,
                       const VehicleGeometry& vehicle, double clearance, double horizon_s) {
  constexpr double kNever = std::numeric_limits<double>::infinity();
  const int count = std::clamp(scan.count, 0, kMaxRangeBeams);
  const double v = 0.5 * (command.left + command.right) * vehicle.max_speed;
  const double omega = (command.right - command.left) * vehicle.max_speed / vehicle.track_width;
  // A turn on the spot sweeps nothing the round body does not already cover.
  if (count == 0 || std::abs(v) < 1e-9) return kNever;

  // The points the beams met, and how near the nearest is now: the body may
  // come as near as `reach`, or — already nearer than that (along a wall) —
  // no nearer than it is.
  std::array<double, kMaxRangeBeams> px{}, py{};
  int hits = 0;
  double nearest = kNever;
  for (int i = 0; i < count; ++i) {
    if (!scan.Hit(i)) continue;
    const double r = scan.ranges[static_cast<size_t>(i)];
    px[hits] = r * std::cos(scan.Angle(i));
    py[hits] = r * std::sin(scan.Angle(i));
    nearest = std::min(nearest, r);
    ++hits;
  }
  if (hits == 0) return kNever;
  constexpr double kCloser = 0.01;  // m nearer than now counts as closing in
  const double reach = std::min(vehicle.body_radius + clearance, nearest - kCloser);
  auto collides = [&](double t) {
    double x = 0.0, y = 0.0;
    ArcPosition(v, omega, t, x, y);
    for (int k = 0; k < hits; ++k) {
      const double dx = px[k] - x, dy = py[k] - y;
      if (dx * dx + dy * dy < reach * reach) return true;
    }
    return false;
  };
  // March in steps shorter than the body's own reach, then bisect the step
  // where it first collides, so that the time varies smoothly with the command.
  const double step = std::min(horizon_s / 20.0, std::max(reach, 0.01) / (2.0 * std::abs(v)));
  double safe = 0.0;
  for (double t = step;; t += step) {
    const double probe = std::min(t, horizon_s);
    if (collides(probe)) {
      double hit = probe;
      for (int i = 0; i < 10; ++i) {
        const double mid = 0.5 * (safe + hit);
        (collides(mid) ? hit : safe) = mid;
      }
      return hit;
    }
    safe = probe;
    if (probe >= horizon_s) return kNever;
  }
}

const RangeScan& PersistentEchoes::Filter(const RangeScan& scan) {
  const int count = std::clamp(scan.count, 0, kMaxRangeBeams);
  const bool same =
      have_last_ && scan.count == last_.count &&
      std::equal(scan.ranges.begin(), scan.ranges.begin() + count, last_.ranges.begin());
  if (!same) {
    before_ = last_;
    have_before_ = have_last_;
    last_ = scan;
    have_last_ = true;
    filtered_ = scan;
    // The first scan (or one of another layout) has nothing to be checked
    // against: taken as it is, erring towards guidance.
    const bool comparable = have_before_ && before_.count == count;
    for (int i = 0; comparable && i < count; ++i) {
      if (!scan.Hit(i)) continue;
      bool seen = false;
      for (int j = std::max(0, i - 1); j <= std::min(count - 1, i + 1); ++j) {
        seen = seen ||
               (before_.Hit(j) && std::abs(before_.ranges[static_cast<size_t>(j)] -
                                           scan.ranges[static_cast<size_t>(i)]) <= tolerance_m_);
      }
      if (!seen) filtered_.ranges[static_cast<size_t>(i)] = static_cast<float>(scan.range_max);
    }
  }
  return filtered_;
}

SharedControl::SharedControl(const SharedControlConfig& config, const VehicleGeometry& vehicle)
    : config_(Validated(config)), vehicle_(vehicle) {}

void SharedControl::Apply(const Guidance& guidance, haptics::ForceField& field) const {
  field.guidance_active = guidance.active;
  field.guidance_point = guidance.point;
  field.guidance_normal = guidance.normal;
  field.guidance_stiffness = config_.stiffness;
  field.guidance_max_force = config_.max_force;
}

}  // namespace haptel::interfaces
