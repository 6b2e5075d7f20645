// The vehicle seam: a new robot-like kind is an adapter, its registration and
// a vehicle file — here a toy kind registered the way docs/vehicles.md shows,
// loaded from its file, opened by OpenVehicle and driven through the one
// vehicle node over DDS, with the watchdog stopping it.
#include <catch2/catch.hpp>
#include <cmath>
#include <mutex>
#include <numbers>
#include <optional>

#include "haptel/config/vehicle.hpp"
#include "haptel/config/vehicle_kinds.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/link/families.hpp"
#include "haptel/vehicles/vehicle_kinds.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::models;
using namespace haptel::vehicles;

namespace {

/// The toy: a point that rolls along its heading at the mean of its treads'
/// levels (max_speed at the top level) and turns at their difference.
class ToyRobot final : public VehicleAdapter {
 public:
  explicit ToyRobot(const VehicleConfig& config) : drive_(config.drive) {
    state_.pose_valid = true;
  }
  void SetMotors(const MotorLevels& levels) override { state_.applied = levels; }
  void Update(double dt) override {
    const double top = drive_.max_speed / drive_.speed_levels;
    const double left = top * state_.applied.left, right = top * state_.applied.right;
    state_.speed = 0.5 * (left + right);
    state_.yaw_rate = (right - left) / drive_.track_width;
    state_.heading += state_.yaw_rate * dt;
    state_.x += state_.speed * std::cos(state_.heading) * dt;
    state_.y += state_.speed * std::sin(state_.heading) * dt;
  }
  AdapterState State() const override { return state_; }

 private:
  TreadDriveConfig drive_;
  AdapterState state_;
};

VehicleKindInfo Kind(const std::string& name, const std::string& summary = "") {
  VehicleKindInfo info;
  info.name = name;
  info.summary = summary;
  return info;
}

/// Registers the toy once per process (a second registration is refused).
void RegisterToy() {
  static const bool registered = [] {
    RegisterKind<RobotFamily>(Kind("toy-robot", "a toy robot for the seam's test"),
                              [](const VehicleConfig& c, const Track&) {
                                KindParts<RobotFamily> parts;
                                parts.adapter = std::make_unique<ToyRobot>(c);
                                return parts;
                              });
    return true;
  }();
  (void)registered;
}

/// The toy's vehicle file: only what differs from the defaults.
std::filesystem::path ToyFile(const std::filesystem::path& dir, int domain) {
  return test::WriteFile(dir / "toy.yaml",
                         "name: toy1\n"
                         "kind: toy-robot\n"
                         "world: " +
                             std::filesystem::absolute("config/tracks/test-short.yaml").string() +
                             "\n"
                             "watchdog_timeout_s: 0.2\n"
                             "camera: {rate_hz: 5, width: 64, height: 48}\n"
                             "link: {domain_id: " +
                             std::to_string(domain) + "}\n");
}

/// The operator's end, on the link's own types.
struct OperatorEnd {
  explicit OperatorEnd(const LinkConfig& config)
      : participant(config, "test-operator"),
        commands(participant, link::TopicName("toy1", "command"), link::Profile::kCommand),
        states(participant, link::TopicName("toy1", "state"), link::Profile::kState,
               [this](const msg::VehicleState& s) {
                 std::lock_guard lock(mutex);
                 last = s;
               }) {
    message.session(42);
    message.operator_name("test");
  }
  void Send(const TreadCommand& c) {
    message.seq(++seq);
    link::RobotMessages::Encode(c, message);
    message.sent_ns(MonotonicNs());
    commands.Write(message);
  }
  std::optional<msg::VehicleState> Last() {
    std::lock_guard lock(mutex);
    return last;
  }

  link::Participant participant;
  link::TreadCommandWriter commands;
  msg::TreadCommand message;
  uint64_t seq = 0;
  std::mutex mutex;
  std::optional<msg::VehicleState> last;
  link::StateReader states;
};

}  // namespace

