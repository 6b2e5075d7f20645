#pragma once
/// @file A simulated vehicle's hidden truth: its *reality* file
/// (config/realities/NAME.yaml) and the values drawn from it for one run.
///
/// The operator side predicts with the vehicle file's nominal model; the
/// simulated vehicle runs a reality that differs from it the way a real one
/// does: tread gains and their asymmetry, skid (an effective track width
/// wider than the geometric one and a sideways slip growing with the turn
/// rate), the motor lag, the battery sagging over the run, floor patches of
/// lower traction, odometry, gyro and range noise, command and state
/// jitter, a clock offset and drift; for the blimp a steady wind and gusts,
/// buoyancy off by a few percent and a heavier gondola. Each is a *spread*
/// (mean and standard deviation), drawn once per run from a seed
/// (DrawReality), so one seed repeats a run exactly and another seed is
/// another robot of the same make.
///
/// Only the vehicle reads its reality (haptel-vehicle --reality, a vehicle
/// file's `reality:`, the robot stepped in the operator's process); the
/// operator side never does. What was drawn goes to the truth record's
/// header (record/truth_record.hpp), under the names DrawnReality::ForEach
/// gives, for scoring after the run.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "haptel/config/archive.hpp"
#include "haptel/config/track.hpp"

namespace haptel {

struct VehicleConfig;

/// A value drawn once per run: normal about `mean` with standard deviation
/// `sd`, clipped to mean ± 2 sd (no wild draw); sd 0 is the mean exactly.
struct Spread {
  double mean = 0.0;
  double sd = 0.0;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(mean), config::Range{-1e6, 1e6});
    a->Visit(HAPTEL_NVP(sd), config::Range{0.0, 1e6});
  }
  void ValidateOrThrow() const;
  bool operator==(const Spread&) const = default;
};

/// Floor patches of lower traction (a dusty tile, a rug's edge): `count`
/// discs placed from the seed on the track's corridor; on one, only
/// `traction` of the treads' speed moves the body (the rest slips; the
/// encoders still count it).
struct FloorPatchesConfig {
  int count = 0;
  Spread radius{0.25, 0.0};   ///< m
  Spread traction{1.0, 0.0};  ///< fraction, in (0, 1]

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(count), config::Range{0, 64});
    a->Visit(HAPTEL_NVP(radius));
    a->Visit(HAPTEL_NVP(traction));
  }
  void ValidateOrThrow() const;
};

/// The track as it was really laid out against its file (the map the operator
/// side localises on): no lab lays boards and posts where the drawing puts
/// them. Every draw is independent, in the track frame, and clipped at 2 sd.
struct MapErrorConfig {
  /// Each round post's centre (gate posts and obstacles), per axis, m.
  double post_sd = 0.0;
  /// Each wall corner (the walls' polylines stay closed: a board shifted
  /// and turned a little), per axis, m.
  double wall_corner_sd = 0.0;
  /// The whole layout turned about the start position, degrees (the first
  /// board laid along a slightly wrong line).
  Spread layout_rotation_deg{0.0, 0.0};

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(post_sd), config::Range{0.0, 0.5});
    a->Visit(HAPTEL_NVP(wall_corner_sd), config::Range{0.0, 0.5});
    a->Visit(HAPTEL_NVP(layout_rotation_deg));
  }
  void ValidateOrThrow() const;
};

