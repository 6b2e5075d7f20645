#include "passivity_bench.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "haptel/config/device.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/run.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/json.hpp"
#include "haptel/haptics/hal.hpp"
#include "haptel/haptics/servo_loop.hpp"
#include "haptel/haptics/sim_device.hpp"
#include "plot.hpp"
#include "smoke.hpp"

namespace haptel::bench {

namespace {

using haptics::Side;
using haptics::Vec3d;

constexpr Side kSide = Side::kRight;
constexpr int64_t kPeriodNs = 1'000'000;  // 1 kHz
constexpr double kWallX = 0.05;           // m: the wall's surface, normal +x
constexpr double kStartX = 0.0;           // m: 5 cm out
constexpr double kPushDepth = 0.01;       // m: the grip aims 1 cm beyond the wall
constexpr double kSettledSpread = 0.0005; // m: peak to peak over the last 0.5 s
constexpr double kDecayRatio = 0.5;       // an oscillation must at least halve in 1 s
constexpr double kContactFromS = 0.5;     // s: after the soft start, for the force error
constexpr double kTargetDelayMs = 3.0;    // the delay the gain is judged at
constexpr int kMaxDelayTicks = 16;

/// The sim arm behind a delay line of `delay_ticks` servo ticks each way:
/// the loop reads what the arm measured that many ticks ago, and the arm
/// gets the command the loop sent that many ticks ago (zero before).
class DelayedDevice final : public haptics::Device {
 public:
  DelayedDevice(haptics::SimDevice& inner, int delay_ticks) : inner_(inner), delay_(delay_ticks) {}
  const haptics::DeviceDescription& description() const override { return inner_.description(); }
  haptics::DeviceStatus ReadWrist(Side side, int64_t now_ns, haptics::WristRaw& out) override {
    haptics::WristRaw now;
    const haptics::DeviceStatus s = inner_.ReadWrist(side, now_ns, now);
    if (s != haptics::DeviceStatus::kOk) return s;
    readings_[reads_ % kRing] = now;
    ++reads_;
    if (reads_ <= static_cast<uint64_t>(delay_)) return haptics::DeviceStatus::kNoData;
    out = readings_[(reads_ - 1 - static_cast<uint64_t>(delay_)) % kRing];
    return haptics::DeviceStatus::kOk;
  }
  haptics::DeviceStatus ReadGlove(Side side, int64_t now_ns, haptics::GloveRaw& out) override {
    return inner_.ReadGlove(side, now_ns, out);
  }
  haptics::DeviceStatus WriteWristForce(Side side, const Vec3d& command) override {
    commands_[writes_ % kRing] = command;
    ++writes_;
    applied_ = writes_ <= static_cast<uint64_t>(delay_) ? Vec3d{}
                                                        : commands_[(writes_ - 1 - static_cast<uint64_t>(delay_)) % kRing];
    return inner_.WriteWristForce(side, applied_);
  }
  haptics::DeviceStatus WriteFingerForces(Side side, const std::array<double, haptics::kFingers>& c) override {
    return inner_.WriteFingerForces(side, c);
  }
  /// The command the arm holds now (device units).
  const Vec3d& applied() const { return applied_; }

