// haptel: the operator side. Each command is its own part; this only
// dispatches (`haptel run` drives one grand-prix lap).
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <string>

#include "haptel/app/in_process_robot.hpp"
#include "haptel/app/link_commands.hpp"
#include "haptel/app/record_command.hpp"
#include "haptel/app/replay_command.hpp"
#include "haptel/app/run_command.hpp"
#include "haptel/app/scene_command.hpp"
#include "haptel/app/station_command.hpp"
#include "haptel/app/study_command.hpp"
#include "haptel/calibration/calibration_procedure.hpp"
#include "haptel/core/child_process.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/log.hpp"

namespace {

constexpr const char* kUsage =
    "usage: haptel run [options]         drive one grand-prix lap (--help for options)\n"
    "       haptel calibrate [options]   calibrate a haptic device (--help for options)\n"
    "       haptel scene FILE [--json]   load a haptic scene, print its objects, mass and bounds\n"
    "       haptel study run FILE        run an A/B study; `haptel study report` reports on it,\n"
    "                                    `haptel study power` says how many participants it needs\n"
    "       haptel station --vehicle NAME --camera CAMERA  a camera station: steer and record one\n"
    "                                    camera of a vehicle (the blimp's surveillance camera)\n"
    "       haptel security init DIR     DDS Security: a CA and signed identities for the link\n"
    "       haptel discovery-server [--listen ADDR:PORT]  a Fast DDS discovery server for the "
    "link\n"
    "       haptel replay FILE.mcap      draw a session file's operator's view again (a window,\n"
    "                                    --mp4, --view none), or --drive its commands again\n"
    "       haptel replay --info FILE.mcap  a session file's channels, counts, rates, duration\n"
    "       haptel record --domain D FILE.mcap  record what a DDS domain shows into a session "
    "file\n"
    "       haptel record --recover IN OUT   a complete session file from a truncated one\n"
    "       haptel bench NAME [options]  benchmarks: servo, view, gravity, blimp, link, video,\n"
    "                                    fuzz, skip, physics, stability, soak, passivity, fleet, "
    "hands,\n"
    "                                    record;\n"
    "                                    --smoke for a short run of any (haptel bench --help\n"
    "                                    gives each one's options)\n"
    "\n"
    "Exit codes: 0 done, 1 failed while running, 2 bad arguments or configuration (nothing ran),\n"
    "3 the vehicle or the haptic device was lost, 4 results not recorded in the database\n"
    "(they are in the fallback file the message names), 5 results recorded but an output\n"
    "asked for failed to be written (the --record MP4, the vehicle's CAN bus log).\n";

/// The benchmarks are a program of their own (haptel-bench, beside this one).
int ExecBench(char** argv) {
  const std::string program = (haptel::ProgramDirectory() / "haptel-bench").string();
  argv[0] = const_cast<char*>("haptel-bench");
  execv(program.c_str(), argv);
  std::fprintf(stderr, "haptel bench: cannot run %s: %s\n", program.c_str(), std::strerror(errno));
  return haptel::cli::kExitFailed;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace haptel;
  log::SetProgram("haptel");
  app::RegisterInProcessRobot();  // haptel run --simulated-time (and each trial of a study's)
  // Each command parses argv from its own name on.
  const std::string command = argc > 1 ? argv[1] : "";
  if (command == "run") return app::RunCommand(argc - 1, argv + 1);
  if (command == "calibrate") return haptics::CalibrateMain(argc - 1, argv + 1);
  if (command == "scene") return app::SceneCommand(argc - 1, argv + 1, std::cout, std::cerr);
  if (command == "bench") return ExecBench(argv + 1);
  if (command == "study") return app::StudyCommand(argc - 1, argv + 1);
  if (command == "station") return app::StationCommand(argc - 1, argv + 1);
  if (command == "security") return app::SecurityCommand(argc - 1, argv + 1);
  if (command == "discovery-server") return app::DiscoveryServerCommand(argc - 1, argv + 1);
  if (command == "replay") return app::ReplayCommand(argc - 1, argv + 1);
  if (command == "record") return app::RecordCommand(argc - 1, argv + 1);
  return cli::Main({"haptel", kUsage}, argc, argv, [&]() -> int {
    if (command.empty())
      throw UsageError(
          "missing command (run, station, calibrate, scene, study, replay, record, security, "
          "discovery-server, bench)");
    throw UsageError(
        "unknown command '" + command +
        "' (run, station, calibrate, scene, study, replay, record, security, discovery-server, "
        "bench)");
  });
}
