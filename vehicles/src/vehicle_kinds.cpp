#include "haptel/vehicles/vehicle_kinds.hpp"

#include <cmath>
#include <ctime>
#include <map>
#include <stdexcept>
#include <utility>

#include "haptel/config/blimp_course.hpp"
#include "haptel/config/error.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/servo/serial_port.hpp"
#include "haptel/vehicles/blimp_adapters.hpp"
#include "haptel/vehicles/can_robot.hpp"
#include "haptel/vehicles/ros2_robot.hpp"
#include "haptel/vehicles/sim_can_robot.hpp"
#include "haptel/vehicles/sim_robot.hpp"
#include "haptel/video/blimp_camera.hpp"

namespace haptel::vehicles {

namespace {

/// "20261124T153012Z": a log file's time of creation, UTC.
std::string FileStamp(int64_t wall_ns) {
  const time_t seconds = static_cast<time_t>(wall_ns / 1'000'000'000);
  tm utc{};
  gmtime_r(&seconds, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y%m%dT%H%M%SZ", &utc);
  return text;
}

/// The CAN kinds log their bus traffic to can.log_dir/<name>-<UTC>.log
/// (candump -L) when it is set.
std::unique_ptr<CandumpWriter> OpenCanLog(const VehicleConfig& config) {
  if (config.can.log_dir.empty()) return nullptr;
  return std::make_unique<CandumpWriter>(
      config.can.log_dir / (config.name + "-" + FileStamp(WallNs()) + ".log"),
      config.can.interface);
}

/// The CAN log's own topic, where the robot keeps a log.
std::unique_ptr<KindReport> CanLogReportOf(const CanRobot& robot) {
  return robot.log() != nullptr ? MakeCanLogReport(robot) : nullptr;
}

template <class Family>
using FactoryTable = std::map<std::string, KindFactory<Family>>;

/// Parts of an adapter alone: its camera is the vehicle file's.
template <class Family>
KindParts<Family> AdapterOnly(std::unique_ptr<typename Family::Adapter> adapter,
                              std::string detail = {}) {
  KindParts<Family> parts;
  parts.adapter = std::move(adapter);
  parts.detail = std::move(detail);
  return parts;
}

// The built-in kinds' factories, one row each beside its row in config's table.
template <class Family>
FactoryTable<Family>& Factories();

template <>
FactoryTable<RobotFamily>& Factories<RobotFamily>() {
  using Parts = KindParts<RobotFamily>;
  static FactoryTable<RobotFamily> table{
      {"sim-robot",
       [](const VehicleConfig& c, const Track& track) {
         return AdapterOnly<RobotFamily>(std::make_unique<SimRobot>(track, c));
       }},
      {"can-robot",
       [](const VehicleConfig& c, const Track&) {
         auto bus =
             std::make_unique<SocketCanBus>(c.can.interface);  // CanUnavailable: a set-up error
         auto robot = std::make_unique<CanRobot>(std::move(bus), c, OpenCanLog(c));
         std::unique_ptr<KindReport> report = CanLogReportOf(*robot);
         Parts parts = AdapterOnly<RobotFamily>(std::move(robot), ", CAN bus " + c.can.interface);
         parts.report = std::move(report);
         return parts;
       }},
      {"can-robot-sim",
       [](const VehicleConfig& c, const Track& track) {
         auto robot = std::make_unique<SimulatedCanRobot>(track, c, OpenCanLog(c));
         std::unique_ptr<KindReport> report = CanLogReportOf(robot->adapter());
         Parts parts = AdapterOnly<RobotFamily>(std::move(robot));
         parts.report = std::move(report);
         return parts;
       }},
      {"ros2",
       [](const VehicleConfig& c, const Track& track) {
         auto robot = std::make_unique<Ros2Robot>(c, track);
         // Its camera is its image topic (unless it names none).
         auto camera = robot->MakeCamera();
         return Parts{std::move(robot), std::move(camera),
                      ", ROS 2 robot on domain " + std::to_string(c.ros2.domain_id) + " (" +
                          c.ros2.cmd_vel + " out, " + c.ros2.odom + " in)",
                      nullptr};
       }},
  };
  return table;
}

template <>
FactoryTable<BlimpFamily>& Factories<BlimpFamily>() {
  static FactoryTable<BlimpFamily> table{
      {"sim-blimp",
       [](const VehicleConfig& c, const BlimpCourseConfig& course) {
         return AdapterOnly<BlimpFamily>(
             std::make_unique<SimBlimpAdapter>(c.airship, course, VehicleReality(c, nullptr)));
       }},
      {"servo-blimp",
       [](const VehicleConfig& c, const BlimpCourseConfig&) {
         if (c.servo.port.empty()) {
           throw UsageError(
               "the servo controller's serial port: give --serial-port PATH (or servo.port in " +
               c.file.string() + ")");
         }
         return AdapterOnly<BlimpFamily>(
             std::make_unique<ServoBlimpAdapter>(
                 c.ServoWithCameras(),
                 std::make_unique<servo::SerialPort>(c.servo.port, c.servo.baud)),
             ", servo controller on " + c.servo.port);
       }},
      {"servo-blimp-sim",
       [](const VehicleConfig& c, const BlimpCourseConfig& course) {
         return AdapterOnly<BlimpFamily>(std::make_unique<SimulatedServoBlimp>(
             c.ServoWithCameras(), c.airship, course, VehicleReality(c, nullptr)));
       }},
  };
  return table;
}

/// The world a family's simulator and camera live in, as its file names it.
std::unique_ptr<Track> LoadWorld(const std::filesystem::path& file, const RobotFamily*) {
  return std::make_unique<Track>(LoadTrack(file));
}
std::unique_ptr<BlimpCourseConfig> LoadWorld(const std::filesystem::path& file,
                                             const BlimpFamily*) {
  return std::make_unique<BlimpCourseConfig>(LoadBlimpCourse(file));
}
std::string WorldName(const Track& track) { return "track '" + track.config().name + "'"; }
std::string WorldName(const BlimpCourseConfig& course) { return "course '" + course.name + "'"; }
/// The camera the vehicle file describes, looking at the family's world.
std::unique_ptr<video::CameraSource> FileCamera(const VehicleConfig& c, const Track& track,
                                                const std::string& file) {
  return video::MakeCameraSource(c.camera, &track, file);
}
std::unique_ptr<video::CameraSource> FileCamera(const VehicleConfig& c,
                                                const BlimpCourseConfig& course,
                                                const std::string& file) {
  return video::MakeBlimpCameraSource(c.camera, course, file);
}

template <class Family>
OpenedVehicle Open(const VehicleConfig& config, const std::string& file) {
  const KindFactory<Family>* factory = FindKindFactory<Family>(config.kind);
  if (factory == nullptr) {
    throw std::invalid_argument("vehicle kind '" + config.kind + "' has no " +
                                ToString(Family::kFamily) + " adapter registered");
  }
  // Shared: the node's simulator (and camera) keep a reference to the world
  // for as long as the node runs.
  std::shared_ptr<const typename Family::World> world =
      LoadWorld(config.world, static_cast<const Family*>(nullptr));
  // The hardware first: a bus or port that cannot open stops here.
  KindParts<Family> parts = (*factory)(config, *world);
  if (parts.adapter == nullptr)
    throw std::logic_error("vehicle kind '" + config.kind + "': its factory made no adapter");
  if (!parts.camera) parts.camera = FileCamera(config, *world, file);
  // Every further camera the vehicle file lists, looking at the same world.
  std::vector<std::unique_ptr<video::CameraSource>> extra;
  for (const CameraConfig& camera : config.extra_cameras) {
    VehicleConfig one = config;
    one.camera = camera;
    extra.push_back(FileCamera(one, *world, file));
  }
  OpenedVehicle opened;
  opened.description =
      WorldName(*world) + ", camera " + parts.camera->Describe() + " " +
      std::to_string(config.camera.width) + "x" + std::to_string(config.camera.height) + " at " +
      std::to_string(static_cast<int>(std::lround(config.camera.rate_hz))) + " Hz" + parts.detail;
  // The node owns the world with its adapter: a std::function must be
  // copyable, so the parts wait in a shared holder until it is built.
  for (size_t i = 0; i < extra.size(); ++i) {
    const CameraConfig& c = config.extra_cameras[i];
    opened.description += ", camera " + c.name + " " + extra[i]->Describe() + " " +
                          std::to_string(c.width) + "x" + std::to_string(c.height);
  }
  auto held = std::make_shared<KindParts<Family>>(std::move(parts));
  auto held_extra =
      std::make_shared<std::vector<std::unique_ptr<video::CameraSource>>>(std::move(extra));
  opened.make_node = [config, world, held, held_extra]() -> std::unique_ptr<Node> {
    // The world is a base declared first, so it outlives the node's own
    // destructor (which still steps the adapter once to stop it).
    struct WorldHolder {
      std::shared_ptr<const typename Family::World> world;
    };
    struct Owning final : WorldHolder, VehicleNodeOf<Family> {
      Owning(const VehicleConfig& c, std::shared_ptr<const typename Family::World> w,
             KindParts<Family>& p, std::vector<std::unique_ptr<video::CameraSource>>& extra)
          : WorldHolder{std::move(w)},
            VehicleNodeOf<Family>(c, std::move(p.camera), std::move(p.adapter), std::move(p.report),
                                  std::move(extra)) {}
    };
    return std::make_unique<Owning>(config, world, *held, *held_extra);
  };
  return opened;
}

}  // namespace

template <class Family>
const KindFactory<Family>* FindKindFactory(const std::string& kind) {
  const FactoryTable<Family>& table = Factories<Family>();
  const auto it = table.find(kind);
  return it == table.end() ? nullptr : &it->second;
}

template <class Family>
void RegisterKind(VehicleKindInfo info, KindFactory<Family> factory) {
  if (!factory) throw std::invalid_argument("vehicle kind '" + info.name + "': no factory");
  info.family = Family::kFamily;
  RegisterVehicleKind(info);  // refuses a name taken or malformed
  Factories<Family>().emplace(info.name, std::move(factory));
}

template const KindFactory<RobotFamily>* FindKindFactory<RobotFamily>(const std::string&);
template const KindFactory<BlimpFamily>* FindKindFactory<BlimpFamily>(const std::string&);
template void RegisterKind<RobotFamily>(VehicleKindInfo, KindFactory<RobotFamily>);
template void RegisterKind<BlimpFamily>(VehicleKindInfo, KindFactory<BlimpFamily>);

OpenedVehicle OpenVehicle(const VehicleConfig& config, const std::string& file) {
  if (config.world.empty()) {
    throw ConfigError(
        file +
        ": key 'world': expected the track file a simulated vehicle drives on (or a blimp's "
        "course; or --track FILE)");
  }
  switch (config.family()) {
    case VehicleFamily::kRobot:
      return Open<RobotFamily>(config, file);
    case VehicleFamily::kBlimp:
      return Open<BlimpFamily>(config, file);
  }
  throw std::logic_error("unknown vehicle family");
}

}  // namespace haptel::vehicles
