#include "haptel/vehicles/ros2_robot.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "haptel/config/error.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/log.hpp"
#include "haptel/link/participant.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/ros2/ros2.h"
#include "haptel/ros2/ros2PubSubTypes.h"
#include "haptel/video/codec.hpp"

namespace haptel::vehicles {

namespace dds = eprosima::fastdds::dds;
using geometry_msgs::msg::dds_::Twist_;
using nav_msgs::msg::dds_::Odometry_;
using sensor_msgs::msg::dds_::CompressedImage_;
using sensor_msgs::msg::dds_::LaserScan_;

namespace {

/// The robot's domain, on the vehicle's interfaces and peers; Haptel's own
/// security, faults and discovery server are not the robot's.
LinkConfig RobotLink(const VehicleConfig& config) {
  LinkConfig link = config.link;
  link.domain_id = config.ros2.domain_id;
  link.security.clear();
  link.security_identity = {};
  link.fault = {};
  link.discovery_server = {};
  return link;
}

/// BEST_EFFORT matches publishers of either reliability.
dds::DataReaderQos ReaderQos(int depth) {
  dds::DataReaderQos q = dds::DATAREADER_QOS_DEFAULT;
  q.reliability().kind = dds::BEST_EFFORT_RELIABILITY_QOS;
  q.durability().kind = dds::VOLATILE_DURABILITY_QOS;
  q.history().kind = dds::KEEP_LAST_HISTORY_QOS;
  q.history().depth = depth;
  return q;
}

double YawOf(const geometry_msgs::msg::dds_::Quaternion_& q) {
  return std::atan2(2.0 * (q.w() * q.z() + q.x() * q.y()),
                    1.0 - 2.0 * (q.y() * q.y() + q.z() * q.z()));
}

bool Finite(const Odometry_& o) {
  const auto& p = o.pose().pose();
  const auto& t = o.twist().twist();
  return std::isfinite(p.position().x()) && std::isfinite(p.position().y()) &&
         std::isfinite(p.orientation().x()) && std::isfinite(p.orientation().y()) &&
         std::isfinite(p.orientation().z()) && std::isfinite(p.orientation().w()) &&
         std::isfinite(t.linear().x()) && std::isfinite(t.angular().z());
}

}  // namespace

/// The participant on the robot's domain and its three endpoints, shared by
/// the adapter and its camera source (the last one gone deletes them).
struct Ros2Robot::Graph {
  explicit Graph(const VehicleConfig& config)
      : participant(RobotLink(config), "haptel-ros2-" + config.name) {
    using link::detail::MakeTopic;
    cmd_topic = MakeTopic<geometry_msgs::msg::dds_::Twist_PubSubType>(
        participant, Ros2DdsTopic(config.ros2.cmd_vel));
    odom_topic = MakeTopic<nav_msgs::msg::dds_::Odometry_PubSubType>(
        participant, Ros2DdsTopic(config.ros2.odom));
    // ROS 2's default for a subscriber: RELIABLE, VOLATILE, keep last 10.
    dds::DataWriterQos wq = dds::DATAWRITER_QOS_DEFAULT;
    wq.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
    wq.durability().kind = dds::VOLATILE_DURABILITY_QOS;
    wq.history().kind = dds::KEEP_LAST_HISTORY_QOS;
    wq.history().depth = 10;
    twist_writer = participant.publisher()->create_datawriter(cmd_topic, wq);
    odom_reader = participant.subscriber()->create_datareader(odom_topic, ReaderQos(10));
    if (!config.ros2.scan.empty()) {
      scan_topic = MakeTopic<sensor_msgs::msg::dds_::LaserScan_PubSubType>(
          participant, Ros2DdsTopic(config.ros2.scan));
      // A laser's driver publishes with the sensor-data profile (BEST_EFFORT);
      // only the newest scan is read.
      scan_reader = participant.subscriber()->create_datareader(scan_topic, ReaderQos(1));
    }
    if (!config.ros2.image.empty()) {
      image_topic = MakeTopic<sensor_msgs::msg::dds_::CompressedImage_PubSubType>(
          participant, Ros2DdsTopic(config.ros2.image));
      image_reader = participant.subscriber()->create_datareader(image_topic, ReaderQos(1));
    }
    if (twist_writer == nullptr || odom_reader == nullptr ||
        (image_topic != nullptr && image_reader == nullptr) ||
        (scan_topic != nullptr && scan_reader == nullptr)) {
      Delete();
      throw std::runtime_error("ros2: DDS refused an endpoint on the robot's topics");
    }
  }
  ~Graph() { Delete(); }
  void Delete() {
    if (scan_reader != nullptr) participant.subscriber()->delete_datareader(scan_reader);
    if (image_reader != nullptr) participant.subscriber()->delete_datareader(image_reader);
    if (odom_reader != nullptr) participant.subscriber()->delete_datareader(odom_reader);
    if (twist_writer != nullptr) participant.publisher()->delete_datawriter(twist_writer);
    for (dds::Topic* t : {scan_topic, image_topic, odom_topic, cmd_topic}) {
      if (t != nullptr) participant.get()->delete_topic(t);
    }
    scan_reader = nullptr;
    scan_topic = nullptr;
    image_reader = nullptr;
    odom_reader = nullptr;
    twist_writer = nullptr;
    image_topic = odom_topic = cmd_topic = nullptr;
  }

