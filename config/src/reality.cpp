#include "haptel/config/reality.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "haptel/config/archives.hpp"
#include "haptel/config/check.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"

namespace haptel {

namespace check = config_check;

namespace {

/// A spread's mean within [min, max] and its sd at most their span.
void CheckSpread(const std::string& key, const Spread& s, double min, double max) {
  check::Number(key + ".mean", s.mean, min, max);
  check::Number(key + ".sd", s.sd, 0.0, max - min);
}

/// Draws in a fixed order from one generator: one seed, one robot.
class Drawer {
 public:
  explicit Drawer(uint64_t seed) : random_(seed) {}
  /// Normal about the mean, clipped to ±2 sd; sd 0 takes no number from the
  /// generator (a file that adds a spread changes only what follows it).
  double operator()(const Spread& s) {
    if (!(s.sd > 0.0)) return s.mean;
    const double z = std::clamp(normal_(random_), -2.0, 2.0);
    return s.mean + s.sd * z;
  }
  double Uniform(double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(random_);
  }

 private:
  std::mt19937_64 random_;
  std::normal_distribution<double> normal_{0.0, 1.0};
};

}  // namespace

void Spread::ValidateOrThrow() const { config_detail::CheckFields(*this); }

void FloorPatchesConfig::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  CheckSpread("radius", radius, 0.01, 2.0);
  CheckSpread("traction", traction, 0.1, 1.0);
}

void MapErrorConfig::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  CheckSpread("layout_rotation_deg", layout_rotation_deg, -10.0, 10.0);
}

void RobotRealityConfig::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  CheckSpread("tread_gain", tread_gain, 0.5, 1.5);
  CheckSpread("tread_asymmetry", tread_asymmetry, -0.3, 0.3);
  CheckSpread("track_width_factor", track_width_factor, 1.0, 2.5);
  CheckSpread("lateral_slip", lateral_slip, 0.0, 0.5);
  CheckSpread("motor_time_constant_factor", motor_time_constant_factor, 0.2, 5.0);
  CheckSpread("battery_fade_per_min", battery_fade_per_min, 0.0, 0.2);
  CheckSpread("gyro_drift_deg_per_min", gyro_drift_deg_per_min, -60.0, 60.0);
}

void BlimpRealityConfig::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  CheckSpread("wind_speed", wind_speed, 0.0, 15.0);
  CheckSpread("wind_direction_deg", wind_direction_deg, -360.0, 360.0);
  CheckSpread("gust_rms", gust_rms, 0.0, 10.0);
  CheckSpread("buoyancy_error", buoyancy_error, -0.2, 0.2);
  CheckSpread("gondola_extra_mass", gondola_extra_mass, 0.0, 5.0);
}

void ClockRealityConfig::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  CheckSpread("offset_s", offset_s, -1e5, 1e5);
  CheckSpread("drift_ppm", drift_ppm, -1000.0, 1000.0);
}

void RealityConfig::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  check::NonEmpty("name", name);
  // Sections a file may leave out are checked here, not by CheckFields.
  check::Nested("robot", robot);
  check::Nested("blimp", blimp);
  check::Nested("clock", clock);
}

RealityConfig LoadReality(const std::filesystem::path& file) {
  return config_detail::LoadFile<RealityConfig>(file);
}

std::filesystem::path RealityFile(const std::string& name_or_file) {
  const std::filesystem::path p(name_or_file);
  if (name_or_file.find('/') == std::string::npos && !p.has_extension()) {
    return ShippedFile("config/realities/" + name_or_file + ".yaml");
  }
  return p;
}

DrawnReality NominalReality(const VehicleConfig& vehicle) {
  DrawnReality d;
  d.name = "none";
  d.seed = 0;
  d.left_gain = vehicle.drive.left_gain;
  d.right_gain = vehicle.drive.right_gain;
  d.track_width = d.effective_track_width = vehicle.drive.track_width;
  d.motor_time_constant = vehicle.drive.motor_time_constant;
  d.range_noise_sd = vehicle.range_sensors.noise_sd;
  d.range_noise_seed = vehicle.range_sensors.seed;
  d.wind_x = vehicle.airship.wind.mean[0];
  d.wind_y = vehicle.airship.wind.mean[1];
  d.gust_rms = vehicle.airship.wind.gust_rms;
  d.volume = vehicle.airship.volume;
  d.payload_mass = vehicle.airship.payload_mass;
  return d;
}

