#include "haptel/app/link_commands.hpp"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <thread>
#include <filesystem>
#include <string>
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
    "usage: haptel security init DIR [--vehicles NAME,...] [--days N]\n"
    "  makes DIR for DDS Security: a CA (ca.pem, ca.key: keep it safe), the operator's identity\n"
    "  and one per vehicle (default robot1,blimp1), the signed governance (everything\n"
    "  authenticated and encrypted) and each identity's signed permissions (the operator\n"
    "  commands, a vehicle publishes only its own state and video), valid for N days\n"
    "  (default 365). Then: haptel run --security DIR, haptel-vehicle --security DIR.\n";

}  // namespace

int SecurityCommand(int argc, const char* const* argv) {
  return cli::Main({"haptel security", kUsage}, argc, argv, [&]() -> int {
    std::filesystem::path dir;
    std::vector<std::string> vehicles{"robot1", "blimp1"};
    int days = 365;
    cli::ReadInput([&] {
      const Args args(argc, argv, {"vehicles", "days"}, {});
      const auto& words = args.positional();
      if (words.empty() || words[0] != "init") throw UsageError("expected `haptel security init DIR`");
      if (words.size() != 2) throw UsageError("expected one folder: `haptel security init DIR`");
      dir = words[1];
      if (auto list = args.Value("vehicles")) {
        vehicles.clear();
        for (const std::string& name : SplitList(*list)) {
          std::string problem = VehicleNameProblem(name);
          if (problem.empty()) problem = link::VehicleIdentityProblem(name);
          if (!problem.empty()) throw UsageError("option --vehicles: '" + name + "': expected " + problem);
          vehicles.push_back(name);
        }
      }
      days = args.Int("days", 1, 3650).value_or(days);
      if (std::filesystem::exists(dir / "ca.pem")) {
        throw UsageError(dir.string() + " already holds a CA (ca.pem): nothing was changed; remove the folder or "
                         "choose another");
      }
      return 0;
    });
    link::InitSecurity(dir, vehicles, days);
    std::string names = link::OperatorIdentity();
    for (const auto& v : vehicles) names += ", " + link::VehicleIdentity(v);
    std::printf("wrote %s: CA, governance, identities %s (valid %d days)\n", dir.c_str(), names.c_str(), days);
    return 0;
  });
}

int DiscoveryServerCommand(int argc, const char* const* argv) {
  const std::atomic<bool>& stop = InstallStopSignals();
  return cli::Main({"haptel discovery-server",
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