 private:
  static constexpr uint64_t kRing = kMaxDelayTicks + 1;
  haptics::SimDevice& inner_;
  int delay_;
  std::array<haptics::WristRaw, kRing> readings_{};
  std::array<Vec3d, kRing> commands_{};
  uint64_t reads_ = 0, writes_ = 0;
  Vec3d applied_{};
};

struct Point {
  double k = 0.0;
  double delay_ms = 0.0;
  bool passivity = false;
  bool stable = false;
  double spread = 0.0;          ///< m, peak to peak of x over the last 0.5 s
  double early_spread = 0.0;    ///< m, the same over the 0.5 s a second earlier
  double energy_j = 0.0;        ///< dissipated by the controller
  double max_alpha = 0.0;       ///< N·s/m
  uint64_t acting_ticks = 0;
  double force_rms_err = 0.0;   ///< N against the ideal wall
  double penetration = 0.0;     ///< m, mean over the last 0.5 s
};

/// The perfect calibration of a sim arm: its hidden truth.
DeviceCalibration Truth(const haptics::SimDevice& device) {
  DeviceCalibration c;
  for (int s = 0; s < haptics::kSides; ++s) {
    const haptics::SimArmTruth& t = device.truth(static_cast<Side>(s));
    ArmCalibration& a = c.arms[s];
    for (int i = 0; i < 3; ++i) {
      a.tracker_scale[i] = t.tracker_scale[i];
      a.tracker_offset[i] = t.tracker_offset[i];
      a.force_slope[i] = t.force_slope[i];
    }
  }
  return c;
}

Point Run(const DeviceConfig& device_config, const OperatorConfig& grip, double k, int delay_ticks, bool passivity,
          double seconds, std::vector<double>& tick_us) {
  DeviceConfig config = device_config;
  config.servo.passivity = passivity;
  haptics::SimDevice arm(config, grip);
  arm.Place(kSide, {kStartX, 0.0, 0.0});
  arm.SetOperatorTarget(kSide, {kWallX + kPushDepth, 0.0, 0.0});
  DelayedDevice device(arm, delay_ticks);
  const DeviceCalibration calibration = Truth(arm);
  haptics::Hal hal(calibration);
  haptics::ServoLoop loop(device, hal, config, calibration);

  Point r;
  r.k = k;
  r.delay_ms = delay_ticks * kPeriodNs * 1e-6;
  r.passivity = passivity;
  const long n = std::lround(seconds / (kPeriodNs * 1e-9));
  const long tail = 500;  // the last 0.5 s, against the 0.5 s a second before it
  double x_min = 1e9, x_max = -1e9, early_min = 1e9, early_max = -1e9, err2 = 0.0, pen_sum = 0.0;
  long err_n = 0;
  haptics::ForceSetpoint sp;
  sp.coupling_enabled = true;
  sp.coupling_stiffness = k;
  sp.coupling_damping = 0.0;
  for (long i = 1; i <= n; ++i) {
    const int64_t now = i * kPeriodNs;
    // The proxy: the tracked wrist (as the HAL has it) kept out of the wall.
    const haptics::HandSample s = hal.LatestSample(kSide);
    sp.coupling_target = s.valid ? s.position : Vec3d{kStartX, 0.0, 0.0};
    sp.coupling_target[0] = std::min(sp.coupling_target[0], kWallX);
    hal.SetSetpoint(kSide, sp, now);
    const int64_t t0 = MonotonicNs();
    loop.Tick(kSide, now);
    tick_us.push_back(static_cast<double>(MonotonicNs() - t0) * 1e-3);

    const Vec3d x = arm.TruePosition(kSide);
    if (!std::isfinite(x[0])) return r;  // unstable
    const double t = static_cast<double>(i) * kPeriodNs * 1e-9;
    const double pen = std::max(0.0, x[0] - kWallX);
    if (t >= kContactFromS) {
      const double felt = arm.MeasureForce(kSide, device.applied())[0];
      const double ideal = -k * pen;
      err2 += (felt - ideal) * (felt - ideal);
      ++err_n;
    }
    if (i > n - 3 * tail && i <= n - 2 * tail) {
      early_min = std::min(early_min, x[0]);
      early_max = std::max(early_max, x[0]);
    }
    if (i > n - tail) {
      x_min = std::min(x_min, x[0]);
      x_max = std::max(x_max, x[0]);
      pen_sum += pen;
    }
  }
  const haptics::ServoCounters c = loop.Counters(kSide);
  r.spread = x_max - x_min;
  r.early_spread = early_max - early_min;
  // Settled, or an oscillation that dies away (the light grip's own,
  // passive one decays slowly); one that keeps up or grows is not stable.
  r.stable = r.spread < kSettledSpread || r.spread < kDecayRatio * r.early_spread;
  r.energy_j = c.passivity_dissipated_j;
  r.max_alpha = c.passivity_max_alpha;
  r.acting_ticks = c.passivity_ticks;
  r.force_rms_err = err_n > 0 ? std::sqrt(err2 / static_cast<double>(err_n)) : 0.0;
  r.penetration = pen_sum / static_cast<double>(tail);
  return r;
}

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const size_t i = std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<long>(i), v.end());
  return v[i];
}

/// The largest K stable before the first unstable one (0: none).
double LargestStable(const std::vector<Point>& points, double delay_ms, bool passivity) {
  double best = 0.0;
  for (const Point& p : points) {
    if (p.delay_ms != delay_ms || p.passivity != passivity) continue;
    if (!p.stable) break;
    best = p.k;
  }
  return best;
}

const Point* Find(const std::vector<Point>& points, double k, double delay_ms, bool passivity) {
  for (const Point& p : points) {
    if (p.k == k && p.delay_ms == delay_ms && p.passivity == passivity) return &p;
  }
  return nullptr;
}

}  // namespace