DrawnReality DrawReality(const RealityConfig& reality, uint64_t seed, const VehicleConfig& vehicle,
                         const Track* track) {
  DrawnReality d = NominalReality(vehicle);
  d.name = reality.name;
  d.seed = seed;
  Drawer draw(seed);
  const RobotRealityConfig& r = reality.robot;
  const double gain = draw(r.tread_gain);
  const double asymmetry = draw(r.tread_asymmetry);
  d.left_gain *= gain * (1.0 + 0.5 * asymmetry);
  d.right_gain *= gain * (1.0 - 0.5 * asymmetry);
  d.effective_track_width = d.track_width * std::max(1.0, draw(r.track_width_factor));
  d.lateral_slip_s = std::max(0.0, draw(r.lateral_slip));
  d.motor_time_constant *= std::max(0.05, draw(r.motor_time_constant_factor));
  d.battery_fade_per_min = std::max(0.0, draw(r.battery_fade_per_min));
  d.odometry = r.odometry ? 1.0 : 0.0;
  d.encoder_noise = r.encoder_noise;
  d.gyro_bias = draw(r.gyro_drift_deg_per_min) * std::numbers::pi / 180.0 / 60.0;
  d.gyro_noise = r.gyro_noise;
  if (r.range_noise_sd > 0.0) {
    d.range_noise_sd = r.range_noise_sd;
    // Its own stream per reality seed (and per vehicle file's seed, so a
    // fleet's robots differ): seeded from the file alone, every reality
    // seed gave one scan noise.
    d.range_noise_seed = seed * 0xBF58476D1CE4E5B9ULL + vehicle.range_sensors.seed;
  }
  d.range_spurious_fraction = r.range_spurious_fraction;
  d.range_dropout_fraction = r.range_dropout_fraction;
  d.command_jitter_s = r.command_jitter_s;
  d.state_jitter_s = r.state_jitter_s;
  if (track != nullptr) {
    // On the corridor: anywhere along the lap, across up to its half width.
    const double half = 0.5 * track->config().corridor_width;
    for (int i = 0; i < r.floor_patches.count; ++i) {
      const double along = draw.Uniform(0.0, track->length());
      const double across = draw.Uniform(-half, half);
      const Vec2 t = track->TangentAt(along);
      const Vec2 c = track->PointAt(along) + across * Vec2(-t.y(), t.x());
      FloorPatch p;
      p.x = c.x();
      p.y = c.y();
      p.radius = std::max(0.01, draw(r.floor_patches.radius));
      p.traction = std::clamp(draw(r.floor_patches.traction), 0.1, 1.0);
      d.floor_patches.push_back(p);
    }
  }
  const BlimpRealityConfig& b = reality.blimp;
  const double wind = std::max(0.0, draw(b.wind_speed));
  const double direction = draw(b.wind_direction_deg) * std::numbers::pi / 180.0;
  d.wind_x += wind * std::cos(direction);
  d.wind_y += wind * std::sin(direction);
  d.gust_rms = std::max(d.gust_rms, draw(b.gust_rms));
  d.volume *= 1.0 + draw(b.buoyancy_error);
  d.payload_mass += std::max(0.0, draw(b.gondola_extra_mass));
  d.clock_offset_s = draw(reality.clock.offset_s);
  d.clock_drift_ppm = draw(reality.clock.drift_ppm);
  // Drawn last: a file without map error draws everything above as before.
  const MapErrorConfig& map = r.map_error;
  if (track != nullptr &&
      (map.post_sd > 0.0 || map.wall_corner_sd > 0.0 || map.layout_rotation_deg.sd > 0.0 ||
       map.layout_rotation_deg.mean != 0.0)) {
    const double turn = draw(map.layout_rotation_deg) * std::numbers::pi / 180.0;
    const Vec2 pivot = track->StartPosition();
    const double c = std::cos(turn), s = std::sin(turn);
    const auto rotated = [&](const Vec2& p) {
      const Vec2 v = p - pivot;
      return Vec2(pivot.x() + c * v.x() - s * v.y(), pivot.y() + s * v.x() + c * v.y());
    };
    // A corner shared by two walls moves once: both walls keep meeting there.
    std::vector<std::pair<Vec2, Vec2>> corners;  // file's point, true point
    const auto corner = [&](const Vec2& p) {
      for (const auto& [file, moved] : corners) {
        if (file == p) return moved;
      }
      const Spread offset{0.0, map.wall_corner_sd};
      const double dx = draw(offset);
      const Vec2 moved = rotated(p) + Vec2(dx, draw(offset));
      corners.emplace_back(p, moved);
      return moved;
    };
    for (const Segment2& wall : track->walls()) {
      const Vec2 a = corner(wall.a);
      d.true_walls.push_back({a, corner(wall.b)});
    }
    for (const CircleObstacle& post : track->round_obstacles()) {
      const Spread offset{0.0, map.post_sd};
      const double dx = draw(offset);
      d.true_posts.push_back({rotated(post.center) + Vec2(dx, draw(offset)), post.radius});
    }
  }
  return d;
}

const std::vector<Segment2>& TrueWalls(const DrawnReality& reality, const Track& track) {
  return reality.true_walls.empty() ? track.walls() : reality.true_walls;
}

const std::vector<CircleObstacle>& TruePosts(const DrawnReality& reality, const Track& track) {
  return reality.true_posts.empty() ? track.round_obstacles() : reality.true_posts;
}

DrawnReality VehicleReality(const VehicleConfig& vehicle, const Track* track) {
  if (vehicle.reality.empty()) return NominalReality(vehicle);
  const RealityConfig reality = LoadReality(vehicle.reality);
  return DrawReality(reality, vehicle.reality_seed.value_or(reality.seed), vehicle, track);
}

}  // namespace haptel
