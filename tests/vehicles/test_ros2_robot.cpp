// The ROS 2 adapter in-process, against Fast DDS endpoints of the test's own
// on a domain of its own: what it sends on cmd_vel, how odometry becomes the
// track-frame pose, the silent robot, bad odometry, the camera topic, the
// laser scan as the state's range field, and the configuration's checks.
#include <zlib.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <limits>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "haptel/config/error.hpp"
#include "haptel/link/participant.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/ros2/ros2.h"
#include "haptel/ros2/ros2PubSubTypes.h"
#include "haptel/vehicles/ros2_robot.hpp"
#include "haptel/video/codec.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::vehicles;
namespace fdds = eprosima::fastdds::dds;

namespace {

/// A track whose start faces north (+y), so the odometry frame is turned.
TrackConfig NorthTrack() {
  TrackConfig t;
  t.name = "north";
  t.centerline = {{0, 0}, {0, 4}, {-3, 4}, {-3, 0}};
  t.corridor_width = 1.0;
  t.start_behind = 0.0;
  return t;
}

VehicleConfig Ros2Vehicle(int domain) {
  VehicleConfig v = LoadVehicle("config/vehicles/ros2-robot.yaml");
  v.ros2.domain_id = domain;
  v.ros2.odom_timeout_s = 0.3;
  return v;
}

/// The robot's side, in Fast DDS: reads twists, writes odometry and images.
struct FakeRobot {
  explicit FakeRobot(int domain) : participant(Link(domain), "test-robot") {
    using link::detail::MakeTopic;
    cmd = MakeTopic<geometry_msgs::msg::dds_::Twist_PubSubType>(participant, "rt/cmd_vel");
    odom = MakeTopic<nav_msgs::msg::dds_::Odometry_PubSubType>(participant, "rt/odom");
    image = MakeTopic<sensor_msgs::msg::dds_::CompressedImage_PubSubType>(
        participant, "rt/camera/image_raw/compressed");
    scan = MakeTopic<sensor_msgs::msg::dds_::LaserScan_PubSubType>(participant, "rt/scan");
    fdds::DataReaderQos rq = fdds::DATAREADER_QOS_DEFAULT;
    rq.reliability().kind =
        fdds::RELIABLE_RELIABILITY_QOS;  // as a ROS 2 subscriber: the adapter must match it
    twist_reader = participant.subscriber()->create_datareader(cmd, rq);
    odom_writer = participant.publisher()->create_datawriter(odom, fdds::DATAWRITER_QOS_DEFAULT);
    image_writer = participant.publisher()->create_datawriter(image, fdds::DATAWRITER_QOS_DEFAULT);
    scan_writer = participant.publisher()->create_datawriter(scan, fdds::DATAWRITER_QOS_DEFAULT);
  }
  ~FakeRobot() {
    participant.subscriber()->delete_datareader(twist_reader);
    participant.publisher()->delete_datawriter(odom_writer);
    participant.publisher()->delete_datawriter(image_writer);
    participant.publisher()->delete_datawriter(scan_writer);
    for (fdds::Topic* t : {cmd, odom, image, scan}) participant.get()->delete_topic(t);
  }
  static LinkConfig Link(int domain) {
    LinkConfig l;
    l.domain_id = domain;
    return l;
  }
  void Odom(double x, double y, double yaw, double v, double w) {
    nav_msgs::msg::dds_::Odometry_ o;
    o.pose().pose().position().x(x);
    o.pose().pose().position().y(y);
    o.pose().pose().orientation().z(std::sin(yaw / 2));
    o.pose().pose().orientation().w(std::cos(yaw / 2));
    o.twist().twist().linear().x(v);
    o.twist().twist().angular().z(w);
    odom_writer->write(&o);
  }
  /// The newest twist received, {v, ω}; false when none came.
  bool LastTwist(double& v, double& w) {
    geometry_msgs::msg::dds_::Twist_ t;
    fdds::SampleInfo info;
    bool got = false;
    while (twist_reader->take_next_sample(&t, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      v = t.linear().x();
      w = t.angular().z();
      got = true;
    }
    return got;
  }

  link::Participant participant;
  fdds::Topic* cmd = nullptr;
  fdds::Topic* odom = nullptr;
  fdds::Topic* image = nullptr;
  fdds::Topic* scan = nullptr;
  fdds::DataReader* twist_reader = nullptr;
  fdds::DataWriter* odom_writer = nullptr;
  fdds::DataWriter* image_writer = nullptr;
  fdds::DataWriter* scan_writer = nullptr;
};

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/// A valid grey PNG of width × height black pixels, made row by row, so
/// that a 10 000 × 10 000 image (100 MB to decode) is 100 kB of bytes and
/// never held whole here: what a robot sent to the adapter in issue 41.
std::vector<uint8_t> BlackPng(uint32_t width, uint32_t height) {
  std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  const auto be32 = [](std::vector<uint8_t>& out, uint32_t v) {
    for (int shift : {24, 16, 8, 0}) out.push_back(static_cast<uint8_t>(v >> shift));
  };
  const auto chunk = [&](const char* type, const std::vector<uint8_t>& data) {
    be32(png, static_cast<uint32_t>(data.size()));
    std::vector<uint8_t> body(type, type + 4);
    body.insert(body.end(), data.begin(), data.end());
    png.insert(png.end(), body.begin(), body.end());
    be32(png, static_cast<uint32_t>(crc32(0, body.data(), static_cast<uInt>(body.size()))));
  };
  std::vector<uint8_t> ihdr;
  be32(ihdr, width);
  be32(ihdr, height);
  for (uint8_t b : {8, 0, 0, 0, 0})
    ihdr.push_back(b);  // 8-bit grey, deflate, no filter, no interlace
  chunk("IHDR", ihdr);
  z_stream z{};
  REQUIRE(deflateInit(&z, Z_BEST_COMPRESSION) == Z_OK);
  std::vector<uint8_t> row(width + 1, 0);  // filter byte 0, then the pixels
  std::vector<uint8_t> idat;
  std::vector<uint8_t> buffer(1 << 16);
  for (uint32_t y = 0; y <= height; ++y) {
    const bool last = y == height;
    z.next_in = last ? nullptr : row.data();
    z.avail_in = last ? 0 : static_cast<uInt>(row.size());
    do {
      z.next_out = buffer.data();
      z.avail_out = static_cast<uInt>(buffer.size());
      deflate(&z, last ? Z_FINISH : Z_NO_FLUSH);
      idat.insert(idat.end(), buffer.data(), buffer.data() + (buffer.size() - z.avail_out));
    } while (z.avail_out == 0);
  }
  deflateEnd(&z);
  chunk("IDAT", idat);
  chunk("IEND", {});
  return png;
}

}  // namespace

TEST_CASE("ros2: motor levels are a differential drive's twist") {
  TreadDriveConfig d;
  d.speed_levels = 8;
  d.max_speed = 0.3;
  d.track_width = 0.16;
  std::array<double, 2> t = Ros2Robot::TwistFor({8, 8}, d);
  CHECK(t[0] == Approx(0.3));
  CHECK(t[1] == Approx(0.0));
  t = Ros2Robot::TwistFor({-4, 4}, d);  // turning on the spot, left
  CHECK(t[0] == Approx(0.0));
  CHECK(t[1] == Approx(0.3 / 0.16));
  t = Ros2Robot::TwistFor({2, 6}, d);
  CHECK(t[0] == Approx(0.15));
  CHECK(t[1] == Approx(0.15 / 0.16));
}

TEST_CASE(
    "ros2: twists out, odometry in the track's frame, a silent robot is a fault and told to stop") {
  const int domain = test::UniqueDomain(61);
  const Track track(NorthTrack());
  Ros2Robot adapter(Ros2Vehicle(domain), track);
  FakeRobot robot(domain);
  CHECK_FALSE(adapter.State().pose_valid);

  // Until the twists arrive (discovery), keep asking for half speed ahead.
  double v = 0.0;
  double w = 0.0;
  REQUIRE(test::WaitFor(
      [&] {
        adapter.SetMotors({4, 4});
        adapter.Update(0.05);
        return robot.LastTwist(v, w) && v > 0.0;
      },
      30.0));
  CHECK(v == Approx(0.15));
  CHECK(w == Approx(0.0));

  // 1 m ahead and a quarter turn left in the odometry frame: with the start
  // facing north that is 1 m north of the start, heading west.
  const Vec2 start = track.StartPosition();
  REQUIRE(test::WaitFor(
      [&] {
        robot.Odom(1.0, 0.0, std::numbers::pi / 2, 0.2, 0.1);
        adapter.Update(0.01);
        return adapter.State().pose_valid;
      },
      30.0));
  AdapterState s = adapter.State();
  CHECK(s.x == Approx(start.x()).margin(1e-9));
  CHECK(s.y == Approx(start.y() + 1.0));
  CHECK(std::abs(std::remainder(s.heading - std::numbers::pi, 2 * std::numbers::pi)) < 1e-9);
  CHECK(s.speed == Approx(0.2));
  CHECK(s.yaw_rate == Approx(0.1));
  CHECK_FALSE(s.fault);

  // Non-finite odometry is dropped and counted; the pose stays.
  robot.Odom(std::nan(""), 0.0, 0.0, 0.0, 0.0);
  REQUIRE(test::WaitFor(
      [&] {
        adapter.Update(0.01);
        return adapter.Counters().odom_dropped == 1;
      },
      30.0));
  CHECK(adapter.State().y == Approx(start.y() + 1.0));

  // Silent past odom_timeout_s: a fault, and zero velocity though the command holds.
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  adapter.SetMotors({4, 4});
  adapter.Update(0.01);
  s = adapter.State();
  CHECK(s.fault);
  CHECK(s.fault_message.find("no odometry on /odom") != std::string::npos);
  REQUIRE(test::WaitFor(
      [&] {
        adapter.Update(0.06);
        return robot.LastTwist(v, w) && v == 0.0;
      },
      30.0));
  // Odometry again: the fault clears.
  robot.Odom(1.0, 0.0, 0.0, 0.0, 0.0);
  REQUIRE(test::WaitFor(
      [&] {
        adapter.Update(0.01);
        return !adapter.State().fault;
      },
      30.0));

  // Stop: zero velocity at once.
  adapter.Stop();
  REQUIRE(test::WaitFor([&] { return robot.LastTwist(v, w) && v == 0.0 && w == 0.0; }, 30.0));
}

TEST_CASE("ros2: the image topic is the camera; an image that does not decode is dropped") {
  const int domain = test::UniqueDomain(62);
  const Track track(NorthTrack());
  VehicleConfig config = Ros2Vehicle(domain);
  Ros2Robot adapter(config, track);
  auto camera = adapter.MakeCamera();
  REQUIRE(camera != nullptr);
  CHECK(camera->Describe() == "ros2 rt/camera/image_raw/compressed");
  FakeRobot robot(domain);

  cv::Mat red(120, 160, CV_8UC3, cv::Scalar(0, 0, 255));
  std::vector<uint8_t> jpeg;
  REQUIRE(cv::imencode(".jpg", red, jpeg));
  cv::Mat frame;
  bool grabbed = false;
  REQUIRE(test::WaitFor(
      [&] {
        sensor_msgs::msg::dds_::CompressedImage_ image;
        image.format("jpeg");
        image.data(jpeg);
        robot.image_writer->write(&image);
        grabbed = camera->Grab({}, frame);
        return grabbed;
      },
      30.0));
  CHECK(frame.cols == config.camera.width);  // resized to what is streamed
  CHECK(frame.rows == config.camera.height);
  const cv::Vec3b centre = frame.at<cv::Vec3b>(frame.rows / 2, frame.cols / 2);
  CHECK(centre[2] > 200);
  CHECK(centre[0] < 50);

  // A PNG whose header is sound and whose pixels are not: decoding fails.
  std::vector<uint8_t> broken;
  REQUIRE(cv::imencode(".png", red, broken));
  for (size_t i = 40; i < broken.size() - 12; ++i) broken[i] = static_cast<uint8_t>(i * 37);
  sensor_msgs::msg::dds_::CompressedImage_ junk;
  junk.format("png");
  junk.data(broken);
  REQUIRE(test::WaitFor(
      [&] {
        robot.image_writer->write(&junk);
        camera->Grab({}, frame);
        return adapter.Counters().images_dropped > 0;
      },
      30.0));
}

TEST_CASE(
    "ros2: a LaserScan is the state's range field, beam for beam; inf meets nothing, out of range "
    "is dropped") {
  // Five beams from -90 degrees to +90 degrees, a laser seeing 0.1 to 4 m.
  const double quarter = std::numbers::pi / 2;
  const std::vector<float> ranges = {1.5f, kInf, 0.05f, kNaN, -kInf};
  const RangeScan s = Ros2Robot::RangeScanFor(-quarter, quarter / 2, 0.1, 4.0, ranges);
  REQUIRE(s.count == 5);
  CHECK(s.angle_min == Approx(-quarter));
  CHECK(s.angle_increment == Approx(quarter / 2));
  CHECK(s.range_max == Approx(4.0));
  CHECK(s.Hit(0));
  CHECK(s.ranges[0] == Approx(1.5f));
  CHECK_FALSE(s.Hit(1));  // +inf: nothing within range
  CHECK(s.ranges[1] == Approx(4.0f));
  CHECK_FALSE(s.Hit(2));  // 5 cm under range_min: invalid, dropped
  CHECK_FALSE(s.Hit(3));  // NaN: no reading
  CHECK(s.Hit(4));        // -inf: nearer than the laser can tell
  CHECK(s.ranges[4] == Approx(0.1f));
  CHECK(s.Angle(4) == Approx(quarter));

  // A reading past range_max is invalid too, and so is a scan without sense.
  CHECK_FALSE(Ros2Robot::RangeScanFor(0.0, 0.1, 0.1, 4.0, std::vector<float>{4.5f}).Hit(0));
  CHECK(Ros2Robot::RangeScanFor(0.0, 0.1, 0.1, 4.0, std::vector<float>{}).count == 0);
  CHECK(Ros2Robot::RangeScanFor(0.0, 0.0, 0.1, 4.0, std::vector<float>{1.0f, 1.0f}).count == 0);
  CHECK(Ros2Robot::RangeScanFor(0.0, 0.1, 0.1, kInf, std::vector<float>{1.0f}).count == 0);
  CHECK(Ros2Robot::RangeScanFor(0.0, 0.1, 5.0, 4.0, std::vector<float>{1.0f}).count == 0);
  CHECK(Ros2Robot::RangeScanFor(kNaN, 0.1, 0.1, 4.0, std::vector<float>{1.0f}).count == 0);
}

TEST_CASE(
    "ros2: a scan of more beams than the field holds is read in sectors, each its nearest valid "
    "range") {
  // A 360-beam laser, one beam a degree from -180 degrees, nothing in range
  // but a post 0.8 m away seen by beams 100 and 101, a wall at 2 m by beams
  // 300..359 and a reading under range_min in beam 5.
  const double degree = std::numbers::pi / 180;
  std::vector<float> ranges(360, kInf);
  ranges[100] = 0.9f;
  ranges[101] = 0.8f;
  for (int i = 300; i < 360; ++i) ranges[static_cast<size_t>(i)] = 2.0f;
  ranges[5] = 0.01f;
  const RangeScan s = Ros2Robot::RangeScanFor(-180 * degree, degree, 0.05, 10.0, ranges);
  // ceil(360 / 32) = 12 beams a sector: 30 sectors, 12 degrees apart, each at its middle.
  REQUIRE(s.count == 30);
  CHECK(s.angle_increment == Approx(12 * degree));
  CHECK(s.angle_min == Approx(-180 * degree + 5.5 * degree));
  for (int sector = 0; sector < s.count; ++sector) {
    INFO("sector " << sector);
    if (sector == 8) {  // beams 96..107
      CHECK(s.ranges[8] == Approx(0.8f));
      CHECK(s.Angle(8) == Approx((-180 + 96 + 5.5) * degree));
    } else if (sector >= 25) {  // beams 300..359
      CHECK(s.ranges[static_cast<size_t>(sector)] == Approx(2.0f));
    } else {
      CHECK_FALSE(s.Hit(sector));  // including sector 0: beam 5's 1 cm is invalid
    }
  }
}

TEST_CASE(
    "ros2: the robot's LaserScan topic reaches the state's range field, and a stale scan is "
    "withdrawn") {
  const int domain = test::UniqueDomain(63);
  const Track track(NorthTrack());
  Ros2Robot adapter(Ros2Vehicle(domain), track);  // odom_timeout_s 0.3
  FakeRobot robot(domain);
  CHECK(adapter.State().ranges.count == 0);

  sensor_msgs::msg::dds_::LaserScan_ laser;
  laser.angle_min(-0.5f);
  laser.angle_max(0.5f);
  laser.angle_increment(0.5f);
  laser.range_min(0.05f);
  laser.range_max(3.0f);
  laser.ranges({kInf, 0.7f, 3.5f});
  REQUIRE(test::WaitFor(
      [&] {
        robot.scan_writer->write(&laser);
        adapter.Update(0.01);
        return adapter.State().ranges.count > 0;
      },
      30.0));
  const RangeScan s = adapter.State().ranges;
  REQUIRE(s.count == 3);
  CHECK(s.angle_min == Approx(-0.5));
  CHECK_FALSE(s.Hit(0));
  CHECK(s.ranges[1] == Approx(0.7f));
  CHECK_FALSE(s.Hit(2));  // past range_max: dropped
  CHECK(adapter.Counters().scans_received >= 1);

  // A scan without beams is counted and dropped; the last good one stays.
  sensor_msgs::msg::dds_::LaserScan_ empty = laser;
  empty.ranges({});
  REQUIRE(test::WaitFor(
      [&] {
        robot.scan_writer->write(&empty);
        adapter.Update(0.01);
        return adapter.Counters().scans_dropped > 0;
      },
      30.0));
  CHECK(adapter.State().ranges.count == 3);

  // No scan for longer than odom_timeout_s: what it saw is withdrawn.
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  adapter.Update(0.01);
  CHECK(adapter.State().ranges.count == 0);
}

TEST_CASE("ros2: the configuration names a bad topic or domain") {
  const VehicleConfig shipped = LoadVehicle("config/vehicles/ros2-robot.yaml");
  CHECK(shipped.kind == "ros2");
  CHECK(Ros2DdsTopic(shipped.ros2.cmd_vel) == "rt/cmd_vel");
  VehicleConfig bad = shipped;
  bad.ros2.cmd_vel = "cmd_vel";  // not absolute
  CHECK_THROWS_WITH(bad.ValidateOrThrow(), Catch::Contains("ros2.cmd_vel"));
  bad = shipped;
  bad.ros2.odom = "/robot//odom";
  CHECK_THROWS_WITH(bad.ValidateOrThrow(), Catch::Contains("ros2.odom"));
  bad = shipped;
  bad.ros2.image = "/camera/1st";
  CHECK_THROWS_WITH(bad.ValidateOrThrow(), Catch::Contains("ros2.image"));
  bad = shipped;
  bad.ros2.image.clear();  // no camera topic: allowed
  CHECK_NOTHROW(bad.ValidateOrThrow());
  CHECK(shipped.ros2.scan == "/scan");
  bad.ros2.scan = "scan";
  CHECK_THROWS_WITH(bad.ValidateOrThrow(), Catch::Contains("ros2.scan"));
  bad.ros2.scan.clear();  // no laser: allowed
  CHECK_NOTHROW(bad.ValidateOrThrow());
  bad.ros2.domain_id = 300;
  CHECK_THROWS_WITH(bad.ValidateOrThrow(), Catch::Contains("ros2.domain_id"));
}

TEST_CASE("ros2: a scan of impossible geometry is refused, saying what is impossible (issue 41)") {
  // It was taken: "31 beams from -5.7e31 deg to +1.7e33 deg".
  const std::vector<float> ranges(31, 1.0f);
  CHECK(Ros2Robot::RangeScanFor(-1e30, 1e30, 0.1, 4.0, ranges).count == 0);
  CHECK_THAT(Ros2Robot::ScanProblem(-1e30, 2e31, 1e30, 0.1, 4.0, ranges.size()),
             Catch::Matchers::Contains("angle_min"));
  // A sweep of more than a full turn (31 beams a radian apart).
  CHECK(Ros2Robot::RangeScanFor(-3.0, 1.0, 0.1, 4.0, ranges).count == 0);
  CHECK_THAT(Ros2Robot::ScanProblem(-3.0, 27.0, 1.0, 0.1, 4.0, ranges.size()),
             Catch::Matchers::Contains("more than a full turn"));
  // An increment of the wrong sign for angle_min to angle_max.
  CHECK_THAT(Ros2Robot::ScanProblem(-1.0, 1.0, -0.05, 0.1, 4.0, 41),
             Catch::Matchers::Contains("angle_increment") && Catch::Matchers::Contains("sign"));
  CHECK_THAT(Ros2Robot::ScanProblem(0.0, 0.0, 0.0, 0.1, 4.0, 2), Catch::Matchers::Contains("zero"));
  CHECK_THAT(Ros2Robot::ScanProblem(0.0, 0.1, 0.1, 0.1, 1e30, 2),
             Catch::Matchers::Contains("range_max"));
  CHECK_THAT(Ros2Robot::ScanProblem(0.0, kInf, 0.1, 0.1, 4.0, 2),
             Catch::Matchers::Contains("angle_max"));
  // A real laser's full turn, counter-clockwise or clockwise, is fine.
  const double degree = std::numbers::pi / 180;
  CHECK(Ros2Robot::ScanProblem(-180 * degree, 179 * degree, degree, 0.05, 12.0, 360).empty());
  CHECK(Ros2Robot::ScanProblem(180 * degree, -179 * degree, -degree, 0.05, 12.0, 360).empty());
  CHECK(Ros2Robot::ScanProblem(-180 * degree, 180 * degree, degree, 0.05, 12.0, 361).empty());
  CHECK(Ros2Robot::ScanProblem(0.3, 0.3, 0.0, 0.05, 12.0, 1).empty());
}

TEST_CASE(
    "ros2: an image too large to decode is refused from its header, before decoding, and counted "
    "(issue 41)") {
  // A 10 000 x 10 000 PNG of 100 kB took the vehicle from 78 to 654 MiB and its video to 1 fps.
  const std::vector<uint8_t> huge_png = BlackPng(10000, 10000);
  CHECK(huge_png.size() < 1000000);
  int width = 0;
  int height = 0;
  REQUIRE(video::PngFrameSize(huge_png.data(), huge_png.size(), width, height));
  CHECK(width == 10000);
  CHECK(height == 10000);
  CHECK_FALSE(video::PngFrameSize(huge_png.data(), 20, width, height));  // cut before IHDR's end

  const int domain = test::UniqueDomain(64);
  const Track track(NorthTrack());
  Ros2Robot adapter(Ros2Vehicle(domain), track);
  auto camera = adapter.MakeCamera();
  REQUIRE(camera != nullptr);
  FakeRobot robot(domain);
  const auto send = [&](const std::vector<uint8_t>& bytes, const char* format) {
    sensor_msgs::msg::dds_::CompressedImage_ image;
    image.format(format);
    image.data(bytes);
    robot.image_writer->write(&image);
  };
  cv::Mat frame;
  REQUIRE(test::WaitFor(
      [&] {
        send(huge_png, "png");
        CHECK_FALSE(camera->Grab({}, frame));
        return adapter.Counters().images_refused > 0;
      },
      30.0));
  CHECK(adapter.Counters().images_dropped == 0);  // refused, not decoded and failed

  // A JPEG whose frame header says 10 000 x 10 000 (its SOF patched): refused too.
  cv::Mat red(120, 160, CV_8UC3, cv::Scalar(0, 0, 255));
  std::vector<uint8_t> jpeg;
  REQUIRE(cv::imencode(".jpg", red, jpeg));
  std::vector<uint8_t> huge_jpeg = jpeg;
  for (size_t i = 2; i + 9 < huge_jpeg.size(); ++i) {
    if (huge_jpeg[i] == 0xFF && huge_jpeg[i + 1] == 0xC0) {  // SOF0: precision, height, width
      huge_jpeg[i + 5] = huge_jpeg[i + 7] = 10000 >> 8;
      huge_jpeg[i + 6] = huge_jpeg[i + 8] = 10000 & 0xFF;
      break;
    }
  }
  REQUIRE(video::JpegFrameSize(huge_jpeg.data(), huge_jpeg.size(), width, height));
  REQUIRE(width == 10000);
  const uint64_t before = adapter.Counters().images_refused;
  REQUIRE(test::WaitFor(
      [&] {
        send(huge_jpeg, "jpeg");
        std::vector<uint8_t> bytes;
        CHECK_FALSE(
            camera->GrabJpeg(bytes));  // not handed on to be passed through or decoded either
        return adapter.Counters().images_refused > before;
      },
      30.0));

  // Another format than JPEG and PNG (a BMP) is refused: its size is not read.
  std::vector<uint8_t> bmp;
  REQUIRE(cv::imencode(".bmp", red, bmp));
  const uint64_t before_bmp = adapter.Counters().images_refused;
  REQUIRE(test::WaitFor(
      [&] {
        send(bmp, "bmp");
        CHECK_FALSE(camera->Grab({}, frame));
        return adapter.Counters().images_refused > before_bmp;
      },
      30.0));

  // A PNG of a sensible size still decodes.
  std::vector<uint8_t> small_png;
  REQUIRE(cv::imencode(".png", red, small_png));
  REQUIRE(test::WaitFor(
      [&] {
        send(small_png, "png");
        return camera->Grab({}, frame);
      },
      30.0));
  CHECK(frame.at<cv::Vec3b>(frame.rows / 2, frame.cols / 2)[2] > 200);
}