int BenchPassivityMain(int argc, const char* const* argv) {
  bool json = false, smoke = false;
  DeviceConfig device;
  try {
    const Args args(argc, argv, {"device"}, {"json", kSmokeFlag});
    json = args.Flag("json");
    smoke = args.Flag(kSmokeFlag);
    device = LoadDevice(args.Value("device").value_or(ShippedFile("config/devices/sim.yaml").string()));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel bench passivity: %s\n", e.what());
    return 2;
  }
  // One arm, no glove or strings, no gravity: the wall's axis alone.
  device.driver = "sim";
  device.sides = {false, true};
  device.has_glove = false;
  device.has_grasp = false;
  device.sim.exo_unbalanced_mass = 0.0;
  device.servo.realtime_priority = 0;
  device.servo.lock_memory = false;
  OperatorConfig grip;
  grip.muscle_stiffness = 250.0;
  grip.muscle_damping = 2.0;
  grip.muscle_integral_gain = 0.0;

  const std::vector<double> delays_ms = smoke ? std::vector<double>{0, 3} : std::vector<double>{0, 1, 3, 5};
  const double k_max = smoke ? 1000.0 : 64000.0;
  const double seconds = smoke ? 1.5 : 4.0;
  PrintSmokeNote("passivity", smoke, "delays 0 and 3 ms, K up to %.0f N/m, %.1f s runs", k_max, seconds);
  const auto dir = OutputDir(smoke);
  const double period_s = 1.0 / device.servo.rate_hz;
  const double bound = 2.0 * device.sim.damping / period_s;
  std::printf("haptel bench passivity: %s; sim arm %.3g kg, damping b = %.3g N*s/m, Coulomb %.3g N, force limit\n"
              "  %.3g N; light grip %.0f N/m, %.1f N*s/m aiming %.0f mm into the wall; controller cap %.3g N*s/m,\n"
              "  speed floor %.3g m/s; passivity bound 2b/T = %.4g N/m\n\n",
              device.file.empty() ? "defaults" : device.file.c_str(), device.sim.arm_mass, device.sim.damping,
              device.sim.coulomb_friction, device.sim.force_limit, grip.muscle_stiffness, grip.muscle_damping,
              kPushDepth * 1e3, device.servo.passivity_max_damping, device.servo.passivity_min_speed, bound);

  std::vector<Point> points;
  std::vector<double> ticks_off, ticks_on;
  const double t_start = NsToS(MonotonicNs());
  for (const double delay : delays_ms) {
    const int delay_ticks = static_cast<int>(std::lround(delay * 1e-3 / period_s));
    for (const bool on : {false, true}) {
      for (double k = 250.0; k <= k_max; k *= 2.0) {
        points.push_back(Run(device, grip, k, delay_ticks, on, seconds, on ? ticks_on : ticks_off));
      }
    }
  }
  const double wall_s = NsToS(MonotonicNs()) - t_start;

  std::printf("  %8s %9s | %6s %9s %10s | %6s %9s %10s %10s %9s %8s\n", "delay ms", "K N/m", "off", "spread mm",
              "F err N", "on", "spread mm", "F err N", "dissip. J", "alpha max", "acted");
  for (const double delay : delays_ms) {
    for (double k = 250.0; k <= k_max; k *= 2.0) {
      const Point* off = Find(points, k, delay, false);
      const Point* on = Find(points, k, delay, true);
      std::printf("  %8.0f %9.0f | %6s %9.3f %10.3f | %6s %9.3f %10.3f %10.4g %9.3g %8llu\n", delay, k,
                  off->stable ? "stable" : "OSC", off->spread * 1e3, off->force_rms_err, on->stable ? "stable" : "OSC",
                  on->spread * 1e3, on->force_rms_err, on->energy_j, on->max_alpha,
                  static_cast<unsigned long long>(on->acting_ticks));
    }
  }
  std::printf("\n  %8s %14s %14s %8s   (largest K stable before the first unstable one)\n", "delay ms", "K_stable off",
              "K_stable on", "gain");
  std::vector<double> stable_off, stable_on;
  for (const double delay : delays_ms) {
    stable_off.push_back(LargestStable(points, delay, false));
    stable_on.push_back(LargestStable(points, delay, true));
    std::printf("  %8.0f %14.0f %14.0f %8.3g\n", delay, stable_off.back(), stable_on.back(),
                stable_off.back() > 0 ? stable_on.back() / stable_off.back() : 0.0);
  }
  // The figures at the target's delay (the largest delay run in a smoke run).
  size_t at = delays_ms.size() - 1;
  for (size_t i = 0; i < delays_ms.size(); ++i) {
    if (delays_ms[i] == kTargetDelayMs) at = i;
  }
  const double k_off = stable_off[at], k_on = stable_on[at];
  const double gain = k_off > 0 ? k_on / k_off : 0.0;
  const double p99_off = Percentile(ticks_off, 0.99), p99_on = Percentile(ticks_on, 0.99);
  const double cost = std::max(0.0, p99_on - p99_off);
  // Transparency at the stiffnesses stable both ways, at the target's delay.
  double err_off = 0.0, err_on = 0.0;
  int err_n = 0;
  for (double k = 250.0; k <= std::min(k_off, k_on); k *= 2.0) {
    err_off += Find(points, k, delays_ms[at], false)->force_rms_err;
    err_on += Find(points, k, delays_ms[at], true)->force_rms_err;
    ++err_n;
  }
  if (err_n > 0) err_off /= err_n, err_on /= err_n;
  std::printf("\n  at %.0f ms each way: K stable %.0f N/m off, %.0f N/m on: gain %.3g (target >= 3) %s\n"
              "  force error against the ideal wall, mean RMS over the K stable both ways: %.3f N off, %.3f N on\n"
              "  servo tick p99 %.3g us off, %.3g us on: the controller costs %.3g us (target <= 2) %s\n"
              "  %zu runs in %.1f s wall; wrote %s/passivity.csv, passivity.png\n",
              delays_ms[at], k_off, k_on, gain, gain >= 3.0 ? "met" : "MISSED", err_off, err_on, p99_off, p99_on,
              cost, cost <= 2.0 ? "met" : "MISSED", points.size(), wall_s, dir.c_str());

  {
    std::ofstream csv(dir / "passivity.csv");
    csv << "stiffness,delay_ms,mode,stable,spread_m,energy_j,max_alpha,acting_ticks,force_rms_err_n,penetration_m\n";
    for (const Point& p : points) {
      csv << p.k << "," << p.delay_ms << "," << (p.passivity ? "on" : "off") << "," << (p.stable ? 1 : 0) << ","
          << p.spread << "," << p.energy_j << "," << p.max_alpha << "," << p.acting_ticks << "," << p.force_rms_err
          << "," << p.penetration << "\n";
    }
  }
  {
    Series off{"largest stable K, controller off", {}, {}};
    Series on{"largest stable K, controller on", {}, {}};
    Series pb{"passivity bound 2b/T", {}, {}};
    for (size_t i = 0; i < delays_ms.size(); ++i) {
      off.x.push_back(delays_ms[i]), off.y.push_back(std::max(stable_off[i], 1.0));
      on.x.push_back(delays_ms[i]), on.y.push_back(std::max(stable_on[i], 1.0));
      pb.x.push_back(delays_ms[i]), pb.y.push_back(bound);
    }
    PlotOptions o;
    o.title = "Virtual wall: largest stable coupling stiffness vs device delay";
    o.x_label = "device delay each way (ms)";
    o.y_label = "K (N/m)";
    o.log_y = true;
    try {
      PlotLines(dir / "passivity.png", {off, on, pb}, o);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "haptel bench passivity: %s\n", e.what());
    }
  }

  if (json) {
    std::ostringstream o;
    o << "{\"delay_ms\":" << JsonNumber(delays_ms[at]) << ",\"stable_stiffness_off\":" << JsonNumber(k_off)
      << ",\"stable_stiffness_on\":" << JsonNumber(k_on) << ",\"gain\":" << JsonNumber(gain)
      << ",\"passivity_bound\":" << JsonNumber(bound) << ",\"cost_us_p99\":" << JsonNumber(cost)
      << ",\"tick_us_p99_off\":" << JsonNumber(p99_off) << ",\"tick_us_p99_on\":" << JsonNumber(p99_on)
      << ",\"force_rms_err_n_off\":" << JsonNumber(err_off) << ",\"force_rms_err_n_on\":" << JsonNumber(err_on)
      << ",\"delays\":[";
    for (size_t i = 0; i < delays_ms.size(); ++i) {
      o << (i ? "," : "") << "{\"delay_ms\":" << JsonNumber(delays_ms[i]) << ",\"stable_stiffness_off\":"
        << JsonNumber(stable_off[i]) << ",\"stable_stiffness_on\":" << JsonNumber(stable_on[i]) << "}";
    }
    o << "],\"points\":[";
    for (size_t i = 0; i < points.size(); ++i) {
      const Point& p = points[i];
      o << (i ? "," : "") << "{\"stiffness\":" << JsonNumber(p.k) << ",\"delay_ms\":" << JsonNumber(p.delay_ms)
        << ",\"mode\":\"" << (p.passivity ? "on" : "off") << "\",\"stable\":" << (p.stable ? "true" : "false")
        << ",\"energy_j\":" << JsonNumber(p.energy_j) << ",\"force_rms_err_n\":" << JsonNumber(p.force_rms_err) << "}";
    }
    o << "]}";
    std::printf("%s\n", JsonLine(o.str(), smoke).c_str());
  }
  return 0;
}

}  // namespace haptel::bench
