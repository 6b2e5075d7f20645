#pragma once
/// @file A vehicle node's configuration.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "haptel/config/airship.hpp"
#include "haptel/config/archive.hpp"
#include "haptel/config/link.hpp"
#include "haptel/config/servo.hpp"
#include "haptel/config/vehicle_kinds.hpp"
#include "haptel/core/camera_aim.hpp"
#include "haptel/core/range_scan.hpp"

namespace haptel {

/// Differential drive of the Lego-style tank: each motor takes a signed speed
/// level, as the brick does; commands are quantised to these levels.
struct TreadDriveConfig {
  int speed_levels = 8;               ///< levels in each direction
  double max_speed = 0.3;             ///< tread speed at the top level, m/s
  double track_width = 0.16;          ///< distance between treads, m
  double motor_time_constant = 0.08;  ///< first-order motor lag, s
  double left_gain = 1.0;             ///< per-motor gain: uneven turning
  double right_gain = 0.95;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(speed_levels), config::Range{1, 1000});
    a->Visit(HAPTEL_NVP(max_speed), config::Range{0.01, 10.0});
    a->Visit(HAPTEL_NVP(track_width), config::Range{0.02, 5.0});
    a->Visit(HAPTEL_NVP(motor_time_constant), config::Range{0.0, 5.0});
    a->Visit(HAPTEL_NVP(left_gain), config::Range{0.5, 1.5});
    a->Visit(HAPTEL_NVP(right_gain), config::Range{0.5, 1.5});
  }

  /// Throws ConfigFieldError unless every value is in range.
  void ValidateOrThrow() const;
};

/// The simulated robot's range sensors: `beams` fanned evenly over `fov_deg`
/// about the heading (a ring of sonars or a planar scanner's sectors), each
/// reading the distance from the robot's centre to the nearest wall or post
/// along it, with Gaussian noise, capped at `max_range` (nothing seen).
/// What the shared-control interfaces (gesture-shared) look ahead with.
struct RangeSensorConfig {
  int beams = 31;           ///< 0: none; at most kMaxRangeBeams (core/range_scan.hpp)
  double fov_deg = 180.0;   ///< from the first beam to the last, centred on the heading
  double max_range = 1.5;   ///< m
  double noise_sd = 0.005;  ///< m, standard deviation of each reading's noise
  unsigned seed = 1;        ///< the noise's seed: a run repeats exactly

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(beams), config::Range{0, kMaxRangeBeams});
    a->Visit(HAPTEL_NVP(fov_deg), config::Range{0.0, 360.0});
    a->Visit(HAPTEL_NVP(max_range), config::Range{0.05, 50.0});
    a->Visit(HAPTEL_NVP(noise_sd), config::Range{0.0, 1.0});
    a->Visit(HAPTEL_NVP(seed), config::Range{0, 2147483647.0});
  }

  /// Throws ConfigFieldError unless every value is in range.
  void ValidateOrThrow() const;
};

struct BodyConfig {
  double radius = 0.11;  ///< collision circle, m
  /// Contacts within this angle of straight ahead press the front bumper.
  double bumper_half_angle_deg = 70.0;
  /// Contacts within this angle of straight ahead press both switches.
  double bumper_both_deg = 8.0;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(radius), config::Range{0.01, 5.0});
    a->Visit(HAPTEL_NVP(bumper_half_angle_deg), config::Range{1.0, 90.0});
    a->Visit(HAPTEL_NVP(bumper_both_deg), config::Range{0.0, 45.0});
  }

  /// Throws ConfigFieldError unless every value is in range.
  void ValidateOrThrow() const;
};

/// Where a vehicle's camera frames come from.
enum class CameraSourceKind {
  kSynthetic,  ///< rendered from the simulated track (video::SyntheticCamera)
  kDevice,     ///< a V4L2 capture device
  kFile,       ///< a video file, played at rate_hz
};

/// "synthetic", "device" or "file", as written in the config file.
const char* CameraSourceName(CameraSourceKind kind);

/// How a vehicle's camera frames are compressed on the link.
enum class CameraCodec {
  kJpeg,  ///< every frame a JPEG (OpenCV): any frame decodes alone
  kH264,  ///< H.264 (libavcodec + libx264) tuned for latency; far fewer bits per frame
};

