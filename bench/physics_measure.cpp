#include "physics_measure.hpp"

#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "haptel/core/clock.hpp"
#include "haptel/core/json.hpp"
#include "haptel/physics/world.hpp"
#include "haptel/testing/box_grip.hpp"
#include "haptel/testing/vec_math.hpp"

namespace haptel::bench::wp {

namespace {

using haptics::AxisAngle;
using haptics::Distance;
using haptics::HandSample;
using haptics::Side;
using physics::PhysicsWorld;

PhysicsConfig WithSolver(const PhysicsConfig& base, double step_s, int iterations) {
  PhysicsConfig c = base;
  c.step_s = step_s;
  c.solver_iterations = iterations;
  c.realtime_priority = 0;
  return c;
}

long Resets(const PhysicsWorld& world) {
  const auto c = world.Counters();
  return static_cast<long>(c.hand_resets + c.body_resets);
}

struct Scenario {
  double cpu_s = 0.0;
  double sim_s = 0.0;
  long resets = 0;
};

/// (b) The palm comes down on a table at 0.1 m/s and is held with the tracked
/// wrist F/k below the surface (10 N through the coupling), `seconds` in all.
Scenario Push(const PhysicsConfig& config, double seconds, double* rest_mm, double* worst_mm) {
  PhysicsWorld world{config};
  world.AddStaticBox({0.0, 0.0, -0.05}, {0.5, 0.5, 0.05});  // table top at z = 0
  world.AddHand(Side::kRight);
  physics::ProxyHand& hand = *world.hand(Side::kRight);
  const auto& hc = config.hand;
  const double half_thickness = hc.palm_half_extents[2];
  const double target_z = half_thickness - 10.0 / hc.coupling_linear_stiffness;
  const double h = config.step_s;
  const long steps = std::lround(seconds / h);
  const long last = std::lround(0.2 / h);
  double z = half_thickness + 0.03;
  double worst = 0.0, rest = 0.0, cpu = 0.0;
  for (long i = 0; i < steps; ++i) {
    z = std::max(target_z, z - 0.1 * h);
    const double c0 = ThreadCpuSeconds();
    hand.SetTracked(haptics::TrackedHand({0.0, 0.0, z}));
    world.Step();
    cpu += ThreadCpuSeconds() - c0;
    const double pen = half_thickness - hand.ProxyWrist().position[2];
    worst = std::max(worst, pen);
    if (i >= steps - last) rest += pen / static_cast<double>(last);
  }
  *rest_mm = 1e3 * rest;
  *worst_mm = 1e3 * worst;
  return {cpu, static_cast<double>(steps) * h, Resets(world)};
}

/// (c) Two palms squeeze a 0.5 kg box (tracked 1 cm inside it: ≈30 N each),
/// lift it 10 cm in 1 s and hold it `hold_s`; slip = how far the box moved
/// relative to the palms' midpoint during the hold.
Scenario Grasp(const PhysicsConfig& config, double hold_s, double* slip_mm) {
  PhysicsWorld world{config};
  const physics::BoxGrip grip(world);
  const physics::BodyId box = grip.box;
  const double z0 = 0.09, h = config.step_s;
  double cpu = 0.0;
  auto run = [&](double seconds, auto z_of) {
    const long n = std::lround(seconds / h);
    for (long i = 0; i < n; ++i) {
      const double z = z_of(static_cast<double>(i) * h);
      const double c0 = ThreadCpuSeconds();
      grip.Track(0.01, z);
      world.Step();
      cpu += ThreadCpuSeconds() - c0;
    }
    return static_cast<double>(n) * h;
  };
  auto relative = [&] {
    const Vec3d b = world.BodyPose(box).position;
    const Vec3d l = world.hand(Side::kLeft)->ProxyWrist().position;
    const Vec3d r = world.hand(Side::kRight)->ProxyWrist().position;
    return Vec3d{b[0] - 0.5 * (l[0] + r[0]), b[1] - 0.5 * (l[1] + r[1]),
                 b[2] - 0.5 * (l[2] + r[2])};
  };
  double sim = run(kGraspSettleS, [&](double) { return z0; });
  sim += run(kGraspLiftS, [&](double t) { return z0 + 0.1 / kGraspLiftS * t; });
  const Vec3d start = relative();
  sim += run(hold_s, [&](double) { return z0 + 0.1; });
  *slip_mm = 1e3 * Distance(relative(), start);
  return {cpu, sim, Resets(world)};
}

}  // namespace

Plan FullPlan() { return Plan{}; }

Plan SmokePlan() {
  Plan p;
  p.steps_ms = {1.0, 8.0};  // the default step and the coarsest
  p.iterations = {5, 20};   // the fewest and the default
  p.trajectory_s = 0.5;     // the ease-in: the 0.025 ms reference is most of a smoke run's time
  p.push_s = 0.6;           // touch-down at 0.3 s, then 0.3 s pressed in
  p.grasp_hold_s = 1.0;
  return p;
}

HandSample Trajectory::At(double t) const {
  const double u = std::clamp(t / dt, 0.0, static_cast<double>(position.size() - 1));
  const size_t i = std::min(static_cast<size_t>(u), position.size() - 2);
  const double f = u - static_cast<double>(i);
  Vec3d p;
  std::array<double, 4> q;
  for (int k = 0; k < 3; ++k) p[k] = (1 - f) * position[i][k] + f * position[i + 1][k];
  double n = 0.0;
  for (int k = 0; k < 4; ++k) {
    q[k] = (1 - f) * orientation[i][k] + f * orientation[i + 1][k];
    n += q[k] * q[k];
  }
  for (double& c : q) c /= std::sqrt(n);
  return haptics::TrackedHand(p, q);
}

Trajectory MakeTrajectory(double seconds) {
  // Per axis: {amplitude (arbitrary), frequency Hz, phase}; scaled below.
  struct Term {
    double a, f, phi;
  };
  const std::array<std::array<Term, 3>, 3> terms{{
      {{{1.0, 0.35, 0.0}, {0.35, 0.9, 1.1}, {0.12, 1.7, 2.3}}},
      {{{0.8, 0.45, 0.7}, {0.30, 1.1, 2.9}, {0.10, 1.6, 0.4}}},
      {{{0.5, 0.55, 1.9}, {0.25, 1.3, 0.2}, {0.08, 1.5, 1.3}}},
  }};
  Trajectory tr;
  const size_t n = static_cast<size_t>(std::lround(seconds / tr.dt)) + 1;
  std::vector<Vec3d> raw(n);
  for (size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * tr.dt;
    const double ease = t < 0.5 ? 0.5 * (1.0 - std::cos(M_PI * t / 0.5)) : 1.0;
    for (int k = 0; k < 3; ++k) {
      double v = 0.0;
      for (const Term& term : terms[k])
        v += term.a * (std::sin(2 * M_PI * term.f * t + term.phi) - std::sin(term.phi));
      raw[i][k] = ease * v;
    }
  }
  double peak = 0.0;
  for (size_t i = 1; i < n; ++i) peak = std::max(peak, Distance(raw[i], raw[i - 1]) / tr.dt);
  const double scale = kPeakSpeed / peak;
  const Vec3d centre{0.10, 0.0, 0.20};
  for (size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * tr.dt;
    tr.position.push_back({centre[0] + scale * raw[i][0], centre[1] + scale * raw[i][1],
                           centre[2] + scale * raw[i][2]});
    tr.orientation.push_back(AxisAngle({0, 0, 1}, 0.3 * std::sin(2 * M_PI * 0.7 * t)));
  }
  return tr;
}

void SaveTrajectory(const std::filesystem::path& file, const Trajectory& tr) {
  std::ofstream out(file);
  out << "t_s,x_m,y_m,z_m,qw,qx,qy,qz\n";
  char buf[256];
  for (size_t i = 0; i < tr.position.size(); ++i) {
    const auto& p = tr.position[i];
    const auto& q = tr.orientation[i];
    std::snprintf(buf, sizeof buf, "%.5f,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n",
                  static_cast<double>(i) * tr.dt, p[0], p[1], p[2], q[0], q[1], q[2], q[3]);
    out << buf;
  }
  if (!out) throw std::runtime_error("cannot write " + file.string());
}

std::optional<Trajectory> LoadTrajectory(const std::filesystem::path& file, double seconds) {
  std::ifstream in(file);
  std::string line;
  if (!std::getline(in, line) || line != "t_s,x_m,y_m,z_m,qw,qx,qy,qz") return std::nullopt;
  Trajectory tr;
  while (std::getline(in, line)) {
    double t, x, y, z, qw, qx, qy, qz;
    if (std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &t, &x, &y, &z, &qw, &qx, &qy,
                    &qz) != 8)
      return std::nullopt;
    if (std::abs(t - static_cast<double>(tr.position.size()) * tr.dt) > 1e-6) return std::nullopt;
    tr.position.push_back({x, y, z});
    tr.orientation.push_back({qw, qx, qy, qz});
  }
  if (tr.position.size() < 2 || std::abs(tr.duration() - seconds) > 1e-6) return std::nullopt;
  return tr;
}