TEST_CASE("a registered kind is in the table with its family; names are checked") {
  RegisterToy();
  const VehicleKindInfo* toy = FindVehicleKind("toy-robot");
  REQUIRE(toy != nullptr);
  CHECK(toy->family == VehicleFamily::kRobot);
  CHECK_FALSE(toy->Uses(kCanSection));
  CHECK(FindKindFactory<RobotFamily>("toy-robot") != nullptr);
  CHECK(FindKindFactory<BlimpFamily>("toy-robot") == nullptr);
  CHECK_THAT(VehicleKindNames(), Catch::Contains("sim-robot") && Catch::Contains("toy-robot"));
  // Taken, malformed, or without a factory: refused, and the table unchanged.
  const size_t kinds = VehicleKinds().size();
  CHECK_THROWS_WITH(RegisterKind<RobotFamily>(Kind("toy-robot"),
                                              [](const VehicleConfig&, const Track&) {
                                                return KindParts<RobotFamily>{};
                                              }),
                    Catch::Contains("registered already"));
  CHECK_THROWS_WITH(RegisterVehicleKind(Kind("toy robot")),
                    Catch::Contains("letters, digits and '-'"));
  CHECK_THROWS_WITH(RegisterKind<RobotFamily>(Kind("no-factory"), nullptr),
                    Catch::Contains("no factory"));
  CHECK(VehicleKinds().size() == kinds);
}

TEST_CASE("every built-in kind has a factory in its family, and only there") {
  for (const VehicleKindInfo& kind : VehicleKinds()) {
    INFO(kind.name);
    const bool robot = FindKindFactory<RobotFamily>(kind.name) != nullptr;
    const bool blimp = FindKindFactory<BlimpFamily>(kind.name) != nullptr;
    CHECK(robot == (kind.family == VehicleFamily::kRobot));
    CHECK(blimp == (kind.family == VehicleFamily::kBlimp));
  }
}

TEST_CASE("a vehicle file naming an unknown kind is refused with the known kinds") {
  const auto dir = test::ScratchDir("kinds");
  const auto file =
      test::WriteFile(dir / "odd.yaml", "name: odd\nkind: hovercraft\nworld: x.yaml\n");
  const std::string what = test::WhatOf<std::exception>([&] { LoadVehicle(file); });
  CHECK_THAT(what, Catch::Contains("kind") && Catch::Contains("sim-robot, can-robot"));
}

TEST_CASE(
    "a toy kind registered as the docs show is loaded, opened and driven through the one node") {
  RegisterToy();
  const int domain = test::UniqueDomain(71);
  const auto dir = test::ScratchDir("toy-kind");
  const auto file = ToyFile(dir, domain);
  const VehicleConfig config = LoadVehicle(file);
  REQUIRE(config.family() == VehicleFamily::kRobot);

  OpenedVehicle opened = OpenVehicle(config, file.string());
  CHECK_THAT(opened.description, Catch::Contains("track '") && Catch::Contains("64x48"));
  const std::unique_ptr<Node> node = opened.make_node();
  node->Start();
  OperatorEnd op(config.link);

  // Full ahead on both treads until the toy has rolled 5 cm.
  std::optional<msg::VehicleState> s;
  const bool rolled = test::WaitFor(
      [&] {
        op.Send({1.0, 1.0});
        s = op.Last();
        return s && s->x() > 0.05f;
      },
      20.0);
  REQUIRE(rolled);
  CHECK(s->motor_left_level() == config.drive.speed_levels);
  CHECK(s->motor_right_level() == config.drive.speed_levels);
  CHECK(std::abs(s->y()) < 1e-3f);  // straight ahead: the toy's treads are even
  CHECK(s->owner_session() == 42);
  CHECK(link::WriterId{s->owner_writer()} ==
        op.commands.id());  // the owner is the writer DDS named

  // No more commands: the watchdog stops it, the toy stands still.
  REQUIRE(test::WaitFor(
      [&] {
        s = op.Last();
        return s && s->watchdog_tripped();
      },
      10.0));
  CHECK(s->motor_left_level() == 0);
  CHECK(s->motor_right_level() == 0);
  node->Stop();
  const NodeCounters counters = node->Counters();
  CHECK(counters.commands_accepted > 0);
  CHECK(counters.watchdog_trips >= 1);
  CHECK(node->AdapterFailure().empty());
  CHECK(std::string(node->MadeSafe()) == "motors stopped");
}