/// "jpeg" or "h264", as written in the config file and in each video sample.
const char* CameraCodecName(CameraCodec codec);

/// A servo output a camera's axis goes to (the blimp's servo controller);
/// channel -1: none (the key absent).
inline ServoChannelConfig NoServoChannel() {
  ServoChannelConfig c;
  c.channel = -1;
  return c;
}

/// The longest camera name: a DDS topic's path segment (link/families.hpp).
constexpr std::size_t kMaxCameraNameLength = 31;
/// The most cameras one vehicle carries (CameraStatus's bound).
constexpr int kMaxVehicleCameras = 8;

/// One camera of a vehicle (`camera:`, or each of `cameras:`). The first a
/// file lists is the driven camera: the driver's, on haptel/<vehicle>/video,
/// turned by the driving command where the vehicle has a head (the blimp's
/// camera_pan/tilt). Every other is its own stream on
/// haptel/<vehicle>/video/<name>, aimed by CameraCommands from its holder
/// within its pan/tilt/zoom ranges (link/families.hpp).
struct CameraConfig {
  /// Names its topics: [a-z0-9_-], 1 to 31 characters, unique on the vehicle.
  std::string name = "pilot";
  CameraSourceKind source = CameraSourceKind::kSynthetic;
  /// V4L2 device for source: device, a path ("/dev/video0") or an index ("0").
  std::string device;
  /// Video file for source: file (resolved against the config file's folder).
  std::filesystem::path file;
  bool loop = true;  ///< source: file: start again at the first frame after the last
  /// Frames per second published, for every source: a file is paced by this,
  /// not by its own frame rate; a device is asked for it.
  double rate_hz = 30.0;
  /// Published frame size; captured frames of another size are resized.
  int width = 640;
  int height = 480;
  double fov_deg = 55.0;  ///< horizontal, webcam-like
  CameraCodec codec = CameraCodec::kJpeg;
  int jpeg_quality = 80;  ///< codec: jpeg, 1..100
  /// codec: h264, the encoder's target bitrate (kbit/s) until the operator
  /// asks for another; its VBV buffer holds about one frame at this rate.
  int bitrate_kbps = 1000;
  double mount_height = 0.12;  ///< m above the floor
  /// Where it sits on the vehicle and where it looks at rest: m ahead of and
  /// left of the body's centre, degrees left of straight ahead (180: a rear
  /// camera) and up (negative: down). A blimp's camera hangs at its gondola:
  /// its height is the blimp's.
  double mount_forward = 0.0;
  double mount_left = 0.0;
  double mount_yaw_deg = 0.0;
  double mount_pitch_deg = 0.0;
  /// The link's capacity goes to the lowest number first (the driven camera: 0).
  int priority = 0;
  /// Its head's travel about the mount (degrees, positive: left, up) and
  /// its lens's zoom (1: none; the field of view is fov_deg at 1×, narrower
  /// by the zoom: ZoomedFovDeg). Equal ends: it does not pan or tilt.
  double pan_min_deg = 0.0;
  double pan_max_deg = 0.0;
  double tilt_min_deg = 0.0;
  double tilt_max_deg = 0.0;
  double zoom_max = 1.0;
  /// The blimp's servo outputs that move its pan, tilt and zoom (each a
  /// servo channel: channel, min_us, neutral_us, max_us, reversed; command
  /// -1..1 over the axis's range, zoom 1× at -1). Absent: not driven by a
  /// servo (a simulator's head, or an axis it lacks).
  ServoChannelConfig pan_servo = NoServoChannel();
  ServoChannelConfig tilt_servo = NoServoChannel();
  ServoChannelConfig zoom_servo = NoServoChannel();

  /// Its ranges in radians (core/camera_aim.hpp).
  CameraRange Range() const;