std::vector<Vec3d> TrackRun(const PhysicsConfig& base, const Trajectory& tr, double step_s,
                            int iterations, double* cpu_s, long* resets) {
  // Finer than the samples: record every `stride` steps; else each step spans `per_sample` samples.
  const bool finer = step_s < tr.dt * (1.0 - 1e-9);
  const long stride = finer ? std::lround(tr.dt / step_s) : 0;
  const long per_sample = finer ? 0 : std::lround(step_s / tr.dt);
  if (finer ? std::abs(static_cast<double>(stride) * step_s - tr.dt) > 1e-12
            : std::abs(static_cast<double>(per_sample) * tr.dt - step_s) > 1e-12) {
    throw std::invalid_argument("TrackRun: step and trajectory sample are not commensurate");
  }
  PhysicsWorld world{WithSolver(base, step_s, iterations)};
  world.AddHand(Side::kRight);
  physics::ProxyHand& hand = *world.hand(Side::kRight);
  const long steps = std::lround(tr.duration() / step_s);
  std::vector<Vec3d> out(tr.position.size(), Vec3d{NAN, NAN, NAN});
  out[0] = tr.position[0];
  double cpu = 0.0;
  for (long k = 0; k < steps; ++k) {
    const HandSample s = tr.At(static_cast<double>(k) * step_s);
    const double c0 = ThreadCpuSeconds();
    hand.SetTracked(s);
    world.Step();
    cpu += ThreadCpuSeconds() - c0;
    // After step k the proxy is at t = (k + 1)·step.
    if (finer) {
      if ((k + 1) % stride == 0)
        out[static_cast<size_t>((k + 1) / stride)] = hand.ProxyWrist().position;
    } else {
      out[static_cast<size_t>((k + 1) * per_sample)] = hand.ProxyWrist().position;
    }
  }
  if (cpu_s) *cpu_s = cpu;
  if (resets) *resets = Resets(world);
  return out;
}

