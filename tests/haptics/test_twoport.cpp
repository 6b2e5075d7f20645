// The two-port time-domain passivity observer and controller across a
// delayed channel, on hand-computed ticks and on a delayed spring.
#include <catch2/catch.hpp>
#include <cmath>
#include <deque>
#include <limits>

#include "haptel/haptics/twoport.hpp"

using namespace haptel::haptics;

namespace {
constexpr double kT = 0.001;  // s
const Vec3d kZero{};
Vec3d X(double x) { return {x, 0.0, 0.0}; }
}  // namespace

TEST_CASE("two-port: the ends split the energy crossing them by the power's sign") {
  TwoPortPassivity loop(ChannelEnd::kLoop);
  TwoPortPassivity arm(ChannelEnd::kDevice);
  // A wall resisting the motion (-2 N rendered, hand moving +1 mm): at the
  // loop's end the environment absorbs 2 mJ (out of the channel), at the
  // arm's end the arm pushes 2 mJ into it.
  loop.Hold(X(-2.0));
  arm.Hold(X(-2.0));
  loop.Observe(X(0.001));
  arm.Observe(X(0.001));
  CHECK(loop.energy_out()[0] == Approx(0.002));
  CHECK(loop.energy_in()[0] == 0.0);
  CHECK(arm.energy_in()[0] == Approx(0.002));
  CHECK(arm.energy_out()[0] == 0.0);
  // The wall pushing the hand back out 1 mm returns it.
  loop.Observe(X(-0.001));
  arm.Observe(X(-0.001));
  CHECK(loop.energy_in()[0] == Approx(0.002));
  CHECK(arm.energy_out()[0] == Approx(0.002));
}

TEST_CASE(
    "two-port: a channel that delivers more than the other end put in is damped by the excess") {
  TwoPortPassivity arm(ChannelEnd::kDevice, TwoPortLimits{100.0, 0.01});
  // The loop's end reports 2 mJ put in; the arm's end was pushed out 1 mm by
  // -3 N: 3 mJ delivered, W = 2 - 3 = -1 mJ. At -1 m/s:
  // alpha = 0.001 / (0.001 * 1^2) = 1 N*s/m, a force of -alpha*v = +1 N.
  arm.Hold(X(-3.0));
  arm.Observe(X(-0.001));
  const TwoPortAction a = arm.Control(X(-3.0), X(0.002), X(-1.0), kT);
  CHECK(a.acted);
  CHECK(a.alpha[0] == Approx(1.0));
  CHECK(a.damping_force[0] == Approx(1.0));
  CHECK(a.alpha[1] == 0.0);  // nothing crossed on y and z: left alone
  CHECK(a.alpha[2] == 0.0);
  // Over the next millimetre the channel delivers 3 mJ more while the loop's
  // end has put in 3 mJ more (5 mJ): the damper's measured 1 mJ closes the
  // gap exactly and the controller lets go. What left the channel net of the
  // damping (6 - 1 mJ) does not exceed what entered it (5 mJ).
  arm.Observe(X(-0.001));
  CHECK(arm.dissipated()[0] == Approx(0.001));
  CHECK(arm.dissipated_total_j() == Approx(0.001));  // y and z dissipated nothing
  CHECK(arm.energy_out()[0] - arm.dissipated()[0] == Approx(0.005));
  CHECK(arm.Margin(X(0.005))[0] == Approx(0.0).margin(1e-15));
  CHECK_FALSE(arm.Control(X(-3.0), X(0.005), X(-1.0), kT).acted);
}

TEST_CASE("two-port: a passive channel is left alone") {
  TwoPortPassivity arm(ChannelEnd::kDevice, TwoPortLimits{100.0, 0.01});
  // The arm delivered 1 mJ while the loop's end had put in 3 mJ: W = +2 mJ.
  arm.Hold(X(-1.0));
  arm.Observe(X(-0.001));
  const TwoPortAction a = arm.Control(X(-1.0), X(0.003), X(-1.0), kT);
  CHECK_FALSE(a.acted);
  CHECK(a.damping_force[0] == 0.0);
  CHECK(arm.Margin(X(0.003))[0] == Approx(0.002));
}

