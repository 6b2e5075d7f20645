// haptel-physics-bench-float: the float-precision half of `haptel bench
// physics` (physics_bench.hpp). Built from the physics sources against float
// Bullet; links nothing that uses double Bullet. Reads the trajectory and the
// reference the parent wrote, measures the grid, prints one JSON line:
// {"points":[…]}.
#include <cstdio>
#include <exception>
#include <string>

#include "haptel/config/physics.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/cli.hpp"
#include "physics_measure.hpp"

int main(int argc, char** argv) {
  using namespace haptel;
  using namespace haptel::bench;
  constexpr const char* kUsage =
      "usage: haptel-physics-bench-float --trajectory FILE --reference FILE [--physics FILE] "
      "[--smoke]\n"
      "  the float half of `haptel bench physics`, which runs it; prints one JSON line;\n"
      "  --smoke: the smoke run's grid and scenarios (`haptel bench physics --smoke`)\n";
  return cli::Main({"haptel-physics-bench-float", kUsage}, argc, argv, [&] {
    const Args args(argc, argv, {"physics", "trajectory", "reference"}, {"smoke"});
    const wp::Plan plan = args.Flag("smoke") ? wp::SmokePlan() : wp::FullPlan();
    const auto traj_file = args.Value("trajectory");
    const auto ref_file = args.Value("reference");
    if (!traj_file || !ref_file)
      throw UsageError("--trajectory FILE and --reference FILE are required");
    const auto tr = wp::LoadTrajectory(*traj_file, plan.trajectory_s);
    const auto ref = wp::LoadReference(*ref_file);
    if (!tr || !ref) throw cli::InputError("cannot read the trajectory or the reference");
    PhysicsConfig config;
    if (const auto p = args.Value("physics")) config = LoadPhysics(*p);
    std::string out = "{\"points\":[";
    bool first = true;
    for (const double step_ms : plan.steps_ms) {
      for (const int iterations : plan.iterations) {
        const wp::Point p = wp::Measure(config, *tr, *ref, step_ms, iterations, "float", plan);
        if (!first) out += ',';
        out += wp::ToJson(p, true);
        first = false;
      }
    }
    std::printf("%s]}\n", out.c_str());
    return cli::kExitOk;
  });
}
