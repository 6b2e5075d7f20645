// `haptel run --fleet FILE`'s command line: one operator, several vehicles
// (mediator/fleet.hpp). Each vehicle is set up as `haptel run` sets up one
// (the same options, its own vehicle, world and name from the fleet file),
// the fleet is run, and each vehicle's run is recorded as a row of its own.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "haptel/app/run_command.hpp"
#include "haptel/config/error.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/json.hpp"
#include "haptel/core/log.hpp"
#include "haptel/core/stop_signals.hpp"
#include "haptel/link/security.hpp"
#include "haptel/mediator/fleet.hpp"
#include "haptel/mediator/run_setup.hpp"
#include "haptel/record/run_picture.hpp"
#include "haptel/record/unsaved_run.hpp"
#include "haptel/view/view_model.hpp"

namespace haptel::app {

using mediator::FleetResult;
using mediator::FleetSetup;
using mediator::FleetVehicleResult;
using mediator::Outcome;
using mediator::Recorder;
using mediator::RunRecord;
using mediator::SessionSetup;
using mediator::ViewKind;

namespace {

/// The options the fleet file sets for each vehicle.
constexpr const char* kPerVehicleOptions[] = {"track", "vehicle", "vehicle-name", "interface"};

/// `argv` without its --fleet option, and with `vehicle`'s own.
std::vector<std::string> VehicleArgv(int argc, const char* const* argv,
                                     const FleetVehicle& vehicle) {
  std::vector<std::string> out;
  for (int i = 0; i < argc; ++i) {
    const std::string word = argv[i];
    if (word == "--fleet") {
      ++i;
      continue;
    }
    if (word.rfind("--fleet=", 0) == 0) continue;
    // The fleet file's reality for this vehicle wins over the run's.
    if (!vehicle.reality.empty() && word == "--reality") {
      ++i;
      continue;
    }
    if (!vehicle.reality.empty() && word.rfind("--reality=", 0) == 0) continue;
    out.push_back(word);
  }
  if (!vehicle.reality.empty()) out.insert(out.end(), {"--reality", vehicle.reality.string()});
  out.insert(out.end(), {"--vehicle", vehicle.vehicle.string(), "--track", vehicle.world.string(),
                         "--vehicle-name", vehicle.name});
  if (!vehicle.interface.empty()) out.insert(out.end(), {"--interface", vehicle.interface});
  if (vehicle.attach) out.push_back("--attach");
  return out;
}

FleetSetup FleetSetupFromArgs(int argc, const char* const* argv, const Args& args) {
  for (const char* option : kPerVehicleOptions) {
    if (args.Value(option)) {
      throw UsageError(
          std::string("option --") + option +
          ": with --fleet each vehicle's comes from the fleet file (its 'vehicles' list)");
    }
  }
  FleetSetup setup;
  setup.fleet = LoadFleet(*args.Value("fleet"));

  for (const FleetVehicle& vehicle : setup.fleet.vehicles) {
    std::vector<std::string> words = VehicleArgv(argc, argv, vehicle);
    // The automatic operator unless told: a fleet runs unattended by
    // default. With --operator person each vehicle gets the interface a
    // person drives its kind with (the fleet file's, else the keys at the
    // simulated device), and the person's input goes to the driven one.
    if (std::find(words.begin(), words.end(), "--operator") == words.end()) {
      words.insert(words.end(), {"--operator", "auto"});
    }
    std::vector<const char*> pointers;
    for (const std::string& w : words) pointers.push_back(w.c_str());
    try {
      const Args vehicle_args =
          mediator::ParseRunArgs(static_cast<int>(pointers.size()), pointers.data());
      setup.vehicles.push_back(mediator::RunSetupFromArgs(vehicle_args));
    } catch (const ConfigError& e) {
      throw ConfigError(setup.fleet.file.string() + ": vehicle '" + vehicle.name +
                        "': " + e.what());
    } catch (const UsageError& e) {
      throw UsageError(setup.fleet.file.string() + ": vehicle '" + vehicle.name + "': " + e.what());
    }
  }
  const size_t most = view::Tiles::kMax;
  if (setup.vehicles.at(0).view != ViewKind::kNone && setup.vehicles.size() > most) {
    throw UsageError("option --view: a view shows at most " + std::to_string(view::Tiles::kMax) +
                     " vehicles (keys 1..9); " + setup.fleet.file.string() + " has " +
                     std::to_string(setup.vehicles.size()) + " (use --view none)");
  }
  return setup;
}

/// One vehicle's row (and its picture); or its fallback file. The row's id, 0 when not saved.
int64_t SaveVehicle(const SessionSetup& setup, Recorder& recorder, RunRecord& rec,
                    std::filesystem::path& unsaved) {
  int64_t id = 0;
  try {
    id = recorder.Save(rec);
    rec.id = id;
  } catch (const std::exception& e) {
    try {
      unsaved = record::WriteUnsavedRun(rec, setup.run.database, WallNs());
      std::fprintf(stderr, "haptel: run of '%s' not recorded: %s; its results are in %s\n",
                   rec.vehicle.c_str(), e.what(), unsaved.c_str());
    } catch (const std::exception& e2) {
      std::fprintf(stderr, "haptel: run of '%s' not recorded: %s; and %s\n", rec.vehicle.c_str(),
                   e.what(), e2.what());
    }
    return 0;
  }
  try {
    const std::filesystem::path png =
        std::filesystem::absolute(record::RunPicturePath(setup.run.database, id));
    if (setup.course) {
      record::WriteRunPicture(record::RenderBlimpRunPicture(rec, *setup.course), png);
    } else {
      record::DrawRunPicture(rec, setup.track, png);
    }
    recorder.SetPicture(id, png);
    rec.picture = png.string();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel: warning: run %lld is saved without its picture: %s\n",
                 static_cast<long long>(id), e.what());
  }
  return id;
}

std::string Ms(double ms) { return ms >= 0.0 ? JsonNumber(ms) : std::string("null"); }

std::string FleetJson(const FleetSetup& setup, const FleetResult& fleet,
                      const std::vector<int64_t>& ids, bool recorded) {
  std::ostringstream o;
  int completed = 0;
  for (const FleetVehicleResult& v : fleet.vehicles) completed += v.result.record.completed ? 1 : 0;
  o << "{\"fleet\":" << JsonString(setup.fleet.name)
    << ",\"fleet_run\":" << JsonString(fleet.fleet_run)
    << ",\"completed\":" << (fleet.outcome == Outcome::kCompleted ? "true" : "false")
    << ",\"outcome\":" << JsonString(ToString(fleet.outcome))
    << ",\"message\":" << JsonString(fleet.message)
    << ",\"vehicles_total\":" << fleet.vehicles.size() << ",\"vehicles_completed\":" << completed
    << ",\"handovers\":" << fleet.handover_ms.size()
    << ",\"handovers_untimed\":" << fleet.handovers_untimed
    << ",\"handover_ms_p50\":" << Ms(fleet.handover_ms_p50)
    << ",\"handover_ms_p95\":" << Ms(fleet.handover_ms_p95)
    << ",\"person_switches\":" << fleet.person_switches
    << ",\"operator_cpu_share\":" << JsonNumber(fleet.operator_cpu_share)
    << ",\"servo_period_p99_us\":" << JsonNumber(fleet.servo_period_p99_us)
    << ",\"servo_cue_period_p99_us\":" << Ms(fleet.servo_cue_period_p99_us)
    << ",\"servo_cue_ticks\":" << fleet.servo_cue_ticks
    << ",\"recorded\":" << (recorded ? "true" : "false")
    << ",\"database\":" << JsonString(setup.vehicles.at(0).run.database.string()) << ",\"lost\":[";
  for (size_t i = 0; i < fleet.lost.size(); ++i) o << (i ? "," : "") << JsonString(fleet.lost[i]);
  o << "],\"vehicles\":[";
  for (size_t i = 0; i < fleet.vehicles.size(); ++i) {
    const FleetVehicleResult& v = fleet.vehicles[i];
    const RunRecord& r = v.result.record;
    o << (i ? "," : "") << "{\"name\":" << JsonString(r.vehicle)
      << ",\"kind\":" << JsonString(r.vehicle_kind)
      << ",\"completed\":" << (r.completed ? "true" : "false")
      << ",\"outcome\":" << JsonString(r.outcome) << ",\"message\":" << JsonString(v.result.message)
      << ",\"lap_time_s\":" << JsonNumber(r.lap_time_s) << ",\"gates_passed\":" << r.gates_passed
      << ",\"gates_total\":" << r.gates_total << ",\"driven_s\":" << JsonNumber(v.driven_s)
      << ",\"neglected_s\":" << JsonNumber(v.neglected_s) << ",\"handovers\":" << v.handovers
      << ",\"selected\":" << JsonString(v.selected) << ",\"vehicle_pid\":" << r.vehicle_pid
      << ",\"distance_m\":" << JsonNumber(r.distance_m) << ",\"run_id\":" << ids[i]
      << ",\"reality\":"
      << (v.result.reality.empty() ? std::string("null")
                                   : "{\"name\":" + JsonString(v.result.reality) +
                                         ",\"seed\":" + std::to_string(v.result.reality_seed) + "}")
      << "}";
  }
  o << "]}";
  return o.str();
}

void PrintFleetSummary(std::FILE* out, const FleetSetup& setup, const FleetResult& fleet,
                       const std::vector<int64_t>& ids) {
  std::fprintf(out, "haptel: fleet '%s' %s — %s\n", setup.fleet.name.c_str(),
               ToString(fleet.outcome).c_str(), fleet.message.c_str());
  std::fprintf(out, "  %-12s %-10s %-16s %8s %7s %9s %11s %5s\n", "vehicle", "kind", "outcome",
               "lap s", "gates", "driven s", "neglected s", "run");
  for (size_t i = 0; i < fleet.vehicles.size(); ++i) {
    const FleetVehicleResult& v = fleet.vehicles[i];
    const RunRecord& r = v.result.record;
    char gates[16];
    std::snprintf(gates, sizeof gates, "%d/%d", r.gates_passed, r.gates_total);
    std::fprintf(out, "  %-12s %-10s %-16s %8.2f %7s %9.1f %11.1f %5lld\n", r.vehicle.c_str(),
                 r.vehicle_kind.c_str(), r.outcome.c_str(), r.lap_time_s, gates, v.driven_s,
                 v.neglected_s, static_cast<long long>(ids[i]));
  }
  if (fleet.handover_ms.empty()) {
    std::fprintf(out, "  no handover\n");
  } else {
    std::fprintf(out,
                 "  %zu handovers (switch to the new vehicle obeying): p50 %.0f ms, p95 %.0f ms\n",
                 fleet.handover_ms.size(), fleet.handover_ms_p50, fleet.handover_ms_p95);
  }
  if (fleet.handovers_untimed > 0) {
    std::fprintf(out, "  %d turns to a vehicle still starting (not timed)\n",
                 fleet.handovers_untimed);
  }
  std::fprintf(out,
               "  operator process CPU %.2f s per wall second; %d switches asked by the person\n",
               fleet.operator_cpu_share, fleet.person_switches);
  if (fleet.servo_cue_ticks > 0) {
    std::fprintf(out,
                 "  servo period p99 %.0f us over the run, %.0f us over the %llu ticks that played "
                 "the switch cue\n",
                 fleet.servo_period_p99_us, fleet.servo_cue_period_p99_us,
                 static_cast<unsigned long long>(fleet.servo_cue_ticks));
  }
  // Lost is a vehicle that answered and went silent; one never heard from is said apart.
  std::string lost;
  std::string silent;
  for (const std::string& n : fleet.lost) {
    const bool never = std::find(fleet.never_answered.begin(), fleet.never_answered.end(), n) !=
                       fleet.never_answered.end();
    std::string& list = never ? silent : lost;
    list += (list.empty() ? "" : ", ") + n;
  }
  const bool others = fleet.lost.size() < fleet.vehicles.size();
  if (!silent.empty()) {
    std::fprintf(
        out,
        "  no vehicle answered: %s (never heard from on domain %d: attached, is it running there? "
        "started, see its lines above)%s\n",
        silent.c_str(), setup.vehicles.at(0).run.link.domain_id,
        others ? "; the others went on" : "");
  }
  if (!lost.empty())
    std::fprintf(out, "  LOST mid-run: %s%s\n", lost.c_str(),
                 others ? " (the others went on)" : "");
  std::fprintf(out, "  recorded in %s as '%s'\n", setup.vehicles.at(0).run.database.c_str(),
               fleet.fleet_run.c_str());
}

}  // namespace

