// Adding an interface and a device driver: both are defined and registered
// in this file alone, as a plug-in would be, and a run goes through the real
// catalogue and registry with them — `haptel run`'s setup reads the device
// file and the interface file, the session builds them, the lap is recorded.
// Its own program: the registrations would show in other tests' lists.
#include <atomic>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "haptel/app/in_process_robot.hpp"
#include "haptel/config/archives.hpp"
#include "haptel/config/check.hpp"
#include "haptel/config/device.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/gesture.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/haptics/device_drivers.hpp"
#include "haptel/haptics/device_factory.hpp"
#include "haptel/haptics/sim_device.hpp"
#include "haptel/interfaces/catalog.hpp"
#include "haptel/interfaces/gesture.hpp"
#include "haptel/mediator/run_setup.hpp"
#include "test_env.hpp"

using namespace haptel;

namespace {

// --- A test-only device driver: the simulated arms, opened by a factory that counts. ---

int devices_opened = 0;

const haptics::RegisterDeviceDriver kTestDriver{{
    .name = "test-sim",
    .simulated = true,
    .reads_trace = false,
    .reads_window = false,
    .calibration = haptics::CalibrationSource::kOptional,
    .check =
        [](const DeviceConfig& config) {
          if (!config.has_glove) config_check::Fail("has_glove", "true for the test-sim driver");
        },
    .available = nullptr,
    .make = [](const DeviceConfig& config,
               const OperatorConfig& muscle) -> std::unique_ptr<haptics::Device> {
      ++devices_opened;
      return std::make_unique<haptics::SimDevice>(config, muscle);
    },
}};

// --- A test-only interface: the gesture mapping under its own name, counting its updates. ---

/// Its own file's keys, named once (Serialize): read strictly and checked by
/// the same archives as the shipped interfaces' configs.
struct LeanConfig {
  std::string name;
  double command_rate_hz = 50.0;
  double lean_scale = 1.0;  ///< the gesture mapping's command, scaled
  GestureConfig gesture;    ///< the mapping it leans on (the shipped gesture file's)

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(name), config::Required{}, config::NonEmpty{});
    a->Visit(HAPTEL_NVP(command_rate_hz), config::Range{1.0, 1000.0});
    a->Visit(HAPTEL_NVP(lean_scale), config::Range{0.1, 1.0});
  }
  void ValidateOrThrow() const { config_detail::CheckFields(*this); }
};

LeanConfig LoadLean(const std::filesystem::path& file) {
  LeanConfig c = config_detail::LoadFile<LeanConfig>(file);
  c.gesture = LoadGesture(ShippedFile("config/interfaces/gesture.yaml"));
  return c;
}

int lean_updates = 0;

class LeanInterface final : public interfaces::MediatorInterface {
 public:
  explicit LeanInterface(const LeanConfig& config)
      : name_(config.name), scale_(config.lean_scale), mapping_(config.gesture) {}
  std::string name() const override { return name_; }
  TreadCommand Update(double t_s, const interfaces::VehicleFeedback& feedback,
                      haptics::Hal& hal) override {
    ++lean_updates;
    const TreadCommand full = mapping_.Update(t_s, feedback, hal);
    return TreadCommand{full.left * scale_, full.right * scale_};
  }
  interfaces::HandTargets HandTargetsFor(const interfaces::MotionIntent& intent) const override {
    return mapping_.HandTargetsFor(intent);
  }
  bool NeedsPhysics() const override { return false; }
  const char* Help(bool) const override { return "lean to drive"; }

 private:
  std::string name_;
  double scale_;
  interfaces::GestureInterface mapping_;
};

const interfaces::RegisterInterface<interfaces::RobotFamily, LeanConfig> kLeanInterface{
    {{.name = "test-lean",
      .family = VehicleFamily::kRobot,
      .hands = {false, true},
      .input = InterfaceInput::kHands,
      .physics = false,
      .summary = "the right hand leans the robot (a test's)"}},
    LoadLean,
    [](const LeanConfig& config, const interfaces::InterfaceParts&) {
      return std::make_unique<LeanInterface>(config);
    }};