TEST_CASE("two-port: an end without a controller charges its deficit to the other end") {
  TwoPortPassivity loop(ChannelEnd::kLoop);
  // The environment absorbed 3 mJ (-3 N against +1 mm) and gave back 1 mJ
  // (-1 N over -1 mm) while the arm had put in only 2 mJ: the loop's end
  // handed out 1 mJ nobody put in and sends E_in - 1 mJ = 0.
  loop.Hold(X(-3.0));
  loop.Observe(X(0.001));
  loop.Hold(X(-1.0));
  loop.Observe(X(-0.001));
  CHECK(loop.energy_in()[0] == Approx(0.001));
  CHECK(loop.Margin(X(0.002))[0] == Approx(-0.001));
  CHECK(loop.EnergyToSend(X(0.002))[0] == Approx(0.0).margin(1e-15));
  // With the arm's 4 mJ it has no deficit and sends its E_in as it is.
  CHECK(loop.EnergyToSend(X(0.004))[0] == Approx(0.001));
}

TEST_CASE("two-port: a bounded credit forgets the surplus, so a later excess is damped") {
  TwoPortLimits unbounded{100.0, 0.01};
  TwoPortLimits bounded = unbounded;
  bounded.max_credit_j = 0.0;
  TwoPortPassivity plain(ChannelEnd::kDevice, unbounded), capped(ChannelEnd::kDevice, bounded);
  for (TwoPortPassivity* pc : {&plain, &capped}) {
    // 5 mJ put in at the other end, none delivered yet: 5 mJ of credit.
    CHECK_FALSE(pc->Control(X(-1.0), X(0.005), X(-1.0), kT).acted);
    // 1 mJ delivered, nothing more put in.
    pc->Observe(X(-0.001));
  }
  // Unbounded, 4 mJ of credit remain; bounded at 0, the 5 mJ were forgotten
  // and the 1 mJ delivered since is an excess: alpha = 1 N*s/m.
  CHECK_FALSE(plain.Control(X(-1.0), X(0.005), X(-1.0), kT).acted);
  const TwoPortAction a = capped.Control(X(-1.0), X(0.005), X(-1.0), kT);
  CHECK(a.acted);
  CHECK(a.alpha[0] == Approx(1.0));
}

TEST_CASE("two-port: alpha is capped and v^2 floored") {
  TwoPortPassivity arm(ChannelEnd::kDevice, TwoPortLimits{5.0, 0.01});
  arm.Hold(X(-1.0));
  arm.Observe(X(-0.001));  // W = -1 mJ
  // Near rest: v^2 floored at 1e-4, alpha = 0.001 / (0.001 * 1e-4) = 1e4, capped at 5.
  const TwoPortAction a = arm.Control(X(-1.0), kZero, X(1e-6), kT);
  CHECK(a.alpha[0] == Approx(5.0));
  CHECK(std::isfinite(a.damping_force[0]));
  arm.Reset();
  CHECK(arm.energy_out()[0] == 0.0);
  CHECK_FALSE(arm.Control(X(-1.0), kZero, X(1.0), kT).acted);
}

namespace {

/// A 0.5 kg mass (the arm) on one end of a channel delayed `delay` ticks
/// each way, a 2000 N/m spring (the virtual environment) on the other,
/// started 1 cm into the spring at rest (0.1 J), no friction. Returns the
/// largest kinetic energy the mass reaches in 3 s: what the channel
/// delivered to the arm. `final_energy` is the mass's kinetic plus the
/// spring's energy at the end, `margin_min` the arm's end's smallest margin.
double DelayedSpring(int delay, bool control, double& margin_min, double& final_energy) {
  constexpr double kMass = 0.5, kK = 2000.0, kX0 = 0.01;
  TwoPortPassivity loop(ChannelEnd::kLoop);
  // The cap keeps the damper stable on the 0.5 kg mass at 1 ms (alpha*T/m <= 0.8).
  TwoPortPassivity arm(ChannelEnd::kDevice, TwoPortLimits{400.0, 1e-4});
  std::deque<double> to_loop(static_cast<size_t>(delay), kX0);  // positions
  std::deque<Vec3d> to_loop_energy(static_cast<size_t>(delay), Vec3d{});
  std::deque<double> to_arm(static_cast<size_t>(delay), -kK * kX0);  // forces
  std::deque<Vec3d> to_arm_energy(static_cast<size_t>(delay), Vec3d{});
  double x = kX0, v = 0.0, x_loop_prev = kX0, x_prev = kX0, force = -kK * kX0, largest = 0.0;
  margin_min = std::numeric_limits<double>::infinity();
  for (int n = 0; n < 3000; ++n) {
    // The arm moves over one period under the force it holds.
    v += force / kMass * kT;
    x += v * kT;
    arm.Observe(X(x - x_prev));
    x_prev = x;
    to_loop.push_back(x);
    to_loop_energy.push_back(arm.energy_in());
    // The loop's end: the position from a delay ago, the spring's answer.
    const double x_loop = to_loop.front();
    const Vec3d arm_in = to_loop_energy.front();
    to_loop.pop_front();
    to_loop_energy.pop_front();
    loop.Observe(X(x_loop - x_loop_prev));
    x_loop_prev = x_loop;
    const double spring = -kK * x_loop;
    loop.Hold(X(spring));
    to_arm.push_back(spring);
    to_arm_energy.push_back(loop.EnergyToSend(arm_in));
    // The arm's end: the force from a delay ago, damped if need be.
    const double rendered = to_arm.front();
    const Vec3d remote_in = to_arm_energy.front();
    to_arm.pop_front();
    to_arm_energy.pop_front();
    force = rendered;
    if (control) {
      const TwoPortAction a = arm.Control(X(rendered), remote_in, X(v), kT);
      force += a.damping_force[0];
    } else {
      arm.Hold(X(rendered));
    }
    margin_min = std::min(margin_min, arm.Margin(remote_in)[0]);
    largest = std::max(largest, 0.5 * kMass * v * v);
    final_energy = 0.5 * kMass * v * v + 0.5 * kK * x_loop * x_loop;
  }
  return largest;
}

}  // namespace