int RunFleetCommand(int argc, const char* const* argv, const std::atomic<bool>& interrupted) {
  bool json = false;
  bool insecure = false;
  const FleetSetup setup = cli::ReadInput([&] {
    const Args args = mediator::ParseRunArgs(argc, argv);
    if (!args.positional().empty()) {
      throw UsageError("unexpected argument '" + args.positional()[0] +
                       "' (options start with --)");
    }
    if (args.Flag("simulated-time")) {
      throw UsageError(
          "option --simulated-time: a fleet's vehicles run in processes of their own, in real "
          "time; "
          "simulated time steps one simulated robot in this process (drop --fleet)");
    }
    json = args.Flag("json");
    insecure = args.Flag("insecure");
    return FleetSetupFromArgs(argc, argv, args);
  });
  // Once for the fleet, for the first vehicle whose link reaches beyond the host.
  for (const SessionSetup& vehicle : setup.vehicles) {
    if (const std::string warning = link::InsecureLinkWarning(vehicle.run.link, insecure);
        !warning.empty()) {
      log::Warn(warning);
      break;
    }
  }
  auto recorder =
      cli::ReadInput([&] { return std::make_unique<Recorder>(setup.vehicles.at(0).run.database); });
  FleetResult fleet = mediator::RunSession(setup, interrupted);
  for (size_t i = 0; i < fleet.vehicles.size(); ++i)
    mediator::TakeReality(setup.vehicles[i], fleet.vehicles[i].result);
  std::vector<int64_t> ids;
  bool recorded = true;
  for (size_t i = 0; i < fleet.vehicles.size(); ++i) {
    std::filesystem::path unsaved;
    ids.push_back(
        SaveVehicle(setup.vehicles[i], *recorder, fleet.vehicles[i].result.record, unsaved));
    recorded = recorded && ids.back() != 0;
  }
  PrintFleetSummary(stderr, setup, fleet, ids);
  if (json) std::printf("%s\n", FleetJson(setup, fleet, ids, recorded).c_str());
  std::fflush(stdout);
  if (!recorded) return cli::kExitNotRecorded;
  return mediator::ExitCode(fleet.outcome);
}

}  // namespace haptel::app