  template <typename Archive>
  void Serialize(Archive* a) {
    using Source = CameraSourceKind;
    a->Visit(HAPTEL_NVP(name));
    a->Visit(HAPTEL_NVP(source), config::Choice<Source>{{{Source::kSynthetic, "synthetic"},
                                                         {Source::kDevice, "device"},
                                                         {Source::kFile, "file"}}});
    a->Visit(HAPTEL_NVP(device));
    a->Visit(HAPTEL_NVP(file), config::RelativeToFile{});
    a->Visit(HAPTEL_NVP(loop));
    a->Visit(HAPTEL_NVP(rate_hz), config::Range{1.0, 120.0});
    a->Visit(HAPTEL_NVP(width), config::Range{16, 4096});
    a->Visit(HAPTEL_NVP(height), config::Range{16, 4096});
    a->Visit(HAPTEL_NVP(fov_deg), config::Range{10.0, 170.0});
    a->Visit(HAPTEL_NVP(codec), config::Choice<CameraCodec>{
                                    {{CameraCodec::kJpeg, "jpeg"}, {CameraCodec::kH264, "h264"}}});
    a->Visit(HAPTEL_NVP(jpeg_quality), config::Range{1, 100});
    a->Visit(HAPTEL_NVP(bitrate_kbps), config::Range{50, 50000});
    a->Visit(HAPTEL_NVP(mount_height), config::Range{0.01, 5.0});
    a->Visit(HAPTEL_NVP(mount_forward), config::Range{-50.0, 50.0});
    a->Visit(HAPTEL_NVP(mount_left), config::Range{-50.0, 50.0});
    a->Visit(HAPTEL_NVP(mount_yaw_deg), config::Range{-180.0, 180.0});
    a->Visit(HAPTEL_NVP(mount_pitch_deg), config::Range{-90.0, 90.0});
    a->Visit(HAPTEL_NVP(priority), config::Range{0, 100});
    a->Visit(HAPTEL_NVP(pan_min_deg), config::Range{-180.0, 180.0});
    a->Visit(HAPTEL_NVP(pan_max_deg), config::Range{-180.0, 180.0});
    a->Visit(HAPTEL_NVP(tilt_min_deg), config::Range{-90.0, 90.0});
    a->Visit(HAPTEL_NVP(tilt_max_deg), config::Range{-90.0, 90.0});
    a->Visit(HAPTEL_NVP(zoom_max), config::Range{1.0, 50.0});
    a->Visit(HAPTEL_NVP(pan_servo), config::IfPresent{});
    a->Visit(HAPTEL_NVP(tilt_servo), config::IfPresent{});
    a->Visit(HAPTEL_NVP(zoom_servo), config::IfPresent{});
  }

  /// Throws ConfigFieldError unless every value is in range, `device` (when
  /// set) is a V4L2 path or index, the source has the device or file it
  /// needs, the name suits a topic, each range's ends are in order and
  /// each servo channel given is valid.
  void ValidateOrThrow() const;
};

/// The robot's CAN bus (kinds can-robot and can-robot-sim): two ODrive motor
/// controllers (CAN Simple protocol, firmware 0.5.x), one per wheel, and the
/// bumper I/O node (vehicles/CAN.md).
struct CanConfig {
  std::string interface = "can0";  ///< SocketCAN interface (can-robot)
  int left_node = 1;               ///< ODrive node ids, 0..63, all distinct
  int right_node = 2;
  int io_node = 3;  ///< the bumper I/O node
  /// The right motor is mounted mirrored: positive turns drive it backwards.
  bool right_reversed = true;
  /// Wheel velocity of each speed level 1..drive.speed_levels (turn/s,
  /// increasing); the negative levels are the same backwards.
  std::vector<double> level_turns_per_s{0.2, 0.4, 0.6, 0.8, 1.0, 1.2, 1.4, 1.6};
  double wheel_circumference = 0.1885;  ///< m per wheel turn (speed from the encoders)
  double command_rate_hz = 100.0;       ///< velocity set-points sent per second
  /// The nodes' heartbeat period (ODrive axis.config.can.heartbeat_rate_ms);
  /// a node silent for 3 periods stops the robot.
  double heartbeat_period_s = 0.03;
  /// The simulated ODrives' velocity ramp (turn/s², vel_ramp_rate).
  double vel_ramp_rate = 8.0;
  /// Folder for the candump -L logs of each run (empty: no log).
  std::filesystem::path log_dir;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(interface));
    a->Visit(HAPTEL_NVP(left_node), config::Range{0, 63});
    a->Visit(HAPTEL_NVP(right_node), config::Range{0, 63});
    a->Visit(HAPTEL_NVP(io_node), config::Range{0, 63});
    a->Visit(HAPTEL_NVP(right_reversed));
    a->Visit(HAPTEL_NVP(level_turns_per_s));  // its length and order: ValidateOrThrow
    a->Visit(HAPTEL_NVP(wheel_circumference), config::Range{0.01, 5.0});
    a->Visit(HAPTEL_NVP(command_rate_hz), config::Range{10.0, 1000.0});
    a->Visit(HAPTEL_NVP(heartbeat_period_s), config::Range{0.005, 2.0});
    a->Visit(HAPTEL_NVP(vel_ramp_rate), config::Range{0.1, 1000.0});
    a->Visit(HAPTEL_NVP(log_dir), config::RelativeToFile{});
  }

  /// Throws ConfigFieldError naming the first field out of range; `levels`
  /// is drive.speed_levels (one velocity per level).
  void ValidateOrThrow(int levels = 8) const;
};

