#include "haptel/app/link_commands.hpp"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "haptel/config/vehicle.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/stop_signals.hpp"
#include "haptel/link/participant.hpp"
#include "haptel/link/security.hpp"

namespace haptel::app {

namespace {

constexpr const char* kUsage =
    "usage: haptel security init DIR [--vehicles NAME,...] [--cameras NAME,...] [--console "
    "NAME,...]\n"
    "                                [--days N]\n"
    "       haptel security console DIR --console NAME,... [--days N]\n"
    "  makes DIR for DDS Security: a CA (ca.pem, ca.key: keep it safe), the operator's identity,\n"
    "  one per vehicle (default robot1,blimp1) and one per camera for its stations (identity\n"
    "  camera-NAME, default surveillance), the signed governance (everything authenticated and\n"
    "  encrypted) and each identity's signed permissions (the operator commands, a vehicle\n"
    "  publishes only its own state and video, a camera station steers only that camera and\n"
    "  cannot drive), valid for N days (default 365). Then: haptel run --security DIR,\n"
    "  haptel-vehicle --security DIR, haptel station --security DIR.\n"
    "  --console NAME,...: also the study console's HTTPS certificate (console.pem, console.key)\n"
    "  for those host names or addresses, signed by the CA: haptel study run --bind ADDR --tls "
    "DIR.\n"
    "  `security console` adds that certificate to a folder made before.\n";

}  // namespace

int SecurityCommand(int argc, const char* const* argv) {
  return cli::Main({"haptel security", kUsage}, argc, argv, [&]() -> int {
    std::filesystem::path dir;
    std::vector<std::string> vehicles{"robot1", "blimp1"};
    std::vector<std::string> cameras{"surveillance"};
    std::vector<std::string> console_names;
    int days = 365;
    bool console_only = false;
    cli::ReadInput([&] {
      const Args args(argc, argv, {"vehicles", "cameras", "days", "console"}, {});
      const auto& words = args.positional();
      if (words.empty() || (words[0] != "init" && words[0] != "console")) {
        throw UsageError(
            "expected `haptel security init DIR` or `haptel security console DIR --console "
            "NAME,...`");
      }
      if (words.size() != 2)
        throw UsageError("expected one folder: `haptel security " + words[0] + " DIR`");
      console_only = words[0] == "console";
      dir = words[1];
      if (auto list = args.Value("console")) {
        for (const std::string& name : SplitList(*list)) {
          if (const std::string problem = link::ConsoleNameProblem(name); !problem.empty()) {
            throw UsageError("option --console: '" + name + "': expected " + problem);
          }
          console_names.push_back(name);
        }
      }
      days = args.Int("days", 1, 3650).value_or(days);
      if (console_only) {
        if (console_names.empty())
          throw UsageError("option --console: expected the console's names (NAME,...)");
        return 0;
      }
      if (auto list = args.Value("vehicles")) {
        vehicles.clear();
        for (const std::string& name : SplitList(*list)) {
          std::string problem = VehicleNameProblem(name);
          if (problem.empty()) problem = link::VehicleIdentityProblem(name);
          if (!problem.empty())
            throw UsageError("option --vehicles: '" + name + "': expected " + problem);
          vehicles.push_back(name);
        }
      }
      if (auto list = args.Value("cameras")) {
        cameras.clear();
        for (const std::string& name : SplitList(*list)) {
          if (const std::string problem = link::CameraIdentityProblem(name); !problem.empty())
            throw UsageError("option --cameras: '" + name + "': expected " + problem);
          cameras.push_back(name);
        }
      }
      // A folder with identities, or anything else in it: refused before anything is made (exit 2).
      if (const std::string problem = link::InitFolderProblem(dir); !problem.empty())
        throw UsageError(problem);
      return 0;
    });
    if (console_only) {
      link::AddConsoleCertificate(dir, console_names, days);
      std::printf("wrote %s/console.pem and console.key for %s (valid %d days)\n", dir.c_str(),
                  JoinList(console_names).c_str(), days);
      return 0;
    }
    link::InitSecurity(dir, vehicles, days, console_names, cameras);
    std::string names = link::OperatorIdentity();
    for (const auto& v : vehicles) names += ", " + link::VehicleIdentity(v);
    std::string stations;
    for (const auto& c : cameras)
      stations += (stations.empty() ? "" : ", ") + link::CameraIdentity(c);
    if (!stations.empty()) stations = "; camera stations " + stations;
    if (!console_names.empty())
      stations += "; the console's certificate for " + JoinList(console_names);
    std::printf("wrote %s: CA, governance, identities %s (valid %d days)%s\n", dir.c_str(),
                names.c_str(), days, stations.c_str());
    return 0;
  });
}

int DiscoveryServerCommand(int argc, const char* const* argv) {
  const std::atomic<bool>& stop = InstallStopSignals();
  return cli::Main(
      {"haptel discovery-server",
       "usage: haptel discovery-server [--listen ADDR:PORT]   (default 127.0.0.1:11811)\n"
       "  serves Fast DDS discovery; then --discovery-server ADDR:PORT on haptel run and\n"
       "  haptel-vehicle. Ends on SIGINT or SIGTERM.\n"},
      argc, argv, [&]() -> int {
        std::string listen = "127.0.0.1:11811";
        cli::ReadInput([&] {
          const Args args(argc, argv, {"listen"}, {});
          if (auto l = args.Value("listen")) {
            try {
              ParseServerAddress(*l);
            } catch (const std::invalid_argument& e) {
              throw UsageError(std::string("option --listen: expected ") + e.what());
            }
            listen = *l;
          }
          return 0;
        });
        const auto [address, port] = ParseServerAddress(listen);
        link::DiscoveryServer server(address, port);
        std::printf("haptel discovery-server: serving on %s\n", listen.c_str());
        std::fflush(stdout);
        while (!stop.load()) std::this_thread::sleep_for(std::chrono::milliseconds(50));
        return 0;
      });
}

}  // namespace haptel::app