  link::Participant participant;
  dds::Topic* cmd_topic = nullptr;
  dds::Topic* odom_topic = nullptr;
  dds::Topic* image_topic = nullptr;
  dds::Topic* scan_topic = nullptr;
  dds::DataWriter* twist_writer = nullptr;
  dds::DataReader* odom_reader = nullptr;
  dds::DataReader* image_reader = nullptr;
  dds::DataReader* scan_reader = nullptr;
  std::atomic<uint64_t> twists_sent{0};
  std::atomic<uint64_t> odom_received{0};
  std::atomic<uint64_t> odom_dropped{0};
  std::atomic<uint64_t> images_received{0};
  std::atomic<uint64_t> images_dropped{0};
  std::atomic<uint64_t> images_refused{0};
  std::atomic<uint64_t> scans_received{0};
  std::atomic<uint64_t> scans_dropped{0};
};

namespace {

/// The robot's CompressedImage topic as a camera: waits up to two frame
/// periods for an image and takes the newest. Grab decodes it to the
/// configured size; GrabJpeg hands its bytes on undecoded, so that a JPEG
/// that already fits goes to the operator as the robot made it.
class Ros2Camera final : public video::CameraSource {
 public:
  Ros2Camera(std::shared_ptr<Ros2Robot::Graph> graph, const CameraConfig& config, std::string topic)
      : graph_(std::move(graph)), config_(config), topic_(std::move(topic)) {}