/// A ROS 2 robot (kind ros2), driven through its own topics: Haptel's
/// motor levels become geometry_msgs/Twist on `cmd_vel` (v and ω from
/// drive.max_speed and drive.track_width, as a differential drive), its
/// nav_msgs/Odometry is the pose (the odometry frame's origin placed at the
/// track's start) and its sensor_msgs/CompressedImage the video. Topic names
/// are ROS names ("/cmd_vel"); on DDS they carry ROS 2's "rt" prefix.
struct Ros2Config {
  int domain_id = 0;  ///< the robot's ROS_DOMAIN_ID
  std::string cmd_vel = "/cmd_vel";
  std::string odom = "/odom";
  /// Empty: no camera topic, the `camera` section's source is used instead.
  std::string image = "/camera/image_raw/compressed";
  /// sensor_msgs/LaserScan in, the robot's range sensors (the state's range
  /// field, what shared control looks ahead with). Empty: none.
  std::string scan = "/scan";
  /// Twist messages per second while driving (ROS bases stop without them).
  double cmd_rate_hz = 20.0;
  /// No odometry for this long, once it came: the robot is reported silent
  /// (a fault) and sent zero velocity.
  double odom_timeout_s = 0.5;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(domain_id), config::Range{0, 232});
    a->Visit(HAPTEL_NVP(cmd_vel));
    a->Visit(HAPTEL_NVP(odom));
    a->Visit(HAPTEL_NVP(image));
    a->Visit(HAPTEL_NVP(scan));
    a->Visit(HAPTEL_NVP(cmd_rate_hz), config::Range{1.0, 1000.0});
    a->Visit(HAPTEL_NVP(odom_timeout_s), config::Range{0.05, 60.0});
  }

  /// Throws ConfigFieldError naming the first field out of range or the
  /// topic name that is not a ROS name.
  void ValidateOrThrow() const;
};

/// The DDS topic of a ROS 2 topic name: "/cmd_vel" → "rt/cmd_vel".
std::string Ros2DdsTopic(const std::string& ros_name);

struct VehicleConfig {
  std::filesystem::path file;
  std::string name = "robot1";
  std::string kind = "sim-robot";  ///< a kind of the table (vehicle_kinds.hpp)
  std::filesystem::path world;     ///< track the simulator drives on
  double sim_rate_hz = 200.0;
  double state_rate_hz = 50.0;
  double watchdog_timeout_s = 0.2;  ///< no command for this long: made safe (0.2 s, as the blimp's)
  TreadDriveConfig drive;
  BodyConfig body;
  RangeSensorConfig
      range_sensors;  ///< the simulated robot's (other kinds report their own, or none)
  /// The driven camera (the file's `camera:`, or the first of `cameras:`).
  CameraConfig camera;
  /// Every other camera of `cameras:`, in the file's order.
  std::vector<CameraConfig> extra_cameras;
  /// The file wrote `cameras:` (errors name "cameras[i]"), not `camera:`.
  bool cameras_listed = false;
  LinkConfig link;
  CanConfig can;                ///< kinds that use kCanSection
  AirshipConfig airship;        ///< kinds that use kAirshipSection (the simulated airship)
  ServoControllerConfig servo;  ///< kinds that use kServoSection
  Ros2Config ros2;              ///< kinds that use kRos2Section
  /// A simulated kind's reality (config/reality.hpp): what the simulator
  /// runs instead of its nominal model. Only the vehicle reads it; the
  /// operator side passes the path on (haptel-vehicle --reality). Empty:
  /// none, the file's model exactly (the twin).
  std::filesystem::path reality;
  /// The reality's seed (haptel-vehicle --reality-seed); unset: the reality
  /// file's. Not in the file.
  std::optional<uint64_t> reality_seed;
  /// Where a simulated vehicle writes its truth record
  /// (record/truth_record.hpp): its drawn reality, then its true pose at
  /// the control rate on the host's CLOCK_MONOTONIC (haptel-vehicle
  /// --truth; `haptel run` sets one per run). Empty: none. Not in the file.
  std::filesystem::path truth_file;

