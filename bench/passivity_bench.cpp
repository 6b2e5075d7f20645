#include "passivity_bench.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bare_loop.hpp"
#include "haptel/config/device.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/run.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/json.hpp"
#include "haptel/haptics/hal.hpp"
#include "haptel/haptics/servo_loop.hpp"
#include "haptel/haptics/sim_device.hpp"
#include "haptel/haptics/twoport.hpp"
#include "haptel/udp/arm_server.hpp"
#include "haptel/udp/udp_device.hpp"
#include "plot.hpp"
#include "servo_bench.hpp"
#include "smoke.hpp"

namespace haptel::bench {

namespace {

using haptics::Side;
using haptics::Vec3d;

constexpr Side kSide = Side::kRight;
constexpr int64_t kPeriodNs = 1'000'000;   // 1 kHz
constexpr double kWallX = 0.05;            // m: the wall's surface, normal +x
constexpr double kStartX = 0.0;            // m: 5 cm out
constexpr double kPushDepth = 0.01;        // m: the grip aims 1 cm beyond the wall
constexpr double kSettledSpread = 0.0005;  // m: peak to peak over the last 0.5 s
constexpr double kDecayRatio = 0.5;        // an oscillation must at least halve in 1 s
constexpr double kContactFromS = 0.5;      // s: after the soft start, for the force error
constexpr double kTargetDelayMs = 3.0;     // the delay the gain is judged at
constexpr int kMaxDelayTicks = 16;
// The grasped box: a free body the hand holds through the coupling (the
// proxy is the box; the box feels the coupling's reaction on the hand as
// the loop saw it), grasped 1 cm from where the hand is and held still.
constexpr double kBoxMass = 0.5;     // kg
constexpr double kBoxOffset = 0.01;  // m: where the box is when the grip closes

/// The modes compared: no controller, the servo loop's one-port controller
/// (passivity.hpp), the two-port across the delay line (twoport.hpp) with
/// its credit unbounded, and with the credit bounded at zero.
/// The UDP rows: the same arm behind the real UDP path — UdpDevice, loopback
/// sockets, protocol version 2, udp::ArmServer adding the delay — without
/// and with the two-port across the wire (the loop's end in the servo loop,
/// the arm's in the server, their energies in the datagrams).
/// `udp-two-port`: the loop's end charges its deficit to the arm's end
/// (servo.passivity_link: charge, the default); `udp-2p-admit`: it
/// dissipates it on the environment's port (passivity_link: admittance).
enum class Mode {
  kOff,
  kOnePort,
  kTwoPort,
  kTwoPortRef,
  kUdpOff,
  kUdpTwoPort,
  kUdpTwoPortAdmittance
};
constexpr std::array<Mode, 7> kModes{Mode::kOff,
                                     Mode::kOnePort,
                                     Mode::kTwoPort,
                                     Mode::kTwoPortRef,
                                     Mode::kUdpOff,
                                     Mode::kUdpTwoPort,
                                     Mode::kUdpTwoPortAdmittance};

const char* ModeName(Mode m) {
  switch (m) {
    case Mode::kOff:
      return "off";
    case Mode::kOnePort:
      return "one-port";
    case Mode::kTwoPort:
      return "two-port";
    case Mode::kTwoPortRef:
      return "two-port-ref";
    case Mode::kUdpOff:
      return "udp-off";
    case Mode::kUdpTwoPort:
      return "udp-two-port";
    case Mode::kUdpTwoPortAdmittance:
      return "udp-2p-admit";
  }
  return "?";
}

bool IsUdp(Mode m) {
  return m == Mode::kUdpOff || m == Mode::kUdpTwoPort || m == Mode::kUdpTwoPortAdmittance;
}
/// The mode a mode's gain is measured against: the same path without a controller.
Mode Baseline(Mode m) { return IsUdp(m) ? Mode::kUdpOff : Mode::kOff; }

/// The sim arm behind a delay line of `delay_ticks` servo ticks each way:
/// the loop reads what the arm measured that many ticks ago, and the arm
/// gets the command the loop sent that many ticks ago (zero before).
///
/// With `two_port` set, each end of the line observes the energy crossing it
/// (twoport.hpp) and its E_in travels with the samples through the same
/// delay: the loop's end pairs the commands the loop wrote with the readings
/// it was handed (as the UDP driver would), the arm's end pairs the force
/// the arm held with its encoder's motion and damps the arm, undelayed, when
/// the channel delivers more than the loop's end put in.
class DelayedDevice final : public haptics::Device {
 public:
  DelayedDevice(haptics::SimDevice& inner, int delay_ticks, const haptics::SimArmTruth& truth,
                double period_s, const haptics::TwoPortLimits* two_port)
      : inner_(inner),
        delay_(delay_ticks),
        truth_(truth),
        period_s_(period_s),
        two_port_(two_port != nullptr),
        arm_end_(haptics::ChannelEnd::kDevice,
                 two_port != nullptr ? *two_port : haptics::TwoPortLimits{}),
        loop_end_(haptics::ChannelEnd::kLoop) {}
  const haptics::DeviceDescription& description() const override { return inner_.description(); }
  haptics::DeviceStatus ReadWrist(Side side, int64_t now_ns, haptics::WristRaw& out) override {
    haptics::WristRaw now;
    const haptics::DeviceStatus s = inner_.ReadWrist(side, now_ns, now);
    if (s != haptics::DeviceStatus::kOk) return s;
    if (two_port_) {
      // The arm's end: its encoder, as the device's server has it.
      const Vec3d p = Metres(now.position);
      Vec3d dx{};
      for (int i = 0; i < 3; ++i) {
        dx[i] = reads_ > 0 ? p[i] - arm_position_[i] : 0.0;
        constexpr double kFilter_s = 0.005;  // as the servo loop's velocity
        if (reads_ > 0)
          arm_velocity_[i] +=
              period_s_ / (kFilter_s + period_s_) * (dx[i] / period_s_ - arm_velocity_[i]);
      }
      arm_position_ = p;
      arm_end_.Observe(dx);
    }
    readings_[reads_ % kRing] = {now, arm_end_.energy_in()};
    ++reads_;
    if (reads_ <= static_cast<uint64_t>(delay_)) return haptics::DeviceStatus::kNoData;
    const Reading& r = readings_[(reads_ - 1 - static_cast<uint64_t>(delay_)) % kRing];
    out = r.raw;
    if (two_port_) {
      // The loop's end: the reading it is handed against the previous one.
      const Vec3d p = Metres(out.position);
      Vec3d dx{};
      for (int i = 0; i < 3; ++i) dx[i] = loop_has_position_ ? p[i] - loop_position_[i] : 0.0;
      loop_position_ = p;
      loop_has_position_ = true;
      loop_end_.Observe(dx);
      loop_remote_in_ = r.energy_in;
      const haptics::Vec3d w = loop_end_.Margin(r.energy_in);
      for (int i = 0; i < 3; ++i) loop_margin_min_ = std::min(loop_margin_min_, w[i]);
    }
    return haptics::DeviceStatus::kOk;
  }
  haptics::DeviceStatus ReadGlove(Side side, int64_t now_ns, haptics::GloveRaw& out) override {
    return inner_.ReadGlove(side, now_ns, out);
  }
  haptics::DeviceStatus WriteWristForce(Side side, const Vec3d& command) override {
    if (two_port_) loop_end_.Hold(Newtons(command));
    commands_[writes_ % kRing] = {command, loop_end_.EnergyToSend(loop_remote_in_)};
    ++writes_;
    const Command arrived = writes_ <= static_cast<uint64_t>(delay_)
                                ? Command{}
                                : commands_[(writes_ - 1 - static_cast<uint64_t>(delay_)) % kRing];
    applied_ = arrived.command;
    if (two_port_) {
      const Vec3d rendered = Newtons(arrived.command);
      const haptics::TwoPortAction a =
          arm_end_.Control(rendered, arrived.energy_in, arm_velocity_, period_s_);
      for (int i = 0; i < 3; ++i) applied_[i] += a.damping_force[i] / truth_.force_slope[i];
      // The arm saturates: hold what it will really apply.
      const Vec3d total = Newtons(applied_);
      Vec3d damping{};
      for (int i = 0; i < 3; ++i) damping[i] = total[i] - rendered[i];
      arm_end_.Hold(rendered, damping);
      if (a.acted) {
        ++acting_ticks_;
        for (int i = 0; i < 3; ++i) max_alpha_ = std::max(max_alpha_, a.alpha[i]);
      }
    }
    return inner_.WriteWristForce(side, applied_);
  }
  haptics::DeviceStatus WriteFingerForces(Side side,
                                          const std::array<double, haptics::kFingers>& c) override {
    return inner_.WriteFingerForces(side, c);
  }
  /// The command the arm holds now (device units).
  const Vec3d& applied() const { return applied_; }
  /// The arm's end's controller: J dissipated (all axes), ticks it acted, largest α.
  double dissipated() const { return arm_end_.dissipated_total_j(); }
  uint64_t acting_ticks() const { return acting_ticks_; }
  double max_alpha() const { return max_alpha_; }
  /// J: the loop's end's smallest margin (< 0: the loop's side drew energy
  /// the arm's side never put in; no controller acts there).
  double loop_margin_min() const { return loop_margin_min_; }