std::vector<Vec3d> ReferenceRun(const PhysicsConfig& base, const Trajectory& trajectory) {
  PhysicsConfig config = base;
  config.reference = true;
  return TrackRun(config, trajectory, 1e-3 * kReferenceStepMs, kReferenceIterations);
}

void SaveReference(const std::filesystem::path& file, const std::vector<Vec3d>& reference) {
  std::ofstream out(file);
  out << "x_m,y_m,z_m\n";
  char buf[128];
  for (const Vec3d& p : reference) {
    std::snprintf(buf, sizeof buf, "%.17g,%.17g,%.17g\n", p[0], p[1], p[2]);
    out << buf;
  }
  if (!out) throw std::runtime_error("cannot write " + file.string());
}

std::optional<std::vector<Vec3d>> LoadReference(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::string line;
  if (!std::getline(in, line) || line != "x_m,y_m,z_m") return std::nullopt;
  std::vector<Vec3d> ref;
  while (std::getline(in, line)) {
    Vec3d p;
    if (std::sscanf(line.c_str(), "%lf,%lf,%lf", &p[0], &p[1], &p[2]) != 3) return std::nullopt;
    ref.push_back(p);
  }
  return ref;
}

Point Measure(const PhysicsConfig& base, const Trajectory& tr, const std::vector<Vec3d>& reference,
              double step_ms, int iterations, const std::string& precision, const Plan& plan) {
  Point p;
  p.step_ms = step_ms;
  p.iterations = iterations;
  p.precision = precision;
  const double h = 1e-3 * step_ms;
  const PhysicsConfig config = WithSolver(base, h, iterations);

  double cpu = 0.0;
  long resets = 0;
  const std::vector<Vec3d> track = TrackRun(base, tr, h, iterations, &cpu, &resets);
  double sum_err = 0.0, sum_lag = 0.0;
  int n = 0;
  for (size_t i = 1; i < track.size(); ++i) {
    if (std::isnan(track[i][0]) || i >= reference.size()) continue;
    const double e = Distance(track[i], reference[i]);
    const double l = Distance(track[i], tr.position[i]);
    sum_err += e * e;
    sum_lag += l * l;
    ++n;
  }
  p.tracking_err_mm = n ? 1e3 * std::sqrt(sum_err / n) : NAN;
  p.lag_mm = n ? 1e3 * std::sqrt(sum_lag / n) : NAN;
  Scenario total{cpu, tr.duration(), resets};

  const Scenario push = Push(config, plan.push_s, &p.penetration_rest_mm, &p.penetration_mm);
  const Scenario grasp = Grasp(config, plan.grasp_hold_s, &p.slip_mm);
  for (const Scenario& s : {push, grasp}) {
    total.cpu_s += s.cpu_s;
    total.sim_s += s.sim_s;
    total.resets += s.resets;
  }
  p.cpu_per_sim_s = total.cpu_s / total.sim_s;
  p.resets = total.resets;
  return p;
}