TEST_CASE(
    "a CAN robot's bus log is its own topic (can_log), not its family's state; other kinds have "
    "none") {
  const int domain = test::UniqueDomain(72);
  const auto dir = test::ScratchDir("can-log-topic");
  const std::string world = std::filesystem::absolute("config/tracks/test-short.yaml").string();
  const auto file =
      test::WriteFile(dir / "can1.yaml", "name: can1\nkind: can-robot-sim\nworld: " + world +
                                             "\ncamera: {rate_hz: 5, width: 64, height: 48}\n"
                                             "can: {log_dir: " +
                                             (dir / "can").string() +
                                             "}\n"
                                             "link: {domain_id: " +
                                             std::to_string(domain) + "}\n");
  const VehicleConfig config = LoadVehicle(file);
  const Track track(LoadTrack(config.world));

  // Only a kind that keeps a bus log has the topic.
  CHECK((*FindKindFactory<RobotFamily>("can-robot-sim"))(config, track).report != nullptr);
  VehicleConfig no_log = config;
  no_log.can.log_dir.clear();
  CHECK((*FindKindFactory<RobotFamily>("can-robot-sim"))(no_log, track).report == nullptr);
  CHECK((*FindKindFactory<RobotFamily>("sim-robot"))(config, track).report == nullptr);

  OpenedVehicle opened = OpenVehicle(config, file.string());
  const std::unique_ptr<Node> node = opened.make_node();
  node->Start();
  link::Participant participant(config.link, "test-operator");
  std::mutex mutex;
  std::optional<msg::CanLogStatus> last;
  link::CanLogReader reader(participant, link::TopicName("can1", "can_log"),
                            link::Profile::kLatched, [&](const msg::CanLogStatus& s) {
                              std::lock_guard lock(mutex);
                              last = s;
                            });
  // The log fills with the nodes' heartbeats; its status follows each flush.
  std::optional<msg::CanLogStatus> s;
  REQUIRE(test::WaitFor(
      [&] {
        std::lock_guard lock(mutex);
        s = last;
        return s && s->frames() > 0;
      },
      20.0));
  node->Stop();
  CHECK(std::filesystem::path(s->path()).parent_path() == std::filesystem::absolute(dir / "can"));
  CHECK(s->frames_lost() == 0);
  CHECK(s->error().empty());
}

