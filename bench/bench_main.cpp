// haptel-bench: the benchmarks, a program of their own so that the product
// (`haptel`) links neither them nor the allocation counter they use (its
// global operator new would tax every allocation of a run). `haptel bench
// NAME ...` execs this program.
#include <cstdio>
#include <string>

#include "gravity_bench.hpp"
#include "physics_bench.hpp"
#include "servo_bench.hpp"
#include "skip_bench.hpp"
#include "stability_bench.hpp"
#include "view_bench.hpp"

namespace {

/// Each benchmark's options, for --help (what its own parser accepts).
struct Usage {
  const char* name;
  const char* options;
  const char* what;
};
constexpr Usage kUsage[] = {
    {"servo", "[--seconds S] [--device FILE] [--json]",
     "servo loop modes against an empty clock_nanosleep loop"},
    {"gravity", "[--device FILE] [--points N] [--counts N] [--seed S] [--grid-out FILE] [--json]",
     "gravity compensation: drift with it off and on"},
    {"skip", "[--physics FILE] [--seconds S] [--json]",
     "physics CPU per simulated second; what a scene skips"},
    {"physics", "[--physics FILE] [--no-float] [--json]",
     "work-precision: step x iterations x float/double"},
    {"stability", "[--physics FILE] [--minutes M] [--json]", "physics stress tests"},
    {"view", "[--seconds S] [--json]",
     "the operator's view: frame rate, CPU, video-to-screen, servo beside it"},
};

bool WantsHelp(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--help" || std::string(argv[i]) == "-h") return true;
  }
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace haptel::bench;
  const std::string which = argc > 1 ? argv[1] : "";
  if (WantsHelp(argc, argv) || which.empty()) {
    std::printf(
        "usage: haptel bench NAME [options]; each writes build/bench/NAME.csv, --json ends with "
        "one line\n");
    for (const Usage& u : kUsage) {
      if (which.empty() || which == "--help" || which == "-h" || which == u.name) {
        std::printf("  haptel bench %-9s %s\n      %s\n", u.name, u.options, u.what);
      }
    }
    return which.empty() ? 2 : 0;
  }
  // Each benchmark parses argv from its own name on.
  if (which == "servo") return BenchServoMain(argc - 1, argv + 1);
  if (which == "gravity") return BenchGravityMain(argc - 1, argv + 1);
  if (which == "skip") return BenchSkipMain(argc - 1, argv + 1);
  if (which == "physics") return BenchPhysicsMain(argc - 1, argv + 1);
  if (which == "stability") return BenchStabilityMain(argc - 1, argv + 1);
  if (which == "view") return BenchViewMain(argc - 1, argv + 1);
  std::fprintf(
      stderr,
      "haptel bench: expected one of: servo, gravity, skip, physics, stability, view (got '%s')\n",
      which.c_str());
  return 2;
}