TEST_CASE("two-port: a delayed spring that gains energy is held to what the spring put in") {
  double margin_min = 0.0, final_energy = 0.0;
  // Without the controller the 5 ms delay each way pumps the oscillation up:
  // the mass reaches more kinetic energy than the spring ever held.
  CHECK(DelayedSpring(5, false, margin_min, final_energy) > 0.3);
  CHECK(margin_min < -0.01);
  CHECK(final_energy > 0.2);
  // With it, the mass never gets more than the spring's 0.1 J (10 % for the
  // explicit integration's own ripple, ~omega*T), and the oscillation dies
  // down: its energy at least halves in 3 s.
  // The spring itself may hold more for a while: the loop's end has no
  // controller, and what it handed the spring beyond the arm's input is
  // charged to the arm's end, paid as the spring gives it back.
  CHECK(DelayedSpring(5, true, margin_min, final_energy) < 0.11);
  CHECK(final_energy < 0.05);
  // Without delay the channel is lossless and the controller stays idle.
  double idle_margin = 0.0;
  CHECK(DelayedSpring(0, true, idle_margin, final_energy) < 0.11);
  CHECK(idle_margin >= -1e-12);
}

TEST_CASE(
    "two-port: the loop's end returns its deficit on the environment's port by an offset, capped") {
  // The environment (a wall) holds -2 N on the hand while the channel hands it
  // 1 mm of motion into the wall: 2 mJ out of the channel at the loop's end,
  // against 1.5 mJ the arm's end reports in. W = -0.5 mJ.
  TwoPortLimits roomy;
  roomy.max_damping = 2.0;  // series admittance 0.5 m/(N*s): cap T*|f|/b = 1 mm
  TwoPortPassivity loop(ChannelEnd::kLoop, roomy);
  loop.Hold(X(-2.0));
  loop.Observe(X(0.001));
  REQUIRE(loop.Margin(X(0.0015))[0] == Approx(-0.0005));
  bool acted = false;
  // Offset = -W/f = 0.0005 / -2 = -0.25 mm: the environment is handed the
  // hand 0.25 mm less deep, and f*offset = +0.5 mJ returns the deficit.
  const Vec3d offset = loop.ControlPosition(X(0.0015), kT, &acted);
  CHECK(acted);
  CHECK(offset[0] == Approx(-0.00025));
  CHECK(loop.dissipated()[0] == Approx(0.0005));
  CHECK(loop.Margin(X(0.0015))[0] == Approx(0.0).margin(1e-12));
  CHECK(loop.charged()[0] == 0.0);

  // Capped (b = 20 N*s/m: 0.1 mm per tick), it returns 0.2 mJ and charges the
  // 0.3 mJ left to the arm's end.
  TwoPortPassivity capped(ChannelEnd::kLoop);
  capped.Hold(X(-2.0));
  capped.Observe(X(0.001));
  CHECK(capped.ControlPosition(X(0.0015), kT)[0] == Approx(-0.0001));
  CHECK(capped.dissipated()[0] == Approx(0.0002));
  CHECK(capped.charged()[0] == Approx(0.0003));

  // A passive end (the arm put in more than the environment took) is left alone.
  TwoPortPassivity passive(ChannelEnd::kLoop, roomy);
  passive.Hold(X(-2.0));
  passive.Observe(X(0.001));
  acted = false;
  CHECK(passive.ControlPosition(X(0.003), kT, &acted)[0] == 0.0);
  CHECK_FALSE(acted);
}
