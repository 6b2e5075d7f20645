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

int main(int argc, char** argv) {
  using namespace haptel::bench;
  const std::string which = argc > 1 ? argv[1] : "";
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