  /// Every camera, the driven one first.
  std::vector<CameraConfig> Cameras() const;
  /// `servo` with the cameras' axes that have a servo (camera_channels).
  ServoControllerConfig ServoWithCameras() const;

  /// The kind's entry in the table (valid once validated).
  const VehicleKindInfo& Kind() const { return VehicleKind(kind); }
  VehicleFamily family() const { return Kind().family; }

  template <typename Archive>
  void Serialize(Archive* a) {
    // Every field but `file`. The kinds' sections are read when the file has
    // them, and validated by ValidateOrThrow when the kind uses them.
    a->Visit(HAPTEL_NVP(name), config::Required{});
    a->Visit(HAPTEL_NVP(kind));
    a->Visit(HAPTEL_NVP(world), config::RelativeToFile{});
    a->Visit(HAPTEL_NVP(sim_rate_hz), config::Range{50.0, 5000.0});
    a->Visit(HAPTEL_NVP(state_rate_hz), config::Range{1.0, 1000.0});
    a->Visit(HAPTEL_NVP(watchdog_timeout_s), config::Range{0.01, 10.0});
    a->Visit(HAPTEL_NVP(drive));
    a->Visit(HAPTEL_NVP(body));
    a->Visit(HAPTEL_NVP(range_sensors));
    // `camera:` one camera, or `cameras:` a list (LoadVehicle reads it).
    a->Visit(HAPTEL_NVP(camera), config::IfPresent{});
    a->Visit(HAPTEL_NVP(link));
    a->Visit(HAPTEL_NVP(can), config::IfPresent{});
    a->Visit(HAPTEL_NVP(airship), config::IfPresent{});
    a->Visit(HAPTEL_NVP(servo), config::IfPresent{});
    a->Visit(HAPTEL_NVP(ros2), config::IfPresent{});
    a->Visit(HAPTEL_NVP(reality), config::RelativeToFile{});
  }

  /// Throws ConfigFieldError unless the name suits DDS topic names, the kind
  /// is known, the rates are in range and every part is valid ("drive.*", ...).
  void ValidateOrThrow() const;

 private:
  /// Each camera (named "camera" or "cameras[i]"), their names unique, and
  /// each camera servo an output the controller has that no other uses.
  void ValidateCameras() const;
};

/// Loads and validates (VehicleConfig::ValidateOrThrow) a vehicle file
/// (strict: unknown keys are errors naming file, key and line).
VehicleConfig LoadVehicle(const std::filesystem::path& file);

/// The names of `vehicle`'s cameras, the driven one first ("pilot,surveillance").
std::string CameraNames(const VehicleConfig& vehicle);
/// Keeps only the cameras `names` lists (a camera set-up: which of the
/// vehicle's cameras stream), the driven one always among them. Returns ""
/// when done, else what is wrong (nothing is changed then): an unknown name
/// (saying the vehicle's), a name twice, or the driven camera left out.
std::string KeepOnlyCameras(VehicleConfig& vehicle, const std::vector<std::string>& names);

/// The longest vehicle name. The name is part of the DDS topic names
/// "haptel/<name>/<channel>" (channels: command, state, video), and RTPS
/// carries a topic name in at most 255 characters: 255 - 15 = 240.
constexpr std::size_t kMaxVehicleNameLength = 240;
/// What a vehicle name needs and `name` lacks, as the "expected …" part of an
/// error ("" when it is a good name): 1 to 240 letters, digits, '_' or '-'.
std::string VehicleNameProblem(const std::string& name);

}  // namespace haptel