std::string Read(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

void Write(const std::filesystem::path& file, const std::string& text) {
  std::ofstream(file) << text;
}

/// A run configuration in `dir` whose interfaces are the shipped ones and
/// the test's (its own interfaces folder), starting with `interface`.
std::filesystem::path RunConfigWith(const std::filesystem::path& dir,
                                    const std::string& interface) {
  const std::filesystem::path shipped = std::filesystem::absolute(ShippedFile("config"));
  std::filesystem::create_directories(dir / "interfaces");
  for (const auto& entry : std::filesystem::directory_iterator(shipped / "interfaces")) {
    std::filesystem::copy_file(entry.path(), dir / "interfaces" / entry.path().filename(),
                               std::filesystem::copy_options::overwrite_existing);
  }
  Write(dir / "interfaces" / "test-lean.yaml",
        "name: test-lean\ncommand_rate_hz: 40\nlean_scale: 0.9\n");
  // The shipped run's relative files, from the shipped folder.
  std::string run = Read(shipped / "haptel.yaml");
  run = std::regex_replace(run, std::regex(R"((\n(track|vehicle|device|physics|database): ))"),
                           "$1" + shipped.string() + "/");
  run = std::regex_replace(run, std::regex(R"(\ninterface: \S+)"), "\ninterface: " + interface);
  Write(dir / "haptel.yaml", run + "interfaces_dir: " + (dir / "interfaces").string() + "\n");
  return dir / "haptel.yaml";
}

/// A device file for the test's driver, otherwise the shipped sim's.
std::filesystem::path TestDevice(const std::filesystem::path& dir, bool glove = true) {
  std::string device = Read(ShippedFile("config/devices/sim.yaml"));
  device = std::regex_replace(device, std::regex(R"(\ndriver: sim)"), "\ndriver: test-sim");
  if (!glove) {
    device = std::regex_replace(device, std::regex(R"(\nhas_glove: true)"), "\nhas_glove: false");
  }
  const std::filesystem::path file = dir / (glove ? "test-sim.yaml" : "test-sim-gloveless.yaml");
  Write(file, device);
  return file;
}

mediator::SessionSetup Setup(const std::filesystem::path& dir, const std::string& interface) {
  const std::vector<std::string> words = {"run",
                                          "--config",
                                          RunConfigWith(dir, interface).string(),
                                          "--device",
                                          TestDevice(dir).string(),
                                          "--track",
                                          "config/tracks/test-short.yaml",
                                          "--operator",
                                          "auto",
                                          "--view",
                                          "none",
                                          "--quiet",
                                          "--simulated-time",
                                          "--database",
                                          (dir / "runs.db").string()};
  std::vector<const char*> argv;
  for (const std::string& w : words) argv.push_back(w.c_str());
  return mediator::RunSetupFromArgs(
      mediator::ParseRunArgs(static_cast<int>(argv.size()), argv.data()));
}

}  // namespace

TEST_CASE("a test's own interface and device driver register and drive a run",
          "[catalogue][extension]") {
  const auto dir = test::ScratchDir("extension");

  // Registered: the catalogue and the registry know them, and the config
  // loaders check names against them.
  const interfaces::InterfaceDescriptor* lean = interfaces::FindInterface("test-lean");
  REQUIRE(lean != nullptr);
  CHECK(lean->kind.hands == std::array<bool, 2>{false, true});
  CHECK(FindInterfaceKind("test-lean") != nullptr);
  CHECK_THAT(InterfaceKindNames(VehicleFamily::kRobot), Catch::Contains("test-lean"));
  REQUIRE(haptics::FindDeviceDriver("test-sim") != nullptr);
  CHECK_NOTHROW(LoadDevice(TestDevice(dir)));
  // The driver's own check runs with the common ones, naming its key.
  CHECK_THROWS_WITH(LoadDevice(TestDevice(dir, false)),
                    Catch::Contains("has_glove") && Catch::Contains("test-sim"));

  // A run with both, through `haptel run`'s setup and the one session loop.
  const mediator::SessionSetup setup = Setup(dir, "test-lean");
  REQUIRE(setup.interfaces.size() == 1);
  CHECK(setup.interfaces[0].name == "test-lean");
  REQUIRE(setup.interfaces[0].config_as<LeanConfig>() != nullptr);
  CHECK(setup.interfaces[0].config_as<LeanConfig>()->lean_scale == 0.9);
  CHECK(setup.interfaces[0].command_rate_hz() == 40.0);
  CHECK(setup.device.driver == "test-sim");
  app::RegisterInProcessRobot();
  record::Recorder recorder(setup.run.database);
  const std::atomic<bool> interrupted{false};
  const mediator::RecordedRun run = mediator::RunAndRecord(setup, recorder, interrupted);
  INFO(run.result.message);
  CHECK(devices_opened >= 1);
  CHECK(lean_updates > 100);
  CHECK(run.result.record.interface == "test-lean");
  CHECK(run.result.outcome == mediator::Outcome::kCompleted);
  CHECK(run.run_id != 0);
}

TEST_CASE("a test's own interface file is read as strictly as a shipped one",
          "[catalogue][extension]") {
  const auto dir = test::ScratchDir("extension-strict");
  Write(dir / "typo.yaml", "name: test-lean\nlean_scael: 0.5\n");
  CHECK_THROWS_WITH(LoadLean(dir / "typo.yaml"),
                    Catch::Contains((dir / "typo.yaml").string()) && Catch::Contains("lean_scael"));
  Write(dir / "range.yaml", "name: test-lean\nlean_scale: 3\n");
  CHECK_THROWS_WITH(LoadLean(dir / "range.yaml"),
                    Catch::Contains("lean_scale") && Catch::Contains("[0.1, 1]"));
}

TEST_CASE("a name neither the catalogue nor the registry holds is refused, naming theirs",
          "[catalogue][extension]") {
  const auto dir = test::ScratchDir("extension-unknown");
  Write(dir / "serial.yaml", "name: serial\ndriver: serial\n");
  CHECK_THROWS_WITH(LoadDevice(dir / "serial.yaml"), Catch::Contains("driver") &&
                                                         Catch::Contains("test-sim") &&
                                                         Catch::Contains("udp"));
  CHECK(interfaces::FindInterface("joystick") == nullptr);
  CHECK_THROWS_AS(haptics::MakeDevice([] {
                    DeviceConfig c;
                    c.driver = "serial";
                    return c;
                  }()),
                  ConfigFieldError);
}
