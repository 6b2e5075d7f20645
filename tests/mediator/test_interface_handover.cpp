// The person's interface handed from one fleet vehicle to another
// (interface_handover.hpp): one interface live at a time, its forces faded
// through the HAL's force scale (never stepped), the one left paused at
// zero, and the person's input given to the driven vehicle only.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "haptel/haptics/force_field.hpp"
#include "haptel/haptics/hal.hpp"
#include "haptel/mediator/interface_handover.hpp"

using namespace haptel;
using haptel::haptics::Side;
using haptel::mediator::HandoverSide;
using haptel::mediator::InterfaceHandover;

namespace {

/// A vehicle's interface as the session drives it: a centring field of its
/// own stiffness on the right hand, refreshed whenever it renders; and
/// everything that happened to it, in order.
class FakeSide final : public HandoverSide {
 public:
  FakeSide(std::string name, double stiffness, std::vector<std::string>& log)
      : name_(std::move(name)), stiffness_(stiffness), log_(log) {}

  /// The session commanded its vehicle with the person's input (FamilySession::Command).
  void Command(double t_s, haptics::Hal& hal, const interfaces::InputState& input) {
    Render(hal);
    driven_t.push_back(t_s);
    presses_seen = input.presses_up;
  }
  void RenderForces(double t_s, haptics::Hal& hal) override {
    Render(hal);
    faded_t.push_back(t_s);
  }
  void PauseForces(haptics::Hal& hal) override {
    log_.push_back(name_ + " paused");
    scale_at_pause = hal.force_scale();
    field_at_pause = hal.Setpoint(Side::kRight).field;
    paused = true;
  }
  void ResumeForces(haptics::Hal&, const interfaces::InputState& now) override {
    log_.push_back(name_ + " resumed");
    presses_at_resume = now.presses_up;
    paused = false;
  }

  std::vector<double> driven_t;  ///< ticks it took the person's input
  std::vector<double> faded_t;   ///< ticks it rendered without a command (the fade)
  bool paused = false;
  double scale_at_pause = -1.0;
  haptics::ForceField field_at_pause;
  uint32_t presses_at_resume = 0;
  uint32_t presses_seen = 0;

 private:
  void Render(haptics::Hal& hal) {
    REQUIRE_FALSE(paused);  // a paused interface never renders
    haptics::ForceField field;
    field.enabled = true;
    field.stiffness = stiffness_;
    hal.SetField(Side::kRight, field);
  }
  std::string name_;
  double stiffness_;
  std::vector<std::string>& log_;
};

/// The hand 5 cm from neutral: the force the servo loop would render now, N.
double ForceNow(const haptics::Hal& hal) {
  const haptics::ForceField field = hal.Setpoint(Side::kRight).field;
  if (!field.enabled) return 0.0;
  const haptics::Vec3d f = haptics::EvaluateForceField(field, {0.05, 0.0, 0.0}, {0.0, 0.0, 0.0});
  return std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
}

constexpr double kTick_s = 0.01;  // the session's 100 Hz
constexpr double kRamp_s = 0.3;   // the run's switch_ramp_s

/// The session's tick as the fleet runs it: the handover's step, the live
/// vehicle driven with the person's input, the ramp's scale settled.
/// Returns the vehicle driven (-1: none).
int SessionTick(InterfaceHandover& handover, std::vector<FakeSide*> sides, double t,
                haptics::Hal& hal, const interfaces::InputState& input) {
  const int live = handover.Tick(t, hal, input);
  if (live >= 0) sides[static_cast<size_t>(live)]->Command(t, hal, input);
  handover.Settle(t, hal, false);
  return live;
}

}  // namespace

TEST_CASE(
    "a turn to another vehicle fades the forces out and in through the force scale, never stepping "
    "them, and "
    "pauses the interface left at zero") {
  haptics::Hal hal;
  std::vector<std::string> log;
  FakeSide a("a", 200.0, log), b("b", 400.0, log);  // 10 N and 20 N at 5 cm
  InterfaceHandover handover({&a, &b}, kRamp_s);
  handover.PauseAll(hal);
  CHECK(a.paused);
  CHECK(b.paused);
  log.clear();

  interfaces::InputState input;
  // The first vehicle: live at once (nothing was rendered before).
  handover.TurnTo(0, 0.0, hal);
  int tick = 0;
  const auto t_of = [](int k) { return k * kTick_s; };
  for (; t_of(tick) < 1.0 - 1e-9; ++tick) {
    input.presses_up = static_cast<uint32_t>(tick);  // the person keeps pressing
    CHECK(SessionTick(handover, {&a, &b}, t_of(tick), hal, input) == 0);
  }
  CHECK(log == std::vector<std::string>{"a resumed"});
  CHECK(ForceNow(hal) == Approx(10.0));
  log.clear();

  // The turn to b; every tick's force, from the one before the turn on.
  handover.TurnTo(1, t_of(tick), hal);
  std::vector<double> forces{ForceNow(hal)};
  std::vector<int> driven;
  for (; t_of(tick) < 2.0 - 1e-9; ++tick) {
    input.presses_up = static_cast<uint32_t>(tick);
    driven.push_back(SessionTick(handover, {&a, &b}, t_of(tick), hal, input));
    forces.push_back(ForceNow(hal));
  }

  // The force never moves by more than the ramp's step (a tick's share of
  // the strongest interface's force) from one tick to the next.
  const double step_N = kTick_s / kRamp_s * 20.0;
  double largest_N = 0.0;
  for (size_t k = 1; k < forces.size(); ++k)
    largest_N = std::max(largest_N, std::abs(forces[k] - forces[k - 1]));
  CHECK(largest_N <= step_N + 1e-9);
  CHECK(*std::min_element(forces.begin(), forces.end()) ==
        Approx(0.0).margin(1e-9));       // it did go through zero
  CHECK(forces.back() == Approx(20.0));  // b's own force, in full
  CHECK(hal.force_scale() == 1.0);
  CHECK_FALSE(handover.swapping());

  // a was paused once, at zero force scale, its field cleared; then b resumed.
  CHECK(log == std::vector<std::string>{"a paused", "b resumed"});
  CHECK(a.scale_at_pause == 0.0);
  CHECK_FALSE(a.field_at_pause.enabled);
  CHECK(handover.live() == 1);
  CHECK(handover.swaps() == 1);
  // a rendered (without a command) only while its forces faded: after the turn, before the pause.
  REQUIRE_FALSE(a.faded_t.empty());
  CHECK(a.faded_t.front() >= 1.0 - 1e-9);
  CHECK(a.faded_t.back() < 1.0 + kRamp_s);

  // The person's input went to a before the turn and to b after the fade,
  // never to both and never to a after the turn; b saw the presses made
  // before it as made (its resume marks them seen).
  CHECK(a.driven_t.back() < 1.0);
  REQUIRE_FALSE(b.driven_t.empty());
  CHECK(b.driven_t.front() >= a.faded_t.back());
  for (size_t k = 0; k < driven.size(); ++k) CHECK(driven[k] != 0);
  CHECK(std::count(driven.begin(), driven.end(), -1) == static_cast<long>(a.faded_t.size()));
  CHECK(b.presses_at_resume == static_cast<uint32_t>(std::lround(b.driven_t.front() / kTick_s)));
}