 private:
  static constexpr uint64_t kRing = kMaxDelayTicks + 1;
  struct Reading {
    haptics::WristRaw raw{};
    Vec3d energy_in{};  ///< the arm's end's E_in when it was read
  };
  struct Command {
    Vec3d command{};
    Vec3d energy_in{};  ///< the loop's end's E_in when it was written
  };
  Vec3d Metres(const Vec3d& raw) const {
    Vec3d m{};
    for (int i = 0; i < 3; ++i) m[i] = truth_.tracker_scale[i] * raw[i] + truth_.tracker_offset[i];
    return m;
  }
  Vec3d Newtons(const Vec3d& command) const { return inner_.MeasureForce(kSide, command); }

  haptics::SimDevice& inner_;
  int delay_;
  haptics::SimArmTruth truth_;
  double period_s_;
  bool two_port_;
  haptics::TwoPortPassivity arm_end_;
  haptics::TwoPortPassivity loop_end_;
  std::array<Reading, kRing> readings_{};
  std::array<Command, kRing> commands_{};
  uint64_t reads_ = 0, writes_ = 0;
  Vec3d applied_{};
  Vec3d arm_position_{}, arm_velocity_{}, loop_position_{}, loop_remote_in_{};
  bool loop_has_position_ = false;
  uint64_t acting_ticks_ = 0;
  double max_alpha_ = 0.0;
  double loop_margin_min_ = 0.0;
};

/// Simulated time for both ends of the UDP path: the server's arm steps to
/// it, and a wait for a reply first lets the in-process server handle what
/// the client sent (loopback delivers at once), so the run is one thread,
/// deterministic, and as fast as the sockets.
class SimClock final : public haptics::udp::Clock {
 public:
  int64_t now_ns = 0;
  haptics::udp::ArmServer* server = nullptr;
  int64_t NowNs() override { return now_ns; }
  WaitResult WaitReadable(int fd, int64_t deadline_ns) override {
    if (server != nullptr) server->Poll(0);
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 0) > 0) return WaitResult::kReadable;
    now_ns = std::max(now_ns, deadline_ns);  // nothing came: the wait ran out
    return WaitResult::kNotYet;
  }
};

