#include "physics_bench.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "haptel/config/paths.hpp"
#include "haptel/config/physics.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/child_process.hpp"
#include "physics_measure.hpp"
#include "plot.hpp"
#include "smoke.hpp"

namespace haptel::bench {

namespace {

using wp::Point;

bool Usable(const Point& p) { return std::isfinite(p.tracking_err_mm) && p.resets == 0; }

/// Indices of the points no other usable point beats in both CPU and tracking error.
std::vector<bool> ParetoFront(const std::vector<Point>& points) {
  std::vector<bool> front(points.size(), false);
  for (size_t i = 0; i < points.size(); ++i) {
    if (!Usable(points[i])) continue;
    bool dominated = false;
    for (size_t j = 0; j < points.size() && !dominated; ++j) {
      if (j == i || !Usable(points[j])) continue;
      const Point &a = points[j], &b = points[i];
      dominated = a.cpu_per_sim_s <= b.cpu_per_sim_s && a.tracking_err_mm <= b.tracking_err_mm &&
                  (a.cpu_per_sim_s < b.cpu_per_sim_s || a.tracking_err_mm < b.tracking_err_mm);
    }
    front[i] = !dominated;
  }
  return front;
}

bool Same(const Point& a, const Point& b) {
  return a.step_ms == b.step_ms && a.iterations == b.iterations && a.precision == b.precision;
}

}  // namespace

int BenchPhysicsMain(int argc, const char* const* argv) {
  bool json = false, with_float = true, smoke = false;
  PhysicsConfig config;
  std::string physics_file;
  try {
    const Args args(argc, argv, {"physics"}, {"json", "no-float", kSmokeFlag});
    json = args.Flag("json");
    smoke = args.Flag(kSmokeFlag);
    with_float = !args.Flag("no-float");
    physics_file = args.Value("physics").value_or(ShippedFile("config/physics.yaml").string());
    config = LoadPhysics(physics_file);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel bench physics: %s\n", e.what());
    return 2;
  }
  config.realtime_priority = 0;
  const double default_step_ms = 1e3 * config.step_s;
  const int default_iterations = config.solver_iterations;
  const wp::Plan plan = smoke ? wp::SmokePlan() : wp::FullPlan();
  PrintSmokeNote("physics", smoke,
                 "%zu steps x %zu iteration counts, %.1f s trajectory, %.1f s push, %.1f s hold",
                 plan.steps_ms.size(), plan.iterations.size(), plan.trajectory_s, plan.push_s,
                 plan.grasp_hold_s);

  const auto dir = OutputDir(smoke);
  const auto traj_file = dir / "trajectory.csv";
  const auto ref_file = dir / "physics_reference.csv";
  std::vector<Point> points;
  Point def;
  std::string float_note;
  try {
    std::optional<wp::Trajectory> loaded = wp::LoadTrajectory(traj_file, plan.trajectory_s);
    const bool made = !loaded;
    if (made) {
      loaded = wp::MakeTrajectory(plan.trajectory_s);
      wp::SaveTrajectory(traj_file, *loaded);
    }
    const wp::Trajectory& tr = *loaded;
    std::printf("haptel bench physics: trajectory %s (%s, %.1f s, %zu samples at %.2f ms)\n",
                traj_file.c_str(), made ? "written" : "read back", tr.duration(),
                tr.position.size(), 1e3 * tr.dt);
    const std::vector<wp::Vec3d> reference = wp::ReferenceRun(config, tr);
    wp::SaveReference(ref_file, reference);

    // The float child runs on the other core while this thread measures double.
    std::unique_ptr<ChildProcess> child;
    if (with_float) {
      const auto exe = ProgramDirectory() / "haptel-physics-bench-float";
      if (!std::filesystem::exists(exe)) {
        float_note =
            "float: " + exe.string() + " not found (build it: target haptel-physics-bench-float)";
      } else {
        try {
          std::vector<std::string> child_args{"--trajectory",    traj_file.string(), "--reference",
                                              ref_file.string(), "--physics",        physics_file};
          if (smoke) child_args.push_back("--smoke");
          child =
              std::make_unique<ChildProcess>(exe.string(), child_args, ChildProcess::Options{true});
        } catch (const std::exception& e) {
          float_note = std::string("float: ") + e.what();
        }
      }
    } else {
      float_note = "float: skipped (--no-float)";
    }

    bool default_in_grid = false;
    for (const double step_ms : plan.steps_ms) {
      for (const int iterations : plan.iterations) {
        points.push_back(wp::Measure(config, tr, reference, step_ms, iterations, "double", plan));
        if (std::abs(step_ms - default_step_ms) < 1e-9 && iterations == default_iterations) {
          def = points.back();
          default_in_grid = true;
        }
      }
    }
    if (!default_in_grid) {
      const double ratio = default_step_ms / wp::kStepsMs.front();
      if (std::abs(ratio - std::round(ratio)) > 1e-9) {
        throw std::runtime_error("the default step is not a multiple of 0.25 ms");
      }
      def = wp::Measure(config, tr, reference, default_step_ms, default_iterations, "double", plan);
      points.push_back(def);
    }

    if (child) {
      // Its few result lines fit the pipe; read them once it is done.
      const int status = child->Wait(600.0);
      const std::vector<Point> floats = wp::ParsePoints(child->out());
      if (!child->err().empty()) std::fputs(child->err().c_str(), stderr);
      if (status != 0 || floats.empty()) {
        float_note = "float: haptel-physics-bench-float failed (status " + std::to_string(status) +
                     "): double points only";
      } else {
        points.insert(points.end(), floats.begin(), floats.end());
        float_note = "float: " + std::to_string(floats.size()) +
                     " points from haptel-physics-bench-float " +
                     "(same sources, float Bullet, compared with the same double reference)";
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel bench physics: %s\n", e.what());
    return 1;
  }

  std::stable_sort(points.begin(), points.end(), [](const Point& a, const Point& b) {
    return a.cpu_per_sim_s < b.cpu_per_sim_s;
  });
  const std::vector<bool> front = ParetoFront(points);
  bool def_on_front = false;
  double best_err_at_cpu = INFINITY, best_cpu_at_err = INFINITY;
  for (size_t i = 0; i < points.size(); ++i) {
    if (Same(points[i], def)) def_on_front = front[i];
    if (!front[i]) continue;
    if (points[i].cpu_per_sim_s <= def.cpu_per_sim_s)
      best_err_at_cpu = std::min(best_err_at_cpu, points[i].tracking_err_mm);
    if (points[i].tracking_err_mm <= def.tracking_err_mm)
      best_cpu_at_err = std::min(best_cpu_at_err, points[i].cpu_per_sim_s);
  }
  const double err_ratio = std::isfinite(best_err_at_cpu) && best_err_at_cpu > 0
                               ? def.tracking_err_mm / best_err_at_cpu
                               : 1.0;
  const double cpu_ratio = std::isfinite(best_cpu_at_err) && best_cpu_at_err > 0
                               ? def.cpu_per_sim_s / best_cpu_at_err
                               : 1.0;

  std::printf(
      "  reference: double, %.3g ms step, %d iterations; tracking error = RMS |proxy - reference "
      "proxy| over %.1f s\n\n",
      wp::kReferenceStepMs, wp::kReferenceIterations, plan.trajectory_s);
  std::printf("%8s %5s %-6s %11s %11s %9s %9s %9s %9s %6s %6s\n", "step ms", "iter", "prec",
              "cpu s/sim s", "track mm", "lag mm", "pen mm", "pen rest", "slip mm", "reset",
              "front");
  for (size_t i = 0; i < points.size(); ++i) {
    const Point& p = points[i];
    std::printf("%8.3g %5d %-6s %11.4f %11.4g %9.3f %9.3f %9.3f %9.3f %6ld %6s%s\n", p.step_ms,
                p.iterations, p.precision.c_str(), p.cpu_per_sim_s, p.tracking_err_mm, p.lag_mm,
                p.penetration_mm, p.penetration_rest_mm, p.slip_mm, p.resets, front[i] ? "*" : "",
                Same(p, def) ? "  <- default" : "");
  }
  std::printf(
      "\n  sorted by cpu s/sim s: thread CPU per simulated second over the three scenarios (%g s "
      "tracking,\n"
      "  %g s push, %g s two-hand grasp); track: RMS vs the reference; lag: RMS |proxy - tracked "
      "wrist|;\n"
      "  pen: deepest penetration of a 10 N push, touch-down at 0.1 m/s included; pen rest: mean "
      "over its last\n"
      "  0.2 s (negative: resting above the surface);\n"
      "  slip: box motion relative to the palms over a %g s hold; reset: NaN/Inf resets (such "
      "points are\n"
      "  left off the front); front: Pareto front over (cpu, track), both precisions.\n",
      plan.trajectory_s, plan.push_s, plan.grasp_s(), plan.grasp_hold_s);
  std::printf("  %s\n", float_note.c_str());
  if (def_on_front) {
    std::printf("  default (%g ms, %d iterations, double): on the Pareto front\n", default_step_ms,
                default_iterations);
  } else {
    std::printf(
        "  default (%g ms, %d iterations, double): off the front; at no more CPU the front has "
        "%.3gx less\n"
        "  tracking error, at no more error it needs %.3gx less CPU\n",
        default_step_ms, default_iterations, err_ratio, cpu_ratio);
  }

  {
    std::ofstream csv(dir / "physics.csv");
    csv << "step_ms,iterations,precision,cpu_per_sim_s,tracking_err_mm,lag_mm,penetration_mm,"
           "penetration_rest_mm,"
           "slip_mm,resets,pareto,default\n";
    for (size_t i = 0; i < points.size(); ++i) {
      const Point& p = points[i];
      csv << p.step_ms << "," << p.iterations << "," << p.precision << "," << p.cpu_per_sim_s << ","
          << p.tracking_err_mm << "," << p.lag_mm << "," << p.penetration_mm << ","
          << p.penetration_rest_mm << "," << p.slip_mm << "," << p.resets << ","
          << (front[i] ? 1 : 0) << "," << (Same(p, def) ? 1 : 0) << "\n";
    }
  }
  std::printf("\n  wrote %s\n", (dir / "physics.csv").c_str());

  {
    // PlotLines has a log y axis only: x is plotted as log10(cpu). One series
    // per precision and iteration count (its six colours: the front is in the
    // table and the CSV, not drawn).
    std::vector<Series> series;
    for (const char* precision : {"double", "float"}) {
      for (const int iterations : plan.iterations) {
        Series s{
            std::string(precision) + ", " + std::to_string(iterations) + " iterations", {}, {}};
        for (const Point& p : points) {  // already sorted by cpu
          if (p.precision != precision || p.iterations != iterations) continue;
          if (!std::isfinite(p.tracking_err_mm) || p.cpu_per_sim_s <= 0) continue;
          s.x.push_back(std::log10(p.cpu_per_sim_s));
          s.y.push_back(p.tracking_err_mm);
        }
        if (!s.x.empty()) series.push_back(s);
      }
    }
    PlotOptions o;
    char title[160];
    std::snprintf(title, sizeof title, "physics work-precision: default %g ms / %d it. %s",
                  default_step_ms, default_iterations,
                  def_on_front ? "on the front" : "off the front");
    o.title = title;
    o.x_label = "log10(cpu s per simulated s)";
    o.y_label = "tracking error vs reference, mm";
    o.log_y = true;
    try {
      PlotLines(dir / "physics_pareto.png", series, o);
      std::printf("  wrote %s\n", (dir / "physics_pareto.png").c_str());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "haptel bench physics: %s\n", e.what());
    }
  }

  if (json) {
    std::ostringstream o;
    o << "{\"points\":[";
    for (size_t i = 0; i < points.size(); ++i) o << (i ? "," : "") << wp::ToJson(points[i], false);
    o << "],\"default\":" << wp::ToJson(def, false)
      << ",\"default_on_front\":" << (def_on_front ? "true" : "false")
      << ",\"default_error_ratio\":" << err_ratio << ",\"default_cpu_ratio\":" << cpu_ratio
      << ",\"pareto\":[";
    bool first = true;
    for (size_t i = 0; i < points.size(); ++i) {
      if (!front[i]) continue;
      o << (first ? "" : ",") << wp::ToJson(points[i], false);
      first = false;
    }
    o << "]}";
    std::printf("%s\n", JsonLine(o.str(), smoke).c_str());
  }
  return 0;
}

}  // namespace haptel::bench