/// The tank robot's reality, relative to its vehicle file's nominal drive
/// (factors of 1 and zeros: the file's model exactly).
struct RobotRealityConfig {
  /// Both treads' speed as a factor of the file's gains (motors that differ
  /// from their datasheet).
  Spread tread_gain{1.0, 0.0};
  /// The treads' relative difference: left × (1 + a/2), right × (1 − a/2).
  Spread tread_asymmetry{0.0, 0.0};
  /// Skid: the effective track width over the geometric one (Mandow et al.
  /// 2007's expansion factor; 1.2–1.6 for a skid-steer on a hard floor).
  Spread track_width_factor{1.0, 0.0};
  /// Skid: sideways slip speed (outward of the turn) per forward speed ×
  /// yaw rate, s/rad.
  Spread lateral_slip{0.0, 0.0};
  /// The motors' time constant as a factor of the file's.
  Spread motor_time_constant_factor{1.0, 0.0};
  /// Speed lost to the battery, a fraction per minute of the run (the
  /// speed never falls below half).
  Spread battery_fade_per_min{0.0, 0.0};
  FloorPatchesConfig floor_patches;
  /// The state's pose is the robot's own estimate (gyro heading, tread
  /// encoder odometry along it), not the simulator's truth. Off: the state
  /// reports the truth, as the twin always did (`none`).
  bool odometry = false;
  /// Each tread encoder's speed reading: relative standard deviation per tick.
  double encoder_noise = 0.0;
  /// The gyro's bias (rad/s drawn from deg/min) and its white noise (rad/s).
  Spread gyro_drift_deg_per_min{0.0, 0.0};
  double gyro_noise = 0.0;
  /// Each range reading's noise (m); 0: the vehicle file's range_sensors.noise_sd.
  double range_noise_sd = 0.0;
  /// The fraction of beams that read a false echo: a range uniform in
  /// [0, max_range) whatever is there (crosstalk, a shoe, dust on the window).
  double range_spurious_fraction = 0.0;
  /// The fraction of beams that meet something and yet read max_range (no
  /// echo: a dark or glancing surface).
  double range_dropout_fraction = 0.0;
  /// Walls and posts displaced from the track file; the robot's beams and
  /// bumpers meet them where they really are.
  MapErrorConfig map_error;
  /// A new command takes effect after a delay drawn uniformly in [0, this] s
  /// (the brick's command loop).
  double command_jitter_s = 0.0;
  /// A state carries what the robot measured up to this long before it is
  /// sent, drawn uniformly per state (s; its stamp says when it measured).
  double state_jitter_s = 0.0;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(tread_gain));
    a->Visit(HAPTEL_NVP(tread_asymmetry));
    a->Visit(HAPTEL_NVP(track_width_factor));
    a->Visit(HAPTEL_NVP(lateral_slip));
    a->Visit(HAPTEL_NVP(motor_time_constant_factor));
    a->Visit(HAPTEL_NVP(battery_fade_per_min));
    a->Visit(HAPTEL_NVP(floor_patches));
    a->Visit(HAPTEL_NVP(odometry));
    a->Visit(HAPTEL_NVP(encoder_noise), config::Range{0.0, 0.5});
    a->Visit(HAPTEL_NVP(gyro_drift_deg_per_min));
    a->Visit(HAPTEL_NVP(gyro_noise), config::Range{0.0, 1.0});
    a->Visit(HAPTEL_NVP(range_noise_sd), config::Range{0.0, 1.0});
    a->Visit(HAPTEL_NVP(range_spurious_fraction), config::Range{0.0, 0.5});
    a->Visit(HAPTEL_NVP(range_dropout_fraction), config::Range{0.0, 0.5});
    a->Visit(HAPTEL_NVP(map_error));
    a->Visit(HAPTEL_NVP(command_jitter_s), config::Range{0.0, 0.5});
    a->Visit(HAPTEL_NVP(state_jitter_s), config::Range{0.0, 0.04});
  }
  void ValidateOrThrow() const;
};

/// The blimp's reality, relative to its vehicle file's airship.
struct BlimpRealityConfig {
  Spread wind_speed{0.0, 0.0};          ///< m/s, steady, horizontal
  Spread wind_direction_deg{0.0, 0.0};  ///< where it blows to, counter-clockwise from +x
  /// m/s, the airship model's gusts: at least this (the vehicle file's when larger).
  Spread gust_rms{0.0, 0.0};
  /// Buoyancy off by this fraction (the helium's purity, the temperature):
  /// the envelope's volume × (1 + this).
  Spread buoyancy_error{0.0, 0.0};
  Spread gondola_extra_mass{0.0, 0.0};  ///< kg on the payload

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(wind_speed));
    a->Visit(HAPTEL_NVP(wind_direction_deg));
    a->Visit(HAPTEL_NVP(gust_rms));
    a->Visit(HAPTEL_NVP(buoyancy_error));
    a->Visit(HAPTEL_NVP(gondola_extra_mass));
  }
  void ValidateOrThrow() const;
};

/// The vehicle's clock against the operator host's: the state's stamps are
/// offset and drift (any vehicle family).
struct ClockRealityConfig {
  Spread offset_s{0.0, 0.0};
  Spread drift_ppm{0.0, 0.0};

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(offset_s));
    a->Visit(HAPTEL_NVP(drift_ppm));
  }
  void ValidateOrThrow() const;
};

struct RealityConfig {
  std::filesystem::path file;
  std::string name;  ///< "lab": what the run's JSON names
  /// The draws' seed unless the vehicle is given another (--reality-seed).
  uint64_t seed = 1;
  RobotRealityConfig robot;
  BlimpRealityConfig blimp;
  ClockRealityConfig clock;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(name), config::Required{});
    a->Visit(HAPTEL_NVP(seed), config::Range{0, 2147483647.0});
    a->Visit(HAPTEL_NVP(robot), config::IfPresent{});
    a->Visit(HAPTEL_NVP(blimp), config::IfPresent{});
    a->Visit(HAPTEL_NVP(clock), config::IfPresent{});
  }
  /// Throws ConfigFieldError naming the first field out of range.
  void ValidateOrThrow() const;
};

/// Loads and validates a reality file (strict: unknown keys are errors
/// naming file, key and line).
RealityConfig LoadReality(const std::filesystem::path& file);

/// The shipped reality `name_or_file` means: a bare name (no '/', no
/// extension) is config/realities/NAME.yaml, anything else a path.
std::filesystem::path RealityFile(const std::string& name_or_file);