TEST_CASE(
    "a robot with a rear camera streams it on its own topic, aimed only by its holder's camera "
    "commands; malformed and foreign ones are counted, the status says who holds it") {
  RegisterToy();
  const int domain = test::UniqueDomain(73);
  const auto dir = test::ScratchDir("toy-cameras");
  const std::string world = std::filesystem::absolute("config/tracks/test-short.yaml").string();
  const auto file = test::WriteFile(
      dir / "toy.yaml",
      "name: toy1\nkind: toy-robot\nworld: " + world +
          "\ncameras:\n"
          "  - {rate_hz: 5, width: 64, height: 48}\n"
          "  - {name: rear, rate_hz: 10, width: 64, height: 48, mount_forward: -0.1,\n"
          "     mount_yaw_deg: 180, pan_min_deg: -90, pan_max_deg: 90, zoom_max: 4}\n"
          "link: {domain_id: " +
          std::to_string(domain) + "}\n");
  const VehicleConfig config = LoadVehicle(file);
  REQUIRE(config.extra_cameras.size() == 1);
  OpenedVehicle opened = OpenVehicle(config, file.string());
  CHECK_THAT(opened.description, Catch::Contains("camera rear"));
  const std::unique_ptr<Node> node = opened.make_node();
  node->Start();

  link::Participant station(config.link, "test-station");
  link::Participant stranger(config.link, "test-stranger");
  link::CameraCommandWriter commands(station, link::CameraCommandTopic("toy1", "rear"),
                                     link::CameraMessages::kCommandProfile);
  link::CameraCommandWriter foreign(stranger, link::CameraCommandTopic("toy1", "rear"),
                                    link::CameraMessages::kCommandProfile);
  std::mutex mutex;
  std::optional<msg::VideoFrame> frame;
  std::optional<msg::CameraStatus> status;
  uint64_t pilot_frames = 0;
  link::VideoReader rear(station, link::VideoTopic("toy1", "rear", false), link::Profile::kVideo,
                         [&](const msg::VideoFrame& f) {
                           std::lock_guard lock(mutex);
                           frame = f;
                         });
  link::VideoReader pilot(station, link::VideoTopic("toy1", "pilot", true), link::Profile::kVideo,
                          [&](const msg::VideoFrame& f) {
                            std::lock_guard lock(mutex);
                            if (f.camera() == "pilot") ++pilot_frames;
                          });
  link::CameraStatusReader statuses(station, link::CameraStatusTopic("toy1"),
                                    link::CameraMessages::kStatusProfile,
                                    [&](const msg::CameraStatus& s) {
                                      std::lock_guard lock(mutex);
                                      status = s;
                                    });
  msg::CameraCommand m;
  m.session(7);
  m.operator_name("station eve");
  uint64_t seq = 0;
  const auto send = [&](link::CameraCommandWriter& writer, const CameraAim& aim) {
    link::CameraMessages::Encode("rear", aim, m);
    m.seq(++seq);
    m.sent_ns(MonotonicNs());
    writer.Write(m);
  };
  // Aimed 0.5 rad left, zoomed 3x: a frame says so, and the command it shows.
  std::optional<msg::VideoFrame> f;
  REQUIRE(test::WaitFor(
      [&] {
        send(commands, {.pan = 0.5, .tilt = 0.0, .zoom = 3.0});
        std::lock_guard lock(mutex);
        f = frame;
        return f && f->command_seq() > 0;
      },
      20.0));
  CHECK(f->camera() == "rear");
  CHECK(f->zoom() == Approx(3.0));
  CHECK(f->pan() == Approx(std::numbers::pi + 0.5).margin(1e-4));  // mounted backwards
  CHECK(f->fov_deg() == Approx(ZoomedFovDeg(config.extra_cameras[0].fov_deg, 3.0)).margin(1e-3));
  CHECK(f->width() == 64);

  // Out of range (zoom 9 of 4) and another writer's: dropped and counted.
  const uint64_t shown = f->command_seq();
  for (int i = 0; i < 5; ++i) {
    send(commands, {.pan = 0.0, .tilt = 0.0, .zoom = 9.0});
    send(foreign, {.pan = -1.0, .tilt = 0.0, .zoom = 1.0});
  }
  std::optional<msg::CameraStatus> s;
  REQUIRE(test::WaitFor(
      [&] {
        std::lock_guard lock(mutex);
        s = status;
        return s && s->cameras().size() == 2 && s->cameras()[1].commands_malformed() >= 5 &&
               s->cameras()[1].commands_refused() >= 5;
      },
      20.0));
  const msg::CameraInfo& info = s->cameras()[1];
  CHECK(info.name() == "rear");
  CHECK(info.video_topic() == "haptel/toy1/video/rear");
  CHECK(info.holder_session() == 7);
  CHECK(info.holder() == "station eve");
  CHECK(link::WriterId{info.holder_writer()} == commands.id());
  CHECK(info.held_since_wall_ns() > 0);
  CHECK(info.zoom() == Approx(3.0));  // where the holder's last good command left it
  CHECK(info.zoom_max() == Approx(4.0));
  CHECK(s->cameras()[0].driven());
  CHECK(s->cameras()[0].name() == "pilot");
  {
    std::lock_guard lock(mutex);
    CHECK(frame->zoom() == Approx(3.0));
    CHECK(frame->command_seq() >= shown);
  }
  // The driven camera streams on as before, on its own topic, named.
  CHECK(test::WaitFor(
      [&] {
        std::lock_guard lock(mutex);
        return pilot_frames > 0;
      },
      20.0));
  node->Stop();
  const NodeCounters counters = node->Counters();
  CHECK(counters.camera_commands_malformed >= 5);
  CHECK(counters.camera_commands_refused >= 5);
  CHECK(counters.camera_frames_published > 0);
}
