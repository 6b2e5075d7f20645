#pragma once
/// @file Any ROS 2 robot as a Haptel vehicle (kind ros2), through its topics
/// alone: no ROS 2 installation, the wire types are generated from
/// link/idl/ros2.idl and spoken by a Fast DDS participant of its own on the
/// robot's domain (Ros2Config).
///
/// - Motor levels become geometry_msgs/Twist on `cmd_vel`, as a differential
///   drive: each side's level is a wheel speed (level / speed_levels ×
///   drive.max_speed), v their mean and ω their difference over
///   drive.track_width. RELIABLE, as ROS 2 subscribers ask by default. Sent
///   when the command changes and at ros2.cmd_rate_hz while it holds.
/// - nav_msgs/Odometry is the pose, its frame's origin placed at the track's
///   start (where the robot was put down); the twist is the speed and yaw rate.
/// - sensor_msgs/CompressedImage (JPEG or PNG) is the camera (MakeCamera).
///   An image's size is read from its header first (ImageProblem): one
///   larger than kMaxImageSide a side, or of another format, is counted and
///   dropped undecoded, said once.
/// - sensor_msgs/LaserScan is the range field of the state (RangeScanFor),
///   what shared control looks ahead with, as the simulated robot's range
///   sensors are. The newest scan counts; one older than ros2.odom_timeout_s
///   is withdrawn (count 0: nothing may be concluded), so the operator is
///   never steered by what the robot saw a while ago.
///
/// Readers are BEST_EFFORT, so they match publishers of either reliability.
/// Odometry that stops for ros2.odom_timeout_s after it came is a fault (the
/// robot is silent), and the robot is sent zero velocity; odometry that
/// comes back clears it. A non-finite odometry sample is counted and dropped.
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/core/range_scan.hpp"
#include "haptel/vehicles/adapter.hpp"
#include "haptel/video/camera_source.hpp"

namespace haptel::vehicles {

/// What went over the ROS 2 topics so far.
struct Ros2Counters {
  uint64_t twists_sent = 0;
  uint64_t odom_received = 0;
  uint64_t odom_dropped = 0;  ///< non-finite pose or twist
  uint64_t images_received = 0;
  uint64_t images_dropped = 0;  ///< not decodable
  uint64_t images_refused =
      0;  ///< too large, or neither JPEG nor PNG, by its header: never decoded (ImageProblem)
  uint64_t scans_received = 0;
  uint64_t scans_dropped =
      0;  ///< a scan whose geometry makes no sense (ScanProblem); the first is said
};

class Ros2Robot final : public VehicleAdapter {
 public:
  /// Joins the robot's domain (config.ros2.domain_id, on config.link's
  /// interfaces and peers, without Haptel's security or faults). Throws
  /// std::runtime_error when DDS refuses, ConfigFieldError for a bad config.
  Ros2Robot(const VehicleConfig& config, const Track& track);
  ~Ros2Robot() override;
  Ros2Robot(const Ros2Robot&) = delete;
  Ros2Robot& operator=(const Ros2Robot&) = delete;

  void SetMotors(const models::MotorLevels& levels) override;
  /// Zero velocity, sent at once.
  void Stop() override;
  /// Takes the odometry that came, sends the twist when due.
  void Update(double dt) override;
  AdapterState State() const override;

  /// The robot's camera topic as a camera source (frames resized to
  /// config.camera's size); null when ros2.image is empty. It shares the
  /// adapter's participant and may outlive the adapter.
  std::unique_ptr<video::CameraSource> MakeCamera();

  Ros2Counters Counters() const;

  /// The twist a differential drive's levels mean: {v m/s, ω rad/s}.
  static std::array<double, 2> TwistFor(const models::MotorLevels& levels,
                                        const TreadDriveConfig& drive);

  /// A sensor_msgs/LaserScan as the state's range field (range_scan.hpp),
  /// the laser taken to be at the robot's centre facing forward (a frame_id
  /// with an offset is not resolved: there is no tf here).
  ///
  /// A scan of up to kMaxRangeBeams beams is copied beam for beam. A longer
  /// one is cut into sectors of k = ceil(n / kMaxRangeBeams) neighbouring
  /// beams, each read as its nearest valid range at the angle of its middle
  /// (the last sector may hold fewer beams; it is given the same width), so
  /// an obstacle any beam of a sector saw is kept.
  ///
  /// Readings follow REP 117: NaN (no reading) and +inf (nothing within
  /// range) meet nothing; -inf (something nearer than the sensor can tell)
  /// is a hit at range_min; a finite reading outside [range_min, range_max]
  /// is invalid and dropped. A beam or sector that met nothing reads
  /// range_max, which is the scan's range_max.
  ///
  /// A scan whose geometry makes no sense (ScanProblem, its angle_max
  /// taken as its last beam's) gives count 0.
  static RangeScan RangeScanFor(double angle_min, double angle_increment, double range_min,
                                double range_max, std::span<const float> ranges);

  /// The largest image side decoded, px: 4K UHD's 3840 fits; 4096 x 4096
  /// decodes to 50 MB, where a 10 000-pixel square would take 300 MB.
  static constexpr int kMaxImageSide = 4096;
  /// Why a CompressedImage's bytes are not decoded, "" when they may be:
  /// neither JPEG nor PNG (its size unknown until decoded), or a size read
  /// from its header (JpegFrameSize, PngFrameSize) over kMaxImageSide.
  static std::string ImageProblem(std::span<const uint8_t> data);

  /// What makes a scan's geometry impossible, "" when nothing does: no
  /// beams; an angle or limit not finite; angle_min or angle_max more than a
  /// full turn from the heading; an increment of zero over several beams, or
  /// of the sign opposite to angle_max − angle_min; beams spanning more than
  /// a full turn (and one beam); range_max not in (0, 10 km], range_min not
  /// in [0, range_max).
  static std::string ScanProblem(double angle_min, double angle_max, double angle_increment,
                                 double range_min, double range_max, size_t beams);

  /// The participant and endpoints on the robot's domain (shared with the camera).
  struct Graph;

 private:
  void SendTwist(double v, double w);

  VehicleConfig config_;
  std::shared_ptr<Graph> graph_;
  double start_x_ = 0.0;
  double start_y_ = 0.0;
  double start_heading_ = 0.0;
  AdapterState state_;
  double v_ = 0.0;  ///< commanded twist
  double w_ = 0.0;
  double since_twist_s_ = 0.0;
  bool twist_due_ = true;
  int64_t last_odom_ns_ = 0;        ///< 0: none yet
  int64_t last_scan_ns_ = 0;        ///< 0: none yet
  bool scan_problem_said_ = false;  ///< the first impossible scan is said, the rest counted
};

}  // namespace haptel::vehicles
