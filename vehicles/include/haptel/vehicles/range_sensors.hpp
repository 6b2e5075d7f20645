#pragma once
/// @file The simulated robot's range sensors: beams cast from the robot's
/// centre against the track's walls and round posts (gate posts and
/// obstacles), each reading the distance to the first thing it meets, plus
/// seeded Gaussian noise, within [0, max_range].
#include <random>

#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/core/range_scan.hpp"

namespace haptel::vehicles {

/// Distance (m) along the ray from `origin` in unit direction `direction` to
/// the first wall or round post of `track` it meets, or `max_range` when none
/// is nearer. An origin inside a post reads 0.
double CastRay(const Track& track, const Vec2& origin, const Vec2& direction, double max_range);
/// The same against these walls and posts (a track as it truly stands).
double CastRay(const std::vector<Segment2>& walls, const std::vector<CircleObstacle>& posts,
               const Vec2& origin, const Vec2& direction, double max_range);

/// What a real range sensor gets wrong besides its noise, per beam: a false
/// echo (a range uniform in [0, max_range)) with probability `spurious`,
/// else a beam that met something reads max_range (no echo) with
/// probability `dropout`. Both 0: no draw is taken.
struct RangeFaults {
  double spurious = 0.0;
  double dropout = 0.0;
};

/// The scan of a robot at (x, y, heading) on `track`, laid out by `config`;
/// `noise` draws each reading's noise (none when config.noise_sd is 0).
RangeScan ScanTrack(const Track& track, double x, double y, double heading,
                    const RangeSensorConfig& config, std::mt19937_64& noise);
/// The same against these walls and posts, with `faults` drawn from `echoes`
/// (its own stream: the noise's draws are those of a scan without faults).
RangeScan ScanTrack(const std::vector<Segment2>& walls, const std::vector<CircleObstacle>& posts,
                    double x, double y, double heading, const RangeSensorConfig& config,
                    std::mt19937_64& noise, const RangeFaults& faults, std::mt19937_64& echoes);

}  // namespace haptel::vehicles