/// The UDP path in one process: an ArmServer on a loopback socket serving
/// `arm`, and the UdpDevice the servo loop drives; a one-way command is
/// handled by the server at once, as a real-time server would.
class UdpPath final : public haptics::Device {
 public:
  UdpPath(haptics::SimDevice& arm, const DeviceConfig& config, double delay_s, bool two_port)
      : socket_(Bind(port_)),
        server_(arm, kSide, socket_.get(), Options(config, delay_s, two_port),
                haptics::udp::UnitsOf(arm, kSide), clock_),
        client_(ClientConfig(config, port_), clock_) {
    clock_.server = &server_;
  }
  SimClock& clock() { return clock_; }
  const haptics::udp::ArmServer& server() const { return server_; }
  const haptics::UdpDevice& client() const { return client_; }

  const haptics::DeviceDescription& description() const override { return client_.description(); }
  haptics::DeviceStatus ReadWrist(Side side, int64_t now_ns, haptics::WristRaw& out) override {
    return client_.ReadWrist(side, now_ns, out);
  }
  haptics::DeviceStatus ReadGlove(Side side, int64_t now_ns, haptics::GloveRaw& out) override {
    return client_.ReadGlove(side, now_ns, out);
  }
  haptics::DeviceStatus WriteWristForce(Side side, const Vec3d& command) override {
    const haptics::DeviceStatus s = client_.WriteWristForce(side, command);
    server_.Poll(0);
    return s;
  }
  haptics::DeviceStatus WriteFingerForces(Side side,
                                          const std::array<double, haptics::kFingers>& c) override {
    return client_.WriteFingerForces(side, c);
  }
  bool HasLink() const override { return client_.HasLink(); }
  bool LinkPassivity(Side side, haptics::LinkEnergy& remote) override {
    return client_.LinkPassivity(side, remote);
  }
  void SetLinkEnergy(Side side, const haptics::LinkEnergy& local) override {
    client_.SetLinkEnergy(side, local);
  }
  void RestartLinkEnergy(Side side) override { client_.RestartLinkEnergy(side); }

 private:
  static UniqueFd Bind(int& port) {
    UniqueFd fd(::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0));
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof addr;
    if (fd.get() < 0 || ::bind(fd.get(), reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
        ::getsockname(fd.get(), reinterpret_cast<sockaddr*>(&addr), &len) != 0) {
      throw std::runtime_error(std::string("cannot bind a loopback UDP socket: ") +
                               std::strerror(errno));
    }
    port = ntohs(addr.sin_port);
    return fd;
  }
  static haptics::udp::ArmServerOptions Options(const DeviceConfig& config, double delay_s,
                                                bool two_port) {
    haptics::udp::ArmServerOptions o;
    o.lost_after_s = config.udp.lost_after_s;
    o.delay_s = delay_s;
    o.passivity = two_port;
    o.limits.max_damping = config.servo.passivity_max_damping;
    o.limits.min_speed = config.servo.passivity_min_speed;
    return o;
  }
  static DeviceConfig ClientConfig(DeviceConfig config, int port) {
    config.driver = "udp";
    config.udp.arms[Index(kSide)] = {"127.0.0.1", port};
    return config;
  }

  int port_ = 0;
  SimClock clock_;
  UniqueFd socket_;
  haptics::udp::ArmServer server_;
  haptics::UdpDevice client_;
};