/// A floor patch as drawn (track frame).
struct FloorPatch {
  double x = 0.0, y = 0.0;  ///< m
  double radius = 0.0;      ///< m
  double traction = 1.0;
};

/// One run's reality: every value drawn, absolute (the file's nominal
/// values applied), under the names the truth record's header uses — the
/// values an estimator is scored against.
struct DrawnReality {
  std::string name;
  uint64_t seed = 0;
  // The robot.
  double left_gain = 1.0;  ///< the treads' true gains (the file's × drawn)
  double right_gain = 1.0;
  double track_width = 0.16;            ///< m, the geometric (the file's)
  double effective_track_width = 0.16;  ///< m, what the yaw rate follows
  double lateral_slip_s = 0.0;          ///< s/rad
  double motor_time_constant = 0.08;    ///< s
  double battery_fade_per_min = 0.0;
  double odometry = 0.0;  ///< 1: the state's pose is the robot's odometry; 0: the truth
  double encoder_noise = 0.0;
  double gyro_bias = 0.0;   ///< rad/s
  double gyro_noise = 0.0;  ///< rad/s
  double range_noise_sd = 0.0;
  /// The range noise's seed: the vehicle file's while the noise is the
  /// file's (none: the twin's scans), the reality's seed mixed with it once
  /// the reality draws its own (another reality seed, other noise). Not a
  /// truth figure: not in ForEach.
  uint64_t range_noise_seed = 1;
  double range_spurious_fraction = 0.0;
  double range_dropout_fraction = 0.0;
  double command_jitter_s = 0.0;
  double state_jitter_s = 0.0;
  std::vector<FloorPatch> floor_patches;
  /// The track as it truly stands when the reality displaces it from the
  /// file (map_error): every wall (Track::walls' order) and round post
  /// (Track::round_obstacles' order) where it really is. Both empty: the
  /// file's own (TrueWalls / TruePosts choose).
  std::vector<Segment2> true_walls;
  std::vector<CircleObstacle> true_posts;
  // The blimp.
  double wind_x = 0.0;  ///< m/s, world frame
  double wind_y = 0.0;
  double gust_rms = 0.0;
  double volume = 0.0;        ///< m³, the true envelope (buoyancy)
  double payload_mass = 0.0;  ///< kg, with the heavier gondola
  // The clock: vehicle = operator + offset + drift × (operator − start).
  double clock_offset_s = 0.0;
  double clock_drift_ppm = 0.0;

  /// Calls visit(name, value) for every number above but the patches, walls and posts, in
  /// this order: the truth record's header writes and reads them so.
  template <typename Self, typename Visit>
  static void ForEach(Self& self, Visit&& visit) {
    visit("left_gain", self.left_gain);
    visit("right_gain", self.right_gain);
    visit("track_width", self.track_width);
    visit("effective_track_width", self.effective_track_width);
    visit("lateral_slip_s", self.lateral_slip_s);
    visit("motor_time_constant", self.motor_time_constant);
    visit("battery_fade_per_min", self.battery_fade_per_min);
    visit("odometry", self.odometry);
    visit("encoder_noise", self.encoder_noise);
    visit("gyro_bias", self.gyro_bias);
    visit("gyro_noise", self.gyro_noise);
    visit("range_noise_sd", self.range_noise_sd);
    visit("range_spurious_fraction", self.range_spurious_fraction);
    visit("range_dropout_fraction", self.range_dropout_fraction);
    visit("command_jitter_s", self.command_jitter_s);
    visit("state_jitter_s", self.state_jitter_s);
    visit("wind_x", self.wind_x);
    visit("wind_y", self.wind_y);
    visit("gust_rms", self.gust_rms);
    visit("volume", self.volume);
    visit("payload_mass", self.payload_mass);
    visit("clock_offset_s", self.clock_offset_s);
    visit("clock_drift_ppm", self.clock_drift_ppm);
  }
};

/// Draws one run's reality for `vehicle` (its nominal drive and airship) from
/// `seed`; floor patches on `track`'s corridor (null: none placed, e.g. a
/// blimp). The same arguments give the same draw.
DrawnReality DrawReality(const RealityConfig& reality, uint64_t seed, const VehicleConfig& vehicle,
                         const Track* track);

/// The walls and round posts where they truly stand in `reality`: its
/// displaced ones, else `track`'s own.
const std::vector<Segment2>& TrueWalls(const DrawnReality& reality, const Track& track);
const std::vector<CircleObstacle>& TruePosts(const DrawnReality& reality, const Track& track);

/// The reality of the vehicle file alone (no reality file): its nominal
/// model exactly, named "none", seed 0.
DrawnReality NominalReality(const VehicleConfig& vehicle);

/// What a simulated vehicle runs: its `reality` file (LoadReality: a
/// ConfigError naming file and key) drawn with its reality_seed, else the
/// file's seed; NominalReality when it names none.
DrawnReality VehicleReality(const VehicleConfig& vehicle, const Track* track);

}  // namespace haptel