std::string ToJson(const Point& p, bool extra) {
  std::string s = "{\"step_ms\":" + JsonNumber(p.step_ms) +
                  ",\"iterations\":" + std::to_string(p.iterations) + ",\"precision\":\"" +
                  p.precision + "\",\"cpu_per_sim_s\":" + JsonNumber(p.cpu_per_sim_s) +
                  ",\"tracking_err_mm\":" + JsonNumber(p.tracking_err_mm) +
                  ",\"penetration_mm\":" + JsonNumber(p.penetration_mm) +
                  ",\"slip_mm\":" + JsonNumber(p.slip_mm);
  if (extra) {
    s += ",\"lag_mm\":" + JsonNumber(p.lag_mm) +
         ",\"penetration_rest_mm\":" + JsonNumber(p.penetration_rest_mm) +
         ",\"resets\":" + std::to_string(p.resets);
  }
  return s + "}";
}

std::vector<Point> ParsePoints(const std::string& text) {
  std::vector<Point> points;
  const char* key = "{\"step_ms\":";
  for (size_t at = text.find(key); at != std::string::npos; at = text.find(key, at + 1)) {
    Point p;
    char precision[16] = {};
    if (std::sscanf(text.c_str() + at,
                    "{\"step_ms\":%lf,\"iterations\":%d,\"precision\":\"%15[a-z0-9]\",\"cpu_per_"
                    "sim_s\":%lf,"
                    "\"tracking_err_mm\":%lf,\"penetration_mm\":%lf,\"slip_mm\":%lf,\"lag_mm\":%lf,"
                    "\"penetration_rest_mm\":%lf,\"resets\":%ld}",
                    &p.step_ms, &p.iterations, precision, &p.cpu_per_sim_s, &p.tracking_err_mm,
                    &p.penetration_mm, &p.slip_mm, &p.lag_mm, &p.penetration_rest_mm,
                    &p.resets) == 10) {
      p.precision = precision;
      points.push_back(p);
    }
  }
  return points;
}

}  // namespace haptel::bench::wp