TEST_CASE(
    "a turn while the forces still ramp up fades them from where they are; a turn back before the "
    "swap pauses "
    "nothing") {
  haptics::Hal hal;
  std::vector<std::string> log;
  FakeSide a("a", 200.0, log), b("b", 200.0, log);
  InterfaceHandover handover({&a, &b}, kRamp_s);
  handover.PauseAll(hal);
  interfaces::InputState input;
  handover.TurnTo(0, 0.0, hal);
  double t = 0.0;
  SessionTick(handover, {&a, &b}, t, hal, input);
  handover.TurnTo(1, t += kTick_s, hal);
  // Into b's ramp up, part way: then back to a.
  while (!(handover.live() == 1 && hal.force_scale() > 0.4))
    SessionTick(handover, {&a, &b}, t += kTick_s, hal, input);
  const double before = hal.force_scale();
  handover.TurnTo(0, t += kTick_s, hal);
  SessionTick(handover, {&a, &b}, t, hal, input);
  CHECK(std::abs(hal.force_scale() - before) <= kTick_s / kRamp_s + 1e-9);
  // Before b's fade is down, a is asked for again... and b once more: the
  // swap at zero goes to the newest choice, so b stays live, unpaused.
  SessionTick(handover, {&a, &b}, t += kTick_s, hal, input);
  handover.TurnTo(1, t, hal);
  log.clear();
  while (handover.swapping()) SessionTick(handover, {&a, &b}, t += kTick_s, hal, input);
  CHECK(log.empty());
  CHECK(handover.live() == 1);
  CHECK(hal.force_scale() == 1.0);
}

TEST_CASE(
    "the vehicle's own interface switch ramping meanwhile: the lower of the two scales, still no "
    "step") {
  haptics::Hal hal;
  std::vector<std::string> log;
  FakeSide a("a", 200.0, log), b("b", 200.0, log);
  InterfaceHandover handover({&a, &b}, kRamp_s);
  handover.PauseAll(hal);
  interfaces::InputState input;
  handover.TurnTo(0, 0.0, hal);
  double t = 0.0;
  SessionTick(handover, {&a, &b}, t, hal, input);
  handover.TurnTo(1, t += kTick_s, hal);
  while (handover.fading_out()) SessionTick(handover, {&a, &b}, t += kTick_s, hal, input);
  // b's own switch (F1-F6, InterfaceSet) ramps its scale down from the
  // swap on: it sets the scale in its Update, the handover's up ramp after it.
  double previous = hal.force_scale();
  const double own_start = t;
  while (handover.swapping()) {
    t += kTick_s;
    handover.Tick(t, hal, input);
    hal.SetForceScale(std::max(0.0, 1.0 - (t - own_start) / kRamp_s));
    handover.Settle(t, hal, true);
    CHECK(std::abs(hal.force_scale() - previous) <= kTick_s / kRamp_s + 1e-9);
    CHECK(hal.force_scale() <= std::max(0.0, 1.0 - (t - own_start) / kRamp_s) + 1e-12);
    previous = hal.force_scale();
  }
}

TEST_CASE(
    "without a ramp (the automatic operator) the interfaces swap at once and the force scale is "
    "left alone") {
  haptics::Hal hal;
  std::vector<std::string> log;
  FakeSide a("a", 200.0, log), b("b", 400.0, log);
  InterfaceHandover handover({&a, &b}, 0.0);
  handover.PauseAll(hal);
  log.clear();
  interfaces::InputState input;
  handover.TurnTo(0, 0.0, hal);
  CHECK(SessionTick(handover, {&a, &b}, 0.0, hal, input) == 0);
  handover.TurnTo(1, 0.01, hal);
  CHECK(SessionTick(handover, {&a, &b}, 0.01, hal, input) == 1);
  CHECK(log == std::vector<std::string>{"a resumed", "a paused", "b resumed"});
  CHECK(a.faded_t.empty());
  CHECK(hal.force_scale() == 1.0);
}