struct Point {
  double k = 0.0;
  double delay_ms = 0.0;
  Mode mode = Mode::kOff;
  bool stable = false;
  double spread = 0.0;        ///< m, peak to peak of x over the last 0.5 s
  double early_spread = 0.0;  ///< m, the same over the 0.5 s a second earlier
  double energy_j = 0.0;      ///< dissipated by the controller
  double max_alpha = 0.0;     ///< N·s/m
  uint64_t acting_ticks = 0;
  double force_rms_err = 0.0;  ///< N against the ideal wall (the box: a rigid box's inertia, -m a)
  double penetration = 0.0;    ///< m, mean over the last 0.5 s
  double loop_margin_min = 0.0;  ///< J, two-port: the loop's end's smallest margin
  double loop_energy_j = 0.0;    ///< J, UDP two-port: what the loop's end returned (its offset)
  uint64_t loop_acting_ticks = 0;
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

/// One run: the arm pressing into the wall, or (`box`) holding the grasped box.
Point Run(const DeviceConfig& device_config, const OperatorConfig& grip, double k, int delay_ticks,
          Mode mode, double seconds, std::vector<double>& tick_us, bool box = false) {
  DeviceConfig config = device_config;
  config.servo.passivity =
      mode == Mode::kOnePort || mode == Mode::kUdpTwoPort || mode == Mode::kUdpTwoPortAdmittance;
  config.servo.passivity_link_admittance = mode == Mode::kUdpTwoPortAdmittance;
  haptics::SimDevice arm(config, grip);
  arm.Place(kSide, {kStartX, 0.0, 0.0});
  arm.SetOperatorTarget(kSide,
                        box ? Vec3d{kStartX, 0.0, 0.0} : Vec3d{kWallX + kPushDepth, 0.0, 0.0});
  double box_x = kStartX + kBoxOffset, box_v = 0.0;
  double x_prev = kStartX, x_prev2 = kStartX;
  haptics::TwoPortLimits limits{config.servo.passivity_max_damping,
                                config.servo.passivity_min_speed};
  if (mode == Mode::kTwoPortRef) limits.max_credit_j = 0.0;
  const bool two_port = mode == Mode::kTwoPort || mode == Mode::kTwoPortRef;
  const bool udp = IsUdp(mode);
  DelayedDevice delayed(arm, udp ? 0 : delay_ticks, arm.truth(kSide), 1.0 / config.servo.rate_hz,
                        two_port ? &limits : nullptr);
  std::unique_ptr<UdpPath> path;
  if (udp)
    path = std::make_unique<UdpPath>(arm, config, delay_ticks * kPeriodNs * 1e-9,
                                     mode != Mode::kUdpOff);
  haptics::Device& device = udp ? static_cast<haptics::Device&>(*path) : delayed;
  const auto applied = [&]() -> const Vec3d& {
    return udp ? path->server().applied() : delayed.applied();
  };
  const DeviceCalibration calibration = Truth(arm);
  haptics::Hal hal(calibration);
  haptics::ServoLoop loop(device, hal, config, calibration);

  Point r;
  r.k = k;
  r.delay_ms = delay_ticks * kPeriodNs * 1e-6;
  r.mode = mode;
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
    if (box) {
      sp.coupling_target = {box_x, 0.0, 0.0};
    } else {
      sp.coupling_target = s.valid ? s.position : Vec3d{kStartX, 0.0, 0.0};
      sp.coupling_target[0] = std::min(sp.coupling_target[0], kWallX);
    }
    hal.SetSetpoint(kSide, sp, now);
    if (udp) path->clock().now_ns = now;
    const int64_t t0 = MonotonicNs();
    loop.Tick(kSide, now);
    tick_us.push_back(static_cast<double>(MonotonicNs() - t0) * 1e-3);

    const double period_s = kPeriodNs * 1e-9;
    if (box) {
      // The box: the coupling's reaction on the hand the loop saw (its
      // sample, as delayed as the loop's), semi-implicit Euler.
      const double hand = s.valid ? s.position[0] : kStartX;
      box_v += k * (hand - box_x) / kBoxMass * period_s;
      box_x += box_v * period_s;
    }
    const Vec3d x = arm.TruePosition(kSide);
    if (!std::isfinite(x[0]) || !std::isfinite(box_x)) return r;  // unstable
    const double t = static_cast<double>(i) * period_s;
    const double pen = box ? 0.0 : std::max(0.0, x[0] - kWallX);
    if (t >= kContactFromS) {
      const double felt = arm.MeasureForce(kSide, applied())[0];
      // A rigid box in the hand pushes back with its inertia alone.
      const double ideal =
          box ? -kBoxMass * (x[0] - 2.0 * x_prev + x_prev2) / (period_s * period_s) : -k * pen;
      err2 += (felt - ideal) * (felt - ideal);
      ++err_n;
    }
    x_prev2 = x_prev;
    x_prev = x[0];
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
  if (udp) {
    // The arm's end as the server counts it; the loop's end in the loop's counters.
    const haptics::udp::ServerCounters& sc = path->server().counters();
    r.energy_j = sc.passivity_dissipated_j;
    r.max_alpha = sc.passivity_max_alpha;
    r.acting_ticks = sc.passivity_ticks;
    r.loop_energy_j = c.passivity_dissipated_j;
    r.loop_acting_ticks = c.passivity_ticks;
  } else {
    r.energy_j = two_port ? delayed.dissipated() : c.passivity_dissipated_j;
    r.max_alpha = two_port ? delayed.max_alpha() : c.passivity_max_alpha;
    r.acting_ticks = two_port ? delayed.acting_ticks() : c.passivity_ticks;
    r.loop_margin_min = delayed.loop_margin_min();
  }
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
double LargestStable(const std::vector<Point>& points, double delay_ms, Mode mode) {
  double best = 0.0;
  for (const Point& p : points) {
    if (p.delay_ms != delay_ms || p.mode != mode) continue;
    if (!p.stable) break;
    best = p.k;
  }
  return best;
}

/// Per mode, per delay: the largest K stable (LargestStable).
using StableTable = std::array<std::vector<double>, kModes.size()>;

/// The table's rows, a delay each, printed as they are found.
StableTable PrintStableTable(const std::vector<Point>& points,
                             const std::vector<double>& delays_ms) {
  StableTable stable;
  for (const double delay : delays_ms) {
    std::printf("  %8.0f", delay);
    for (size_t m = 0; m < kModes.size(); ++m) {
      stable[m].push_back(LargestStable(points, delay, kModes[m]));
      std::printf(" %14.0f", stable[m].back());
    }
    std::printf("\n");
  }
  return stable;
}

const Point* Find(const std::vector<Point>& points, double k, double delay_ms, Mode mode) {
  for (const Point& p : points) {
    if (p.k == k && p.delay_ms == delay_ms && p.mode == mode) return &p;
  }
  return nullptr;
}

/// The servo loop's own period, threaded at the device file's rate and
/// scheduling, with the controller off and on, beside the bare loop
/// (bare_loop.hpp): `rounds` rounds of the three, each `seconds` long, the
/// order rotated every round so the machine's drift falls on all three alike.
struct LoopTiming {
  static constexpr int kBare = 0, kOff = 1, kOn = 2;
  std::array<std::vector<double>, 3> p99_us;  ///< per kind, one per round
  std::array<double, 3> median_us{};          ///< per kind, over the rounds
  double bare_spread_us = 0.0;                ///< the bare loop's p99, largest minus smallest round
  double bin_us = 10.0;         ///< the period histogram's bin: percentiles come in whole bins
  double tolerance_us = 0.0;    ///< what "unchanged" allows: max(spread, one bin)
  bool unchanged = false;       ///< |on − off| within the tolerance
  uint64_t allocations_on = 0;  ///< in the process while the loop ran with the controller
  bool realtime = false;
};

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

LoopTiming MeasureLoopTiming(const DeviceConfig& shipped, int rounds, double seconds) {
  LoopTiming t;
  DeviceConfig config = shipped;
  config.driver = "sim";
  for (int round = 0; round < rounds; ++round) {
    for (int j = 0; j < 3; ++j) {
      const int kind = (round + j) % 3;
      if (kind == LoopTiming::kBare) {
        const BareLoop bare =
            MeasureBareLoop(config.servo.rate_hz, config.servo.realtime_priority, seconds);
        t.p99_us[kind].push_back(bare.stats.period_p99_us);
        t.bin_us = bare.bin_us;
        t.realtime = bare.stats.realtime;
        continue;
      }
      config.servo.passivity = kind == LoopTiming::kOn;
      haptics::SimDevice arms(config, OperatorConfig{});
      const ServoLoopRun run = MeasureServoLoop(arms, config, seconds);
      t.p99_us[kind].push_back(run.stats.period_p99_us);
      if (kind == LoopTiming::kOn) t.allocations_on += run.allocations;
    }
  }
  for (int kind = 0; kind < 3; ++kind) t.median_us[kind] = Median(t.p99_us[kind]);
  const auto [lo, hi] =
      std::minmax_element(t.p99_us[LoopTiming::kBare].begin(), t.p99_us[LoopTiming::kBare].end());
  t.bare_spread_us = *hi - *lo;
  // The percentiles come in whole bins: a spread of zero still allows one.
  t.tolerance_us = std::max(t.bare_spread_us, t.bin_us);
  t.unchanged =
      std::abs(t.median_us[LoopTiming::kOn] - t.median_us[LoopTiming::kOff]) <= t.tolerance_us;
  return t;
}

}  // namespace

int BenchPassivityMain(int argc, const char* const* argv) {
  bool json = false, smoke = false;
  DeviceConfig device;
  try {
    const Args args(argc, argv, {"device"}, {"json", kSmokeFlag});
    json = args.Flag("json");
    smoke = args.Flag(kSmokeFlag);
    device =
        LoadDevice(args.Value("device").value_or(ShippedFile("config/devices/sim.yaml").string()));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel bench passivity: %s\n", e.what());
    return 2;
  }
  // The loop's timing runs on the device file as shipped (its arms, rate and
  // scheduling); the wall's runs below in simulated time on one arm.
  const DeviceConfig shipped = device;
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
  grip.tremor_amplitude = 0.0;  // the loop's stability is measured, not the hand's shaking

  const std::vector<double> delays_ms =
      smoke ? std::vector<double>{0, 3} : std::vector<double>{0, 1, 3, 5};
  const double k_max = smoke ? 1000.0 : 64000.0;
  const double seconds = smoke ? 1.5 : 4.0;
  PrintSmokeNote("passivity", smoke, "delays 0 and 3 ms, K up to %.0f N/m, %.1f s runs", k_max,
                 seconds);
  const auto dir = OutputDir(smoke);
  const double period_s = 1.0 / device.servo.rate_hz;
  const double bound = 2.0 * device.sim.damping / period_s;
  std::printf(
      "haptel bench passivity: %s; sim arm %.3g kg, damping b = %.3g N*s/m, Coulomb %.3g N, force "
      "limit\n"
      "  %.3g N; light grip %.0f N/m, %.1f N*s/m aiming %.0f mm into the wall; controller cap %.3g "
      "N*s/m,\n"
      "  speed floor %.3g m/s; passivity bound 2b/T = %.4g N/m\n\n",
      device.file.empty() ? "defaults" : device.file.c_str(), device.sim.arm_mass,
      device.sim.damping, device.sim.coulomb_friction, device.sim.force_limit,
      grip.muscle_stiffness, grip.muscle_damping, kPushDepth * 1e3,
      device.servo.passivity_max_damping, device.servo.passivity_min_speed, bound);

  std::vector<Point> points;
  std::array<std::vector<double>, kModes.size()> ticks;
  const double t_start = NsToS(MonotonicNs());
  for (const double delay : delays_ms) {
    const int delay_ticks = static_cast<int>(std::lround(delay * 1e-3 / period_s));
    for (size_t m = 0; m < kModes.size(); ++m) {
      for (double k = 250.0; k <= k_max; k *= 2.0) {
        points.push_back(Run(device, grip, k, delay_ticks, kModes[m], seconds, ticks[m]));
      }
    }
  }
  // The grasped box, the same sweep (its ticks are not timed: the wall's are).
  std::vector<Point> box_points;
  std::vector<double> untimed;
  for (const double delay : delays_ms) {
    const int delay_ticks = static_cast<int>(std::lround(delay * 1e-3 / period_s));
    for (const Mode mode : kModes) {
      for (double k = 250.0; k <= k_max; k *= 2.0) {
        box_points.push_back(Run(device, grip, k, delay_ticks, mode, seconds, untimed, true));
        untimed.clear();
      }
    }
  }
  const double wall_s = NsToS(MonotonicNs()) - t_start;
  const int timing_rounds = smoke ? 2 : 3;
  const double timing_seconds = smoke ? 0.3 : 3.0;
  const LoopTiming timing = MeasureLoopTiming(shipped, timing_rounds, timing_seconds);

  std::printf("  %8s %9s |", "delay ms", "K N/m");
  for (const Mode m : kModes) std::printf(" %12s %7s |", ModeName(m), "F err N");
  std::printf(" %10s %7s %10s\n", "2-port J", "acted", "loop W mJ");
  for (const double delay : delays_ms) {
    for (double k = 250.0; k <= k_max; k *= 2.0) {
      std::printf("  %8.0f %9.0f |", delay, k);
      for (const Mode m : kModes) {
        const Point* p = Find(points, k, delay, m);
        std::printf(" %12s %7.3f |", p->stable ? "stable" : "OSC", p->force_rms_err);
      }
      const Point* tp = Find(points, k, delay, Mode::kTwoPort);
      std::printf(" %10.4g %7llu %10.3g\n", tp->energy_j,
                  static_cast<unsigned long long>(tp->acting_ticks), tp->loop_margin_min * 1e3);
    }
  }
  std::printf("\n  %8s", "delay ms");
  for (const Mode m : kModes) std::printf(" %14s", ModeName(m));
  std::printf("   largest K stable (N/m) before the first unstable one\n");
  // stable[m][d]: the largest stable K of mode m at delay d.
  const StableTable stable = PrintStableTable(points, delays_ms);
  // The figures at the target's delay (the largest delay run in a smoke run).
  size_t at = delays_ms.size() - 1;
  for (size_t i = 0; i < delays_ms.size(); ++i) {
    if (delays_ms[i] == kTargetDelayMs) at = i;
  }
  const auto index = [](Mode mode) {
    return static_cast<size_t>(std::find(kModes.begin(), kModes.end(), mode) - kModes.begin());
  };
  const double k_off = stable[0][at];
  std::array<double, kModes.size()> gain{}, p99{}, err_common{}, err_own{};
  size_t best = 1;
  for (size_t m = 0; m < kModes.size(); ++m) {
    // Each path against itself without a controller: the UDP rows against udp-off.
    const double k_base = stable[index(Baseline(kModes[m]))][at];
    gain[m] = k_base > 0 ? stable[m][at] / k_base : 0.0;
    if (m > 0 && !IsUdp(kModes[m]) && gain[m] > gain[best]) best = m;
    p99[m] = Percentile(ticks[m], 0.99);
    // Transparency: the force error at the stiffnesses stable both off and in
    // this mode (comparable across modes), and at this mode's own largest.
    int n = 0;
    for (double k = 250.0; k <= std::min(stable[index(Baseline(kModes[m]))][at], stable[m][at]);
         k *= 2.0) {
      err_common[m] += Find(points, k, delays_ms[at], kModes[m])->force_rms_err;
      ++n;
    }
    if (n > 0) err_common[m] /= n;
    const Point* own = Find(points, stable[m][at], delays_ms[at], kModes[m]);
    err_own[m] = own != nullptr ? own->force_rms_err : 0.0;
  }
  const double cost = std::max(0.0, p99[best] - p99[0]);
  const size_t udp_on = index(Mode::kUdpTwoPort),
               udp_off = index(Mode::kUdpOff);  // the default: charge
  std::printf(
      "\n  at %.0f ms each way, against K stable %.0f N/m off (the UDP rows: %.0f N/m udp-off):\n",
      delays_ms[at], k_off, stable[udp_off][at]);
  for (size_t m = 1; m < kModes.size(); ++m) {
    const size_t base = index(Baseline(kModes[m]));
    if (m == base) continue;
    std::printf(
        "    %-12s K stable %6.0f N/m, gain %.3g; force RMS error %.3f N (%s %.3f N) over K <= "
        "%.0f N/m,"
        " %.3f N at its largest; tick p99 %.3g us\n",
        ModeName(kModes[m]), stable[m][at], gain[m], err_common[m], ModeName(kModes[base]),
        err_common[base], std::min(stable[base][at], stable[m][at]), err_own[m], p99[m]);
  }
  const size_t udp_admit = index(Mode::kUdpTwoPortAdmittance);
  std::printf(
      "  across the real UDP path (protocol v2, the two-port's ends in the servo loop and the "
      "server):\n"
      "    gain %.3g with the loop's end charging its deficit to the arm's (the default; target >= "
      "3) %s;\n"
      "    %.3g with the loop's end's admittance, at %.3g N of force error against %.3g N "
      "udp-off\n",
      gain[udp_on], gain[udp_on] >= 3.0 ? "met" : "MISSED", gain[udp_admit], err_common[udp_admit],
      err_common[udp_off]);
  std::printf(
      "  best: %s, gain %.3g (target >= 3) %s; it costs %.3g us of tick p99 (off %.3g us; target "
      "<= 2) %s\n"
      "  %zu runs (the wall's and the box's) in %.1f s wall; wrote %s/passivity.csv, "
      "passivity.png\n",
      ModeName(kModes[best]), gain[best], gain[best] >= 3.0 ? "met" : "MISSED", cost, p99[0],
      cost <= 2.0 ? "met" : "MISSED", points.size() + box_points.size(), wall_s, dir.c_str());

  // The grasped box: largest stable K per mode and delay, and the gains at the target's delay.
  std::printf(
      "\n  the grasped box (%.2g kg, grasped %.0f mm from the hand and held still), largest K "
      "stable (N/m):\n"
      "  %8s",
      kBoxMass, kBoxOffset * 1e3, "delay ms");
  for (const Mode m : kModes) std::printf(" %14s", ModeName(m));
  std::printf("\n");
  const StableTable box_stable = PrintStableTable(box_points, delays_ms);
  std::array<double, kModes.size()> box_gain{}, box_err{};
  for (size_t m = 0; m < kModes.size(); ++m) {
    const double k_base = box_stable[index(Baseline(kModes[m]))][at];
    box_gain[m] = k_base > 0 ? box_stable[m][at] / k_base : 0.0;
    int n = 0;
    for (double k = 250.0; k <= std::min(k_base, box_stable[m][at]); k *= 2.0) {
      box_err[m] += Find(box_points, k, delays_ms[at], kModes[m])->force_rms_err;
      ++n;
    }
    if (n > 0) box_err[m] /= n;
  }
  std::printf(
      "  at %.0f ms: gain %.3g %s, %.3g udp-two-port; force RMS error against a rigid box's "
      "inertia %.3f N\n"
      "  %s, %.3f N off, over the K stable both ways; wrote %s/passivity_box.csv\n",
      delays_ms[at], box_gain[best], ModeName(kModes[best]), box_gain[udp_on], box_err[best],
      ModeName(kModes[best]), box_err[0], dir.c_str());

  std::printf(
      "\n  the servo loop itself (threaded, %s, %.0f Hz, %s): period p99 over %d rounds of %.1f s "
      "each,\n"
      "  the three kinds in a rotated order; \"unchanged\": on within off's p99 +- the bare loop's "
      "own\n"
      "  spread over the rounds (or one %.0f us bin, whichever is larger)\n",
      shipped.file.empty() ? "defaults" : shipped.file.filename().c_str(), shipped.servo.rate_hz,
      timing.realtime ? "SCHED_FIFO" : "not real-time: SCHED_FIFO refused", timing_rounds,
      timing_seconds, timing.bin_us);
  std::printf("    %-22s %10s %8s   %s\n", "loop", "p99 us", "x bare", "p99 per round (us)");
  const char* kind_names[3] = {"bare clock_nanosleep", "servo, controller off",
                               "servo, controller on"};
  for (int kind = 0; kind < 3; ++kind) {
    std::printf("    %-22s %10.0f %8.2f  ", kind_names[kind], timing.median_us[kind],
                timing.median_us[0] > 0 ? timing.median_us[kind] / timing.median_us[0] : 0.0);
    for (const double v : timing.p99_us[kind]) std::printf(" %.0f", v);
    std::printf("\n");
  }
  std::printf(
      "    on - off = %+.0f us against a tolerance of %.0f us (bare spread %.0f us): %s; "
      "allocations with the\n"
      "    controller on: %llu\n",
      timing.median_us[2] - timing.median_us[1], timing.tolerance_us, timing.bare_spread_us,
      timing.unchanged ? "unchanged (met)" : "CHANGED (missed)",
      static_cast<unsigned long long>(timing.allocations_on));

  {
    std::ofstream csv(dir / "passivity.csv");
    csv << "stiffness,delay_ms,mode,stable,spread_m,energy_j,max_alpha,acting_ticks,force_rms_err_"
           "n,penetration_m,"
           "loop_margin_min_j,loop_energy_j,loop_acting_ticks\n";
    for (const Point& p : points) {
      csv << p.k << "," << p.delay_ms << "," << ModeName(p.mode) << "," << (p.stable ? 1 : 0) << ","
          << p.spread << "," << p.energy_j << "," << p.max_alpha << "," << p.acting_ticks << ","
          << p.force_rms_err << "," << p.penetration << "," << p.loop_margin_min << ","
          << p.loop_energy_j << "," << p.loop_acting_ticks << "\n";
    }
  }
  {
    std::ofstream csv(dir / "passivity_box.csv");
    csv << "stiffness,delay_ms,mode,stable,spread_m,energy_j,max_alpha,acting_ticks,force_rms_err_"
           "n\n";
    for (const Point& p : box_points) {
      csv << p.k << "," << p.delay_ms << "," << ModeName(p.mode) << "," << (p.stable ? 1 : 0) << ","
          << p.spread << "," << p.energy_j << "," << p.max_alpha << "," << p.acting_ticks << ","
          << p.force_rms_err << "\n";
    }
  }
  {
    std::vector<Series> series;
    for (size_t m = 0; m < kModes.size(); ++m) {
      Series line{std::string("largest stable K, ") + ModeName(kModes[m]), {}, {}};
      for (size_t i = 0; i < delays_ms.size(); ++i)
        line.x.push_back(delays_ms[i]), line.y.push_back(std::max(stable[m][i], 1.0));
      series.push_back(line);
    }
    Series pb{"passivity bound 2b/T", {}, {}};
    for (const double d : delays_ms) pb.x.push_back(d), pb.y.push_back(bound);
    series.push_back(pb);
    PlotOptions o;
    o.title = "Virtual wall: largest stable coupling stiffness vs device delay";
    o.x_label = "device delay each way (ms)";
    o.y_label = "K (N/m)";
    o.log_y = true;
    try {
      PlotLines(dir / "passivity.png", series, o);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "haptel bench passivity: %s\n", e.what());
    }
  }