  bool Grab(const video::CameraPose& /*pose*/, cv::Mat& bgr_out) override {
    if (!GrabJpeg(jpeg_)) return false;
    if (!video::DecodeCameraJpeg(jpeg_, config_, decoded_, bgr_out)) {
      graph_->images_dropped.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    return true;
  }
  bool DeliversJpeg() const override { return true; }
  bool GrabJpeg(std::vector<uint8_t>& jpeg_out) override {
    dds::DataReader* reader = graph_->image_reader;
    const double wait_s = 2.0 / config_.rate_hz;
    if (!reader->wait_for_unread_message(eprosima::fastrtps::Duration_t(wait_s))) return false;
    bool got = false;
    dds::SampleInfo info;
    while (reader->take_next_sample(&image_, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      graph_->images_received.fetch_add(1, std::memory_order_relaxed);
      got = true;
    }
    if (!got) return false;
    // Its size from its header before anything decodes it: a 100-kB PNG can
    // say 10 000 x 10 000 pixels, 300 MB to decode.
    if (const std::string problem = Ros2Robot::ImageProblem(image_.data()); !problem.empty()) {
      graph_->images_refused.fetch_add(1, std::memory_order_relaxed);
      if (!refusal_said_) {
        refusal_said_ = true;
        log::Warn("ros2: an image on " + topic_ + " refused: " + problem +
                  "; such images are dropped undecoded and counted (said once)");
      }
      return false;
    }
    jpeg_out.assign(image_.data().begin(), image_.data().end());
    return true;
  }
  std::string Describe() const override { return "ros2 " + topic_; }

 private:
  std::shared_ptr<Ros2Robot::Graph> graph_;
  CameraConfig config_;
  std::string topic_;
  CompressedImage_ image_;
  std::vector<uint8_t> jpeg_;
  cv::Mat decoded_;
  bool refusal_said_ = false;
};

}  // namespace

Ros2Robot::Ros2Robot(const VehicleConfig& config, const Track& track)
    : config_(Validated(config)), graph_(std::make_shared<Graph>(config_)) {
  const Vec2 start = track.StartPosition();
  start_x_ = start.x();
  start_y_ = start.y();
  start_heading_ = track.StartHeading();
  state_.x = start_x_;
  state_.y = start_y_;
  state_.heading = start_heading_;
}

Ros2Robot::~Ros2Robot() {
  // Leave the robot standing still, whatever happened before.
  SendTwist(0.0, 0.0);
}

std::array<double, 2> Ros2Robot::TwistFor(const models::MotorLevels& levels,
                                          const TreadDriveConfig& drive) {
  const double per_level = drive.max_speed / std::max(1, drive.speed_levels);
  const double left = levels.left * per_level;
  const double right = levels.right * per_level;
  return {0.5 * (left + right), (right - left) / drive.track_width};
}

std::string Ros2Robot::ImageProblem(std::span<const uint8_t> data) {
  int width = 0;
  int height = 0;
  const char* format = "JPEG";
  if (!video::JpegFrameSize(data.data(), data.size(), width, height)) {
    format = "PNG";
    if (!video::PngFrameSize(data.data(), data.size(), width, height)) {
      return "neither a JPEG nor a PNG with its size in its header (" +
             std::to_string(data.size()) + " bytes)";
    }
  }
  if (width > kMaxImageSide || height > kMaxImageSide) {
    return std::string("a ") + format + " of " + std::to_string(width) + " x " +
           std::to_string(height) + " pixels; expected at most " + std::to_string(kMaxImageSide) +
           " a side";
  }
  return "";
}

std::string Ros2Robot::ScanProblem(double angle_min, double angle_max, double angle_increment,
                                   double range_min, double range_max, size_t beams) {
  constexpr double kTurn = 2.0 * M_PI;
  constexpr double kSlack = 1e-3;    // rad: float32 angles of a full turn round to a little over it
  constexpr double kMaxRange = 1e4;  // m: no range sensor sees 10 km
  const auto text = [](const char* what, double value) {
    char line[160];
    std::snprintf(line, sizeof line, "%s %.6g", what, value);
    return std::string(line);
  };
  if (beams == 0) return "no beams";
  if (!std::isfinite(angle_min)) return text("a non-finite angle_min:", angle_min);
  if (!std::isfinite(angle_max)) return text("a non-finite angle_max:", angle_max);
  if (!std::isfinite(angle_increment))
    return text("a non-finite angle_increment:", angle_increment);
  if (std::abs(angle_min) > kTurn + kSlack)
    return text("angle_min more than a full turn from the heading: rad", angle_min);
  if (std::abs(angle_max) > kTurn + kSlack)
    return text("angle_max more than a full turn from the heading: rad", angle_max);
  if (beams > 1 && angle_increment == 0.0)
    return "an angle_increment of zero over " + std::to_string(beams) + " beams";
  if (beams > 1 && angle_max != angle_min && (angle_max - angle_min) * angle_increment < 0.0) {
    return text("an angle_increment of the wrong sign: rad", angle_increment) +
           text(" from angle_min", angle_min) + text(" to angle_max", angle_max);
  }
  const double sweep = std::abs(angle_increment) * static_cast<double>(beams - 1);
  if (sweep > kTurn + std::abs(angle_increment) + kSlack) {
    return std::to_string(beams) + text(" beams spanning more than a full turn: rad", sweep);
  }
  if (!std::isfinite(range_max) || !(range_max > 0.0 && range_max <= kMaxRange)) {
    return text("range_max not in (0, 10000] m:", range_max);
  }
  if (!std::isfinite(range_min) || !(range_min >= 0.0 && range_min < range_max)) {
    return text("range_min not in [0, range_max) m:", range_min);
  }
  return "";
}

RangeScan Ros2Robot::RangeScanFor(double angle_min, double angle_increment, double range_min,
                                  double range_max, std::span<const float> ranges) {
  RangeScan scan;
  const size_t n = ranges.size();
  const double last = angle_min + angle_increment * static_cast<double>(n > 0 ? n - 1 : 0);
  if (!ScanProblem(angle_min, last, angle_increment, range_min, range_max, n).empty()) return scan;
  const size_t per_sector = (n + kMaxRangeBeams - 1) / kMaxRangeBeams;
  scan.count = static_cast<int>((n + per_sector - 1) / per_sector);
  // Each sector's angle is its middle beam's (a half-beam between two for
  // an even width).
  scan.angle_min = angle_min + angle_increment * 0.5 * static_cast<double>(per_sector - 1);
  scan.angle_increment = angle_increment * static_cast<double>(per_sector);
  scan.range_max = range_max;
  for (int sector = 0; sector < scan.count; ++sector) {
    double nearest = range_max;
    const size_t first = static_cast<size_t>(sector) * per_sector;
    for (size_t i = first; i < std::min(n, first + per_sector); ++i) {
      const double r = ranges[i];
      if (std::isnan(r) || r == std::numeric_limits<double>::infinity())
        continue;  // no reading; nothing in range
      if (r == -std::numeric_limits<double>::infinity()) {
        nearest = std::min(nearest, range_min);  // nearer than the sensor can tell
      } else if (r >= range_min && r <= range_max) {
        nearest = std::min(nearest, r);
      }  // else: invalid (REP 117), dropped
    }
    scan.ranges[static_cast<size_t>(sector)] = static_cast<float>(nearest);
  }
  return scan;
}

void Ros2Robot::SendTwist(double v, double w) {
  Twist_ t;
  t.linear().x(v);
  t.angular().z(w);
  if (graph_->twist_writer->write(&t)) graph_->twists_sent.fetch_add(1, std::memory_order_relaxed);
  since_twist_s_ = 0.0;
}

void Ros2Robot::SetMotors(const models::MotorLevels& levels) {
  const auto [v, w] = TwistFor(levels, config_.drive);
  if (levels.left != state_.applied.left || levels.right != state_.applied.right) twist_due_ = true;
  state_.applied = levels;
  v_ = v;
  w_ = w;
}

void Ros2Robot::Stop() {
  state_.applied = {};
  v_ = w_ = 0.0;
  SendTwist(0.0, 0.0);
  twist_due_ = false;
}

void Ros2Robot::Update(double dt) {
  const int64_t now = MonotonicNs();
  Odometry_ odom;
  dds::SampleInfo info;
  while (graph_->odom_reader->take_next_sample(&odom, &info) == ReturnCode_t::RETCODE_OK) {
    if (!info.valid_data) continue;
    if (!Finite(odom)) {
      graph_->odom_dropped.fetch_add(1, std::memory_order_relaxed);
      continue;
    }
    graph_->odom_received.fetch_add(1, std::memory_order_relaxed);
    last_odom_ns_ = now;
    const auto& p = odom.pose().pose();
    const double c = std::cos(start_heading_);
    const double s = std::sin(start_heading_);
    state_.x = start_x_ + c * p.position().x() - s * p.position().y();
    state_.y = start_y_ + s * p.position().x() + c * p.position().y();
    state_.heading = std::remainder(start_heading_ + YawOf(p.orientation()), 2.0 * M_PI);
    state_.speed = odom.twist().twist().linear().x();
    state_.yaw_rate = odom.twist().twist().angular().z();
    state_.pose_valid = true;
  }
  if (graph_->scan_reader != nullptr) {
    LaserScan_ laser;
    while (graph_->scan_reader->take_next_sample(&laser, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      const std::string problem =
          ScanProblem(laser.angle_min(), laser.angle_max(), laser.angle_increment(),
                      laser.range_min(), laser.range_max(), laser.ranges().size());
      const RangeScan scan =
          problem.empty() ? RangeScanFor(laser.angle_min(), laser.angle_increment(),
                                         laser.range_min(), laser.range_max(), laser.ranges())
                          : RangeScan{};
      if (scan.count == 0) {
        graph_->scans_dropped.fetch_add(1, std::memory_order_relaxed);
        if (!scan_problem_said_) {
          scan_problem_said_ = true;
          log::Warn("ros2: a scan on " + Ros2DdsTopic(config_.ros2.scan) + " refused: " + problem +
                    "; impossible scans are dropped and counted (said once)");
        }
        continue;
      }
      graph_->scans_received.fetch_add(1, std::memory_order_relaxed);
      state_.ranges = scan;
      last_scan_ns_ = now;
    }
    // What the robot saw a while ago is not what is ahead of it now.
    if (last_scan_ns_ != 0 && NsToS(now - last_scan_ns_) > config_.ros2.odom_timeout_s)
      state_.ranges = RangeScan{};
  }
  const bool silent =
      last_odom_ns_ != 0 && NsToS(now - last_odom_ns_) > config_.ros2.odom_timeout_s;
  if (silent && !state_.fault) {
    state_.fault = true;
    state_.fault_message = "ROS 2 robot silent: no odometry on " + config_.ros2.odom + " for " +
                           std::to_string(config_.ros2.odom_timeout_s).substr(0, 4) + " s";
  } else if (!silent && state_.fault) {
    state_.fault = false;
    state_.fault_message.clear();
  }
  // A silent robot is told to stand still; one that talks gets its twist
  // when it changes and at the configured rate while it holds.
  const double v = silent ? 0.0 : v_;
  const double w = silent ? 0.0 : w_;
  since_twist_s_ += dt;
  if (twist_due_ || since_twist_s_ >= 1.0 / config_.ros2.cmd_rate_hz) {
    SendTwist(v, w);
    twist_due_ = false;
  }
}

AdapterState Ros2Robot::State() const { return state_; }

std::unique_ptr<video::CameraSource> Ros2Robot::MakeCamera() {
  if (graph_->image_reader == nullptr) return nullptr;
  return std::make_unique<Ros2Camera>(graph_, config_.camera, Ros2DdsTopic(config_.ros2.image));
}

Ros2Counters Ros2Robot::Counters() const {
  Ros2Counters c;
  c.twists_sent = graph_->twists_sent.load();
  c.odom_received = graph_->odom_received.load();
  c.odom_dropped = graph_->odom_dropped.load();
  c.images_received = graph_->images_received.load();
  c.images_dropped = graph_->images_dropped.load();
  c.images_refused = graph_->images_refused.load();
  c.scans_received = graph_->scans_received.load();
  c.scans_dropped = graph_->scans_dropped.load();
  return c;
}

}  // namespace haptel::vehicles
