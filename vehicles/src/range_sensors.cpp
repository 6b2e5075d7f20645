#include "haptel/vehicles/range_sensors.hpp"

#include <algorithm>
#include <cmath>

namespace haptel::vehicles {

namespace {

/// A standard normal draw (Box–Muller: the same on every standard library,
/// so a seed gives the same scan everywhere).
double Normal(std::mt19937_64& random) {
  const double u1 = (static_cast<double>(random() >> 11) + 0.5) * 0x1.0p-53;
  const double u2 = static_cast<double>(random() >> 11) * 0x1.0p-53;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

/// Uniform in [0, 1) from 53 bits (the same on every standard library).
double Uniform(std::mt19937_64& random) { return static_cast<double>(random() >> 11) * 0x1.0p-53; }

}  // namespace

double CastRay(const Track& track, const Vec2& origin, const Vec2& direction, double max_range) {
  return CastRay(track.walls(), track.round_obstacles(), origin, direction, max_range);
}

double CastRay(const std::vector<Segment2>& walls, const std::vector<CircleObstacle>& posts,
               const Vec2& origin, const Vec2& direction, double max_range) {
  double nearest = max_range;
  for (const Segment2& wall : walls) {
    // origin + t·direction = a + u·(b − a), t >= 0, u in [0, 1].
    const Vec2 edge = wall.b - wall.a;
    const double denominator = Cross2(direction, edge);
    if (std::abs(denominator) < 1e-12) continue;  // parallel: the wall's ends are someone else's
    const Vec2 to_a = wall.a - origin;
    const double t = Cross2(to_a, edge) / denominator;
    const double u = Cross2(to_a, direction) / denominator;
    if (t >= 0.0 && u >= 0.0 && u <= 1.0) nearest = std::min(nearest, t);
  }
  for (const CircleObstacle& post : posts) {
    // |origin + t·direction − centre| = radius: the smaller root in front.
    const Vec2 to_origin = origin - post.center;
    const double b = to_origin.dot(direction);
    const double c = to_origin.squaredNorm() - post.radius * post.radius;
    if (c <= 0.0) return 0.0;  // inside it
    const double discriminant = b * b - c;
    if (discriminant < 0.0) continue;
    const double t = -b - std::sqrt(discriminant);
    if (t >= 0.0) nearest = std::min(nearest, t);
  }
  return nearest;
}

RangeScan ScanTrack(const Track& track, double x, double y, double heading,
                    const RangeSensorConfig& config, std::mt19937_64& noise) {
  std::mt19937_64 unused;
  return ScanTrack(track.walls(), track.round_obstacles(), x, y, heading, config, noise, {},
                   unused);
}

RangeScan ScanTrack(const std::vector<Segment2>& walls, const std::vector<CircleObstacle>& posts,
                    double x, double y, double heading, const RangeSensorConfig& config,
                    std::mt19937_64& noise, const RangeFaults& faults, std::mt19937_64& echoes) {
  RangeScan scan;
  scan.count = std::clamp(config.beams, 0, kMaxRangeBeams);
  if (scan.count == 0) return scan;
  const double fov = config.fov_deg * std::numbers::pi / 180.0;
  scan.angle_increment = scan.count > 1 ? fov / (scan.count - 1) : 0.0;
  scan.angle_min = scan.count > 1 ? -fov / 2.0 : 0.0;
  scan.range_max = config.max_range;
  const Vec2 origin(x, y);
  for (int i = 0; i < scan.count; ++i) {
    const double angle = heading + scan.Angle(i);
    double range =
        CastRay(walls, posts, origin, Vec2(std::cos(angle), std::sin(angle)), config.max_range);
    // Noise only on what the beam meets: "nothing within range" stays exact.
    if (range < config.max_range && config.noise_sd > 0.0) {
      range = std::clamp(range + config.noise_sd * Normal(noise), 0.0,
                         std::nextafter(config.max_range, 0.0));
    }
    if (faults.spurious > 0.0 && Uniform(echoes) < faults.spurious) {
      range = Uniform(echoes) * config.max_range;  // a false echo, whatever is there
    } else if (faults.dropout > 0.0 && range < config.max_range &&
               Uniform(echoes) < faults.dropout) {
      range = config.max_range;  // no echo came back
    }
    scan.ranges[static_cast<size_t>(i)] = static_cast<float>(range);
  }
  return scan;
}

}  // namespace haptel::vehicles