  if (json) {
    // JSON keys: "on" is the one-port controller (as before the two-port).
    const auto key = [](Mode m) -> std::string {
      switch (m) {
        case Mode::kOff:
          return "off";
        case Mode::kOnePort:
          return "on";
        case Mode::kTwoPort:
          return "two_port";
        case Mode::kTwoPortRef:
          return "two_port_ref";
        case Mode::kUdpOff:
          return "udp_off";
        case Mode::kUdpTwoPort:
          return "udp_two_port";
        case Mode::kUdpTwoPortAdmittance:
          return "udp_two_port_admittance";
      }
      return "?";
    };
    std::ostringstream o;
    o << "{\"delay_ms\":" << JsonNumber(delays_ms[at]);
    for (size_t m = 0; m < kModes.size(); ++m)
      o << ",\"stable_stiffness_" << key(kModes[m]) << "\":" << JsonNumber(stable[m][at]);
    o << ",\"gain\":" << JsonNumber(gain[best]) << ",\"gain_mode\":\"" << ModeName(kModes[best])
      << "\"";
    // The UDP rows' own, each over udp_off's: the default (charge), and the admittance.
    o << ",\"gain_udp\":" << JsonNumber(gain[udp_on])
      << ",\"gain_udp_admittance\":" << JsonNumber(gain[index(Mode::kUdpTwoPortAdmittance)]);
    for (size_t m = 1; m < kModes.size(); ++m) {
      if (kModes[m] != Mode::kUdpOff)
        o << ",\"gain_" << key(kModes[m]) << "\":" << JsonNumber(gain[m]);
    }
    o << ",\"passivity_bound\":" << JsonNumber(bound) << ",\"cost_us_p99\":" << JsonNumber(cost);
    o << ",\"servo_p99_us_bare\":" << JsonNumber(timing.median_us[LoopTiming::kBare])
      << ",\"servo_p99_us_off\":" << JsonNumber(timing.median_us[LoopTiming::kOff])
      << ",\"servo_p99_us_on\":" << JsonNumber(timing.median_us[LoopTiming::kOn])
      << ",\"servo_p99_spread_us_bare\":" << JsonNumber(timing.bare_spread_us)
      << ",\"servo_p99_tolerance_us\":" << JsonNumber(timing.tolerance_us)
      << ",\"servo_p99_unchanged\":" << (timing.unchanged ? "true" : "false")
      << ",\"servo_allocations_on\":" << timing.allocations_on
      << ",\"servo_realtime\":" << (timing.realtime ? "true" : "false");
    for (size_t m = 0; m < kModes.size(); ++m) {
      o << ",\"tick_us_p99_" << key(kModes[m]) << "\":" << JsonNumber(p99[m])
        << ",\"force_rms_err_n_" << key(kModes[m]) << "\":" << JsonNumber(err_common[m])
        << ",\"force_rms_err_n_at_stable_" << key(kModes[m]) << "\":" << JsonNumber(err_own[m]);
    }
    o << ",\"delays\":[";
    for (size_t i = 0; i < delays_ms.size(); ++i) {
      o << (i ? "," : "") << "{\"delay_ms\":" << JsonNumber(delays_ms[i]);
      for (size_t m = 0; m < kModes.size(); ++m)
        o << ",\"stable_stiffness_" << key(kModes[m]) << "\":" << JsonNumber(stable[m][i]);
      o << "}";
    }
    o << "],\"box\":{\"mass_kg\":" << JsonNumber(kBoxMass);
    for (size_t m = 0; m < kModes.size(); ++m) {
      o << ",\"stable_stiffness_" << key(kModes[m]) << "\":" << JsonNumber(box_stable[m][at]);
    }
    o << ",\"gain\":" << JsonNumber(box_gain[best])
      << ",\"gain_udp\":" << JsonNumber(box_gain[udp_on]) << ",\"force_rms_err_n_"
      << key(kModes[best]) << "\":" << JsonNumber(box_err[best])
      << ",\"force_rms_err_n_off\":" << JsonNumber(box_err[0]) << ",\"points\":[";
    for (size_t i = 0; i < box_points.size(); ++i) {
      const Point& p = box_points[i];
      o << (i ? "," : "") << "{\"stiffness\":" << JsonNumber(p.k)
        << ",\"delay_ms\":" << JsonNumber(p.delay_ms) << ",\"mode\":\"" << ModeName(p.mode)
        << "\",\"stable\":" << (p.stable ? "true" : "false")
        << ",\"energy_j\":" << JsonNumber(p.energy_j)
        << ",\"force_rms_err_n\":" << JsonNumber(p.force_rms_err) << "}";
    }
    o << "]},\"points\":[";
    for (size_t i = 0; i < points.size(); ++i) {
      const Point& p = points[i];
      o << (i ? "," : "") << "{\"stiffness\":" << JsonNumber(p.k)
        << ",\"delay_ms\":" << JsonNumber(p.delay_ms) << ",\"mode\":\"" << ModeName(p.mode)
        << "\",\"stable\":" << (p.stable ? "true" : "false")
        << ",\"energy_j\":" << JsonNumber(p.energy_j)
        << ",\"loop_energy_j\":" << JsonNumber(p.loop_energy_j)
        << ",\"force_rms_err_n\":" << JsonNumber(p.force_rms_err) << "}";
    }
    o << "]}";
    std::printf("%s\n", JsonLine(o.str(), smoke).c_str());
  }
  return 0;
}

}  // namespace haptel::bench
