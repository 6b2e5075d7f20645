#include "gravity_bench.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "haptel/calibration/calibration.hpp"
#include "haptel/calibration/calibration_procedure.hpp"
#include "haptel/config/device.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/gravity_grid.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/run.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/json.hpp"
#include "haptel/haptics/device_drivers.hpp"
#include "haptel/testing/vec_math.hpp"
#include "plot.hpp"
#include "smoke.hpp"

namespace haptel::bench {

namespace {

using haptics::Distance;
using haptics::GravityGrid;
using haptics::Side;
using haptics::SimDevice;
using haptics::Vec3d;

constexpr int64_t kMs = 1'000'000;
constexpr double kBoxMargin = 0.05;    ///< m between the sampled box and the hard stops
constexpr double kDriftSeconds = 1.0;  ///< simulated time per release

constexpr const char* kUsage =
    "usage: haptel bench gravity [options]\n"
    "  --device FILE    sim device file (default config/devices/sim.yaml)\n"
    "  --points N       release points in the box (default 50)\n"
    "  --seed S         seed of the release points (default 1)\n"
    "  --counts N       grid vertices per axis (default 5)\n"
    "  --grid-out FILE  where to save the sampled grid (default build/bench/gravity_grid.yaml)\n"
    "  --smoke          a short run for the tests: 3 points, a 2x2x2 grid (outputs in "
    "build/bench/smoke/)\n"
    "  --json           end with one JSON line of results\n";

/// The compensation command for a tracker reading, as the servo loop does it.
Vec3d CompensationCommand(const ArmCalibration& c, const GravityGrid* grid, const Vec3d& raw) {
  if (grid == nullptr) return {};
  return {0.0, 0.0, grid->Evaluate(haptics::TrackerToMetres(c, raw)) / c.force_slope[2]};
}

struct PointResult {
  Vec3d start{};
  double weight_n = 0.0;  ///< true unbalanced weight there
  double grid_n = 0.0;    ///< compensation there
  double off_m_s = 0.0;
  double on_m_s = 0.0;
};

}  // namespace

ArmCalibration SimTruthCalibration(const SimDevice& device, Side side) {
  const haptics::SimArmTruth& t = device.truth(side);
  ArmCalibration c;
  c.tracker_scale = t.tracker_scale;
  c.tracker_offset = t.tracker_offset;
  c.force_slope = t.force_slope;
  c.finger_force_slope = t.finger_force_slope;
  for (int j = 0; j < kCalibrationGloveSensors && j < haptics::kGloveJoints; ++j) {
    c.glove_gain[j] = t.glove_gain[j];
    c.glove_offset[j] = t.glove_offset[j];
  }
  return c;
}

double MeasureDrift(SimDevice& device, Side side, const ArmCalibration& calibration,
                    const GravityGrid* grid, const Vec3d& start, double seconds, int64_t& now_ns) {
  device.Place(side, start);
  haptics::WristRaw raw;
  // Read at the same time stamp (no simulated time passes): the compensation
  // is already running when the operator lets go.
  device.ReadWrist(side, now_ns, raw);
  device.WriteWristForce(side, CompensationCommand(calibration, grid, raw.position));
  device.Release(side);
  const Vec3d released = device.TruePosition(side);
  const int ticks = static_cast<int>(std::llround(seconds * 1000.0));
  for (int i = 0; i < ticks; ++i) {
    now_ns += kMs;
    device.ReadWrist(side, now_ns, raw);
    device.WriteWristForce(side, CompensationCommand(calibration, grid, raw.position));
  }
  device.WriteWristForce(side, Vec3d{});
  return Distance(device.TruePosition(side), released) / seconds;
}

int BenchGravityMain(int argc, const char* const* argv) {
  DeviceConfig config;
  int points = 50;
  int seed = 1;
  int counts = 5;
  bool json = false, smoke = false;
  std::filesystem::path grid_out;
  try {
    const Args args(argc, argv, {"device", "points", "seed", "counts", "grid-out"},
                    {"json", "help", kSmokeFlag});
    if (args.Flag("help")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    for (const std::string& word : args.positional()) {
      if (word != "bench" && word != "gravity")
        throw UsageError("unexpected argument '" + word + "'");
    }
    json = args.Flag("json");
    smoke = args.Flag(kSmokeFlag);
    if (smoke) {  // the fewest vertices a trilinear grid has, and a few releases
      points = 3;
      counts = 2;
    }
    points = args.Int("points", 1, 100000).value_or(points);
    seed = args.Int("seed", 0, 1 << 30).value_or(seed);
    counts = args.Int("counts", 2, 50).value_or(counts);
    const std::filesystem::path device_file =
        args.Value("device").value_or(ShippedFile("config/devices/sim.yaml").string());
    config = LoadDevice(device_file);
    if (!haptics::DriverOf(config).simulated) {
      throw ConfigError(device_file.string() +
                        ": key 'driver': expected 'sim' for haptel bench gravity (it needs "
                        "the simulated arm's true position), got '" +
                        config.driver + "'");
    }
    grid_out = args.Value("grid-out").value_or("");
    // Now, not after the sampling: a FIFO would be waited on for ever.
    CheckFileOption("grid-out", grid_out, "a file name for the grid, such as grid.yaml");
  } catch (const UsageError& e) {
    std::fprintf(stderr, "haptel bench gravity: %s (see --help)\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel bench gravity: %s\n", e.what());
    return 2;
  }

  PrintSmokeNote("gravity", smoke, "%d release points, a %dx%dx%d grid", points, counts, counts,
                 counts);
  SimDevice device(config, OperatorConfig{});
  const Side side = config.sides[1] ? Side::kRight : Side::kLeft;
  // The bench sees the device as a user would: through a measured calibration.
  std::ostringstream calibration_log;
  haptics::CalibrationOptions calibrate;
  calibrate.auto_mode = true;
  const ArmCalibration calibration = haptics::RunCalibration(device, calibrate, calibration_log)
                                         .arms[static_cast<size_t>(haptics::Index(side))];
  const SimArmConfig& sim = config.sim;

  haptics::GravitySamplerConfig sampler;
  for (int a = 0; a < 3; ++a) {
    sampler.box_min[a] = sim.workspace_min[a] + kBoxMargin;
    sampler.box_max[a] = sim.workspace_max[a] - kBoxMargin;
    if (!(sampler.box_min[a] < sampler.box_max[a])) {
      std::fprintf(stderr,
                   "haptel bench gravity: %s: the workspace is too small for a %.0f cm margin\n",
                   config.file.c_str(), kBoxMargin * 100);
      return 2;
    }
  }
  sampler.counts = {counts, counts, counts};
  sampler.device = config.name;

  // 1. Sample the grid (simulated time, 1 ms ticks).
  const haptics::GravitySampleReport report =
      haptics::SampleGravityOnSim(device, side, calibration, sampler);
  if (!report.ok) {
    std::fprintf(stderr, "haptel bench gravity: %s\n", report.error.c_str());
    if (json) {
      const std::string line =
          "{\"ok\":false,\"vertices_done\":" + std::to_string(report.vertices.size()) +
          ",\"sampling_sim_s\":" + JsonNumber(report.sim_time_s) + "}";
      std::printf("%s\n", JsonLine(line, smoke).c_str());
    }
    return 1;
  }
  const auto dir = OutputDir(smoke);
  if (grid_out.empty()) grid_out = dir / "gravity_grid.yaml";
  SaveGravityGrid(grid_out, report.grid);
  const GravityGrid grid(report.grid);

  double vertex_mean_s = 0.0, vertex_max_s = 0.0, force_error_max = 0.0;
  for (const haptics::GravityVertexReport& v : report.vertices) {
    vertex_mean_s += v.sim_time_s / static_cast<double>(report.vertices.size());
    vertex_max_s = std::max(vertex_max_s, v.sim_time_s);
    force_error_max =
        std::max(force_error_max,
                 std::abs(v.force_n - device.UnbalancedMass(v.target) * SimDevice::kGravity));
  }

  // 2. Release the arm at random points, compensation off then on.
  std::mt19937 rng(static_cast<uint32_t>(seed));
  std::vector<PointResult> results;
  int64_t now = report.end_ns;
  for (int n = 0; n < points; ++n) {
    PointResult r;
    for (int a = 0; a < 3; ++a) {
      r.start[a] =
          std::uniform_real_distribution<double>(sampler.box_min[a], sampler.box_max[a])(rng);
    }
    r.weight_n = device.UnbalancedMass(r.start) * SimDevice::kGravity;
    r.grid_n = grid.Evaluate(r.start);
    r.off_m_s = MeasureDrift(device, side, calibration, nullptr, r.start, kDriftSeconds, now);
    r.on_m_s = MeasureDrift(device, side, calibration, &grid, r.start, kDriftSeconds, now);
    results.push_back(r);
  }
  double mean_off = 0.0, mean_on = 0.0;
  int on_zero = 0;
  for (const PointResult& r : results) {
    mean_off += r.off_m_s / points;
    mean_on += r.on_m_s / points;
    on_zero += r.on_m_s == 0.0 ? 1 : 0;
  }
  const double floor_m_s =
      std::max(sim.encoder_resolution, 1e-6) / 1.0;  // one encoder step per second
  const bool floored = mean_on < floor_m_s;
  const double ratio = mean_off / std::max(mean_on, floor_m_s);

  // Table.
  std::printf("haptel bench gravity: %s, %s arm, friction %.2f N, encoder %.0f um\n\n",
              config.name.c_str(), side == Side::kRight ? "right" : "left", sim.coulomb_friction,
              sim.encoder_resolution * 1e6);
  std::printf("sampling: %dx%dx%d = %zu vertices over [%.2f %.2f %.2f]..[%.2f %.2f %.2f] m\n",
              counts, counts, counts, report.vertices.size(), sampler.box_min[0],
              sampler.box_min[1], sampler.box_min[2], sampler.box_max[0], sampler.box_max[1],
              sampler.box_max[2]);
  std::printf("  simulated %.1f s (per vertex mean %.2f s, max %.2f s), wall %.3f s\n",
              report.sim_time_s, vertex_mean_s, vertex_max_s, report.wall_time_s);
  std::printf(
      "  max |sampled force - true weight| at the vertices: %.3f N (Coulomb friction %.3f N)\n\n",
      force_error_max, sim.coulomb_friction);
  std::printf("%5s %8s %8s %8s %9s %9s %13s %13s\n", "point", "x m", "y m", "z m", "weight N",
              "grid N", "off mm/s", "on mm/s");
  for (size_t n = 0; n < results.size(); ++n) {
    const PointResult& r = results[n];
    std::printf("%5zu %8.3f %8.3f %8.3f %9.3f %9.3f %13.3f %13.4f\n", n + 1, r.start[0], r.start[1],
                r.start[2], r.weight_n, r.grid_n, r.off_m_s * 1e3, r.on_m_s * 1e3);
  }
  std::printf("\n%-44s %12.3f mm/s\n", "mean drift, compensation off", mean_off * 1e3);
  std::printf("%-44s %12.4f mm/s  (%d of %d points did not move)\n", "mean drift, compensation on",
              mean_on * 1e3, on_zero, points);
  std::printf("%-44s %12.1f%s\n", "drift_ratio (off / on)", ratio,
              floored ? "  (on-drift below 1 encoder step/s: floored there, a lower bound)" : "");
  std::printf(
      "\n  drift: |true position after %.0f s - at release| / %.0f s. Off, the arm falls until "
      "the\n"
      "  workspace floor stops it. On, the grid force is commanded every 1 ms tick from the\n"
      "  tracker reading through the calibration; friction holds what the grid leaves over.\n",
      kDriftSeconds, kDriftSeconds);

  // CSV, plot.
  {
    std::ofstream csv(dir / "gravity.csv");
    csv << "point,x_m,y_m,z_m,weight_n,grid_force_n,drift_off_mm_s,drift_on_mm_s\n";
    csv.precision(9);
    for (size_t n = 0; n < results.size(); ++n) {
      const PointResult& r = results[n];
      csv << n + 1 << "," << r.start[0] << "," << r.start[1] << "," << r.start[2] << ","
          << r.weight_n << "," << r.grid_n << "," << r.off_m_s * 1e3 << "," << r.on_m_s * 1e3
          << "\n";
    }
    std::ofstream vcsv(dir / "gravity_vertices.csv");
    vcsv << "i,j,k,x_m,y_m,z_m,force_n,true_weight_n,start_force_n,sim_time_s,decisions\n";
    vcsv.precision(9);
    for (const haptics::GravityVertexReport& v : report.vertices) {
      vcsv << v.index[0] << "," << v.index[1] << "," << v.index[2] << "," << v.target[0] << ","
           << v.target[1] << "," << v.target[2] << "," << v.force_n << ","
           << device.UnbalancedMass(v.target) * SimDevice::kGravity << "," << v.start_force_n << ","
           << v.sim_time_s << "," << v.decisions << "\n";
    }
  }
  // On a log scale 0 cannot be drawn: on-drift below the floor sits on the floor line.
  Series off{"compensation off", {}, {}}, on{"compensation on*", {}, {}};
  Series floor_line{
      "1 encoder step/s", {1.0, static_cast<double>(points)}, {floor_m_s * 1e3, floor_m_s * 1e3}};
  for (size_t n = 0; n < results.size(); ++n) {
    off.x.push_back(static_cast<double>(n + 1));
    off.y.push_back(results[n].off_m_s * 1e3);
    on.x.push_back(static_cast<double>(n + 1));
    on.y.push_back(std::max(results[n].on_m_s, floor_m_s) * 1e3);
  }
  PlotLines(dir / "gravity.png", {off, floor_line, on},
            {"drift over 1 s after release (*on: below 1 encoder step/s drawn at it)",
             "release point", "drift, mm/s", true});
  std::printf("\n  wrote %s, %s, %s, %s\n", (dir / "gravity.csv").c_str(),
              (dir / "gravity_vertices.csv").c_str(), (dir / "gravity.png").c_str(),
              grid_out.c_str());

  if (json) {
    std::ostringstream o;
    o << "{\"drift_mean_off_mm_s\":" << JsonNumber(mean_off * 1e3)
      << ",\"drift_mean_on_mm_s\":" << JsonNumber(mean_on * 1e3)
      << ",\"drift_ratio\":" << JsonNumber(ratio)
      << ",\"drift_ratio_floored\":" << (floored ? "true" : "false")
      << ",\"drift_floor_mm_s\":" << JsonNumber(floor_m_s * 1e3)
      << ",\"drift_on_zero_points\":" << on_zero
      << ",\"sampling_sim_s\":" << JsonNumber(report.sim_time_s)
      << ",\"sampling_wall_s\":" << JsonNumber(report.wall_time_s)
      << ",\"sampling_vertex_mean_s\":" << JsonNumber(vertex_mean_s)
      << ",\"sampling_vertex_max_s\":" << JsonNumber(vertex_max_s)
      << ",\"force_error_max_n\":" << JsonNumber(force_error_max)
      << ",\"friction_n\":" << JsonNumber(sim.coulomb_friction)
      << ",\"vertices\":" << report.vertices.size() << ",\"points\":" << points << "}";
    std::printf("%s\n", JsonLine(o.str(), smoke).c_str());
  }
  std::fflush(stdout);
  return 0;
}

}  // namespace haptel::bench
