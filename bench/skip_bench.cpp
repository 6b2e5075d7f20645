#include "skip_bench.hpp"

#include <time.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "haptel/core/clock.hpp"
#include "haptel/haptics/vec_math.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/physics.hpp"
#include "haptel/config/scene.hpp"
#include "haptel/core/args.hpp"
#include "haptel/physics/scene_builder.hpp"
#include "haptel/physics/world.hpp"
#include "plot.hpp"

namespace haptel::bench {

namespace {

using haptics::Side;

constexpr double kWarmupS = 2.5;  ///< Bullet: asleep after 2 s at rest
constexpr double kBoxHalf = 0.05;

struct Result {
  std::string name;
  std::string description;
  bool world = false;
  int boxes = 0;
  int boxes_asleep = 0;
  long steps = 0;
  double sim_s = 0.0;
  double cpu_s = 0.0;
  double cpu_per_sim_s() const { return sim_s > 0.0 ? cpu_s / sim_s : 0.0; }
};

/// `n` boxes resting on the floor around the table: the cells of a 0.3 m grid
/// outside the table's footprint, nearest first, each jittered and turned.
std::vector<SceneObject> FloorBoxes(int n) {
  struct Cell {
    double x, y;
  };
  std::vector<Cell> cells;
  const double pitch = 0.3;
  for (int i = -40; i <= 40; ++i) {
    for (int j = -40; j <= 40; ++j) {
      const double x = i * pitch, y = j * pitch;
      if (std::abs(x) < 0.8 && std::abs(y) < 0.6) continue;  // under and next to the table
      cells.push_back({x, y});
    }
  }
  std::stable_sort(cells.begin(), cells.end(), [](const Cell& a, const Cell& b) {
    return a.x * a.x + a.y * a.y < b.x * b.x + b.y * b.y;
  });
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> jitter(-0.05, 0.05);
  std::uniform_real_distribution<double> yaw(-M_PI, M_PI);
  std::vector<SceneObject> boxes;
  for (int k = 0; k < n && k < static_cast<int>(cells.size()); ++k) {
    SceneObject o;
    o.name = "floor_box_" + std::to_string(k);
    o.dynamic = true;
    o.mass = 0.5;
    o.position = {cells[k].x + jitter(rng), cells[k].y + jitter(rng), kBoxHalf};
    o.rotation = Eigen::AngleAxisd(yaw(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    SceneShape s;
    s.kind = ShapeKind::kBox;
    s.half_extents = Eigen::Vector3d::Constant(kBoxHalf);
    o.shapes.push_back(s);
    boxes.push_back(std::move(o));
  }
  return boxes;
}

/// The operator's hands hovering above the table, moving gently (2 cm, 0.5 Hz).
haptics::HandSample HoveringHand(Side side, double t) {
  const double x = side == Side::kLeft ? -0.25 : 0.25;
  const double w = 2.0 * M_PI * 0.5;
  return haptics::TrackedHand({x + 0.02 * std::sin(w * t), -0.1 + 0.02 * std::cos(w * t), 0.95});
}

void Run(physics::PhysicsWorld& world, double& t, double seconds) {
  const double h = world.config().step_s;
  const long steps = std::lround(seconds / h);
  for (long i = 0; i < steps; ++i) {
    for (Side side : {Side::kLeft, Side::kRight}) {
      if (physics::ProxyHand* hand = world.hand(side)) hand->SetTracked(HoveringHand(side, t));
    }
    world.Step();
    t += h;
  }
}

Result MeasureCockpit(const PhysicsConfig& config, const Scene& table, int boxes, double seconds,
                      const std::string& name) {
  Result r;
  r.name = name;
  r.boxes = boxes;
  Scene scene = table;
  for (SceneObject& o : FloorBoxes(boxes)) scene.objects.push_back(std::move(o));
  r.description = "hands + table + " + std::to_string(boxes) + " boxes on the floor";
  auto world = physics::PhysicsWorld::CreateIfNeeded(config, physics::NeedsOf(scene, true));
  r.world = world != nullptr;
  world->AddHand(Side::kLeft);
  world->AddHand(Side::kRight);
  const physics::BuiltScene built = physics::BuildScene(*world, scene);
  double t = 0.0;
  Run(*world, t, kWarmupS);
  const long steps_before = static_cast<long>(world->Counters().steps);
  const double cpu0 = ThreadCpuSeconds();
  Run(*world, t, seconds);
  r.cpu_s = ThreadCpuSeconds() - cpu0;
  r.steps = static_cast<long>(world->Counters().steps) - steps_before;
  r.sim_s = static_cast<double>(r.steps) * config.step_s;
  for (const physics::SceneBody& node : built.nodes) {
    if (node.dynamic && scene.objects[node.object].name.rfind("floor_box_", 0) == 0 &&
        world->BodySleeping(node.body)) {
      ++r.boxes_asleep;
    }
  }
  return r;
}

std::string Number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace

int BenchSkipMain(int argc, const char* const* argv) {
  double seconds = 2.0;
  bool json = false;
  PhysicsConfig config;
  Scene table;
  try {
    const Args args(argc, argv, {"physics", "seconds"}, {"json"});
    json = args.Flag("json");
    if (auto s = args.Value("seconds")) {
      seconds = std::stod(*s);
      if (!(seconds >= 0.1 && seconds <= 60)) throw UsageError("--seconds: expected a number in [0.1, 60]");
    }
    config = LoadPhysics(args.Value("physics").value_or(ShippedFile("config/physics.yaml").string()));
    table = LoadScene(ShippedFile("config/scenes/table.yaml"));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel bench skip: %s\n", e.what());
    return 2;
  }
  config.realtime_priority = 0;  // stepped on this thread, never started

  std::vector<Result> results;
  {  // gesture: no physical controls, no scene bodies.
    Result r;
    r.name = "gesture";
    r.description = "no controls, no bodies: no world";
    const auto world = physics::PhysicsWorld::CreateIfNeeded(config, physics::NeedsOf(Scene{}, false));
    r.world = world != nullptr;
    if (r.world) {
      std::fprintf(stderr, "haptel bench skip: the gesture interface got a physics world\n");
      return 1;
    }
    results.push_back(r);
  }
  Result cockpit = MeasureCockpit(config, table, 0, seconds, "cockpit");
  cockpit.description = "two proxy hands + table scene";
  results.push_back(cockpit);
  for (const int n : {0, 100, 1000}) {
    results.push_back(MeasureCockpit(config, table, n, seconds, "cockpit_sleeping_" + std::to_string(n)));
  }
  const double base = results[2].cpu_per_sim_s();

  std::printf("haptel bench skip: %.1f simulated s per world after %.1f s of warm-up, step %.4g s\n", seconds,
              kWarmupS, config.step_s);
  std::printf("  cockpit = two proxy hands + the table scene, without the wheel and throttle bodies\n"
              "  (CockpitControlsBody sits in the device frame, its hub at z = 0: in the table scene's floor)\n\n");
  std::printf("%-22s %-42s %6s %8s %10s %12s %9s\n", "world", "what", "world", "asleep", "us/step",
              "cpu s/sim s", "x slp_0");
  for (const Result& r : results) {
    const std::string asleep = r.boxes > 0 ? std::to_string(r.boxes_asleep) + "/" + std::to_string(r.boxes) : "-";
    const double us_per_step = r.steps > 0 ? 1e6 * r.cpu_s / static_cast<double>(r.steps) : 0.0;
    std::printf("%-22s %-42s %6s %8s %10.1f %12.4f %9.2f\n", r.name.c_str(), r.description.c_str(),
                r.world ? "yes" : "no", asleep.c_str(), us_per_step, r.cpu_per_sim_s(),
                base > 0.0 ? r.cpu_per_sim_s() / base : 0.0);
  }
  std::printf("\n  cpu s/sim s: thread CPU time spent stepping per simulated second (the share of\n"
              "  one core the physics thread needs); x slp_0: ratio to cockpit_sleeping_0 in this run;\n"
              "  asleep: floor boxes Bullet had put to sleep at the end.\n");

  const auto dir = BenchDir();
  {
    std::ofstream csv(dir / "skip.csv");
    csv << "world,has_world,boxes,boxes_asleep,steps,sim_s,cpu_s,cpu_per_sim_s,ratio_to_sleeping_0\n";
    for (const Result& r : results) {
      csv << r.name << "," << (r.world ? 1 : 0) << "," << r.boxes << "," << r.boxes_asleep << "," << r.steps << ","
          << r.sim_s << "," << r.cpu_s << "," << r.cpu_per_sim_s() << ","
          << (base > 0.0 ? r.cpu_per_sim_s() / base : 0.0) << "\n";
    }
  }
  std::printf("\n  wrote %s\n", (dir / "skip.csv").c_str());

  if (json) {
    std::ostringstream o;
    o << "{\"cpu_per_sim_s\":{";
    for (size_t i = 0; i < results.size(); ++i) {
      o << (i ? "," : "") << "\"" << results[i].name << "\":" << Number(results[i].cpu_per_sim_s());
    }
    o << "}}";
    std::printf("%s\n", o.str().c_str());
  }
  return 0;
}

}  // namespace haptel::bench
