// The predictive display's blimp model against the simulated blimp itself:
// commands sent through a link of known delay, states coming back as late
// (in the link's single precision), and the predictor saying where the
// blimp is now.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <deque>
#include <random>
#include <vector>

#include "haptel/mediator/blimp_predictor.hpp"
#include "haptel/models/sim_blimp.hpp"

using namespace haptel;
using namespace haptel::mediator;

namespace {

/// Open ground: the start at the origin facing east, one gate and the
/// landing far away, one building well off to the side.
BlimpCourseConfig OpenField() {
  BlimpCourseConfig c;
  c.name = "open";
  c.start = {{0.0, 0.0}, 0.0};
  c.gates = {{"far", {400.0, 0.0, 10.0}, 0.0, 12.0, 8.0}};
  c.buildings = {{"shed", {0.0, -150.0}, {10.0, 10.0}, 5.0, 0.0}};
  c.landing = {{400.0, 200.0}, 10.0, 1.0};
  return c;
}

/// The simulated blimp at the end of a link `delay_s` long each way, as its
/// node runs it: it steps at its model's rate, applies the newest command
/// that has reached it, goes to neutral `watchdog_s` after the last, and
/// publishes a state every `state_every` steps, which reaches the operator
/// `delay_s` later. Commands leave every `send_every` steps. One clock.
struct DelayedLink {
  AirshipConfig airship;
  BlimpCourseConfig course = OpenField();
  models::SimBlimp blimp{airship, course};
  double delay_s;
  double watchdog_s = 0.2;
  double dt = airship.step_s;
  int state_every = 4;    ///< 50 Hz
  int send_every = 10;    ///< 20 Hz: the blimp gesture cockpit's rate
  bool sending = true;    ///< false: the operator's commands stop
  double measured_rtt_s;  ///< the round trip the predictor is told (a faulty measurement: not 2
                          ///< delay_s)
  /// A busy receiver: each state arrives up to this much later still (in order).
  double receipt_jitter_s = 0.0;
  /// A loaded vehicle: each command reaches the blimp up to this much later
  /// than the delay (in order).
  double command_jitter_s = 0.0;
  std::mt19937 random{7};
  double t = 0.0;
  long step = 0;
  struct Sent {
    double t;
    BlimpCommand command;
    double arrives_s;
  };
  std::deque<Sent> in_flight;
  std::deque<BlimpStateSample> states_in_flight;
  BlimpCommand applied;
  double applied_sent_s = -1.0;
  double applied_since_s = -1e9;

  explicit DelayedLink(double delay, AirshipConfig model = {})
      : airship(model), delay_s(delay), measured_rtt_s(2.0 * delay) {}

  /// One step of the vehicle; `command` is sent when due. Calls `on_state`
  /// for each state arriving at the operator.
  template <typename OnState>
  void Step(BlimpPredictor& predictor, const BlimpCommand& command, OnState on_state) {
    if (sending && step % send_every == 0) {
      predictor.OnCommand(t, command);
      double arrives_s =
          t + delay_s + std::uniform_real_distribution<double>(0.0, command_jitter_s)(random);
      if (!in_flight.empty()) arrives_s = std::max(arrives_s, in_flight.back().arrives_s);
      in_flight.push_back({t, command, arrives_s});
    }
    while (!in_flight.empty() && in_flight.front().arrives_s <= t + 1e-9) {
      applied = Clamped(in_flight.front().command);
      applied_sent_s = in_flight.front().t;
      applied_since_s = t;
      in_flight.pop_front();
    }
    const bool failsafe = t - applied_since_s > watchdog_s;
    blimp.Step(dt, failsafe ? BlimpCommand{} : applied);
    t += dt;
    ++step;
    if (step % state_every == 0) {
      BlimpStateSample s = Sample(failsafe);
      s.received_s += std::uniform_real_distribution<double>(0.0, receipt_jitter_s)(random);
      if (!states_in_flight.empty())
        s.received_s = std::max(s.received_s, states_in_flight.back().received_s);
      states_in_flight.push_back(s);
    }
    while (!states_in_flight.empty() && states_in_flight.front().received_s <= t + 1e-9) {
      predictor.OnRoundTrip(measured_rtt_s);
      on_state(states_in_flight.front());
      states_in_flight.pop_front();
    }
  }

  /// The state as the link carries it (floats), leaving now.
  BlimpStateSample Sample(bool failsafe) const {
    auto f = [](double v) { return static_cast<double>(static_cast<float>(v)); };
    BlimpStateSample s;
    s.received_s = t + delay_s;
    s.stamp_ns = static_cast<int64_t>(std::llround(t * 1e9));
    const Eigen::Vector3d p = blimp.position(), v = blimp.ground_velocity();
    s.position = {f(p.x()), f(p.y()), f(p.z())};
    s.yaw = f(blimp.yaw());
    s.pitch = f(blimp.pitch());
    s.roll = f(blimp.roll());
    s.velocity = {f(v.x()), f(v.y()), f(v.z())};
    s.applied = failsafe ? BlimpCommand{} : applied;
    s.command_sent_s = applied_sent_s;
    s.command_age_s = applied_sent_s >= 0.0 ? t - applied_since_s : -1.0;
    return s;
  }
};

/// A flight as a pilot's hands give it: a climb on the tilted helix plane,
/// cruising with the rudder thrown from side to side, the power stepping
/// and the elevator nodding, a turnabout on the tail rotor at zero power,
/// then on again, descending.
BlimpCommand Commands(double t) {
  BlimpCommand c;
  if (t < 4.0) {
    c.power = 0.5;
    c.helix = 0.7;
  } else if (t < 14.0) {
    c.power = std::fmod(t, 3.0) < 1.5 ? 0.9 : 0.4;
    c.helix = 0.15;
    c.rudder = std::sin(0.9 * (t - 4.0)) > 0.0 ? 0.7 : -0.7;
    c.elevator = 0.3 * std::sin(1.1 * t);
  } else if (t < 18.0) {
    c.tail_rotor = 0.9;
  } else {
    c.power = 0.6;
    c.helix = -0.2;
    c.rudder = -0.4;
  }
  return c;
}

double Percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(p * static_cast<double>(v.size() - 1))];
}

}  // namespace

TEST_CASE(
    "With the delay known exactly, the blimp's predictor says where the simulated blimp is now") {
  for (const double delay_s : {0.1, 0.4}) {
    CAPTURE(delay_s);
    DelayedLink link(delay_s);
    BlimpPredictor predictor(link.airship, link.course, link.watchdog_s);
    double worst_now_m = 0.0, worst_heading_rad = 0.0, worst_delayed_m = 0.0;
    BlimpStateSample newest;
    bool have_state = false;
    while (link.t < 22.0) {
      link.Step(predictor, Commands(link.t), [&](const BlimpStateSample& s) {
        predictor.OnState(s);
        newest = s;
        have_state = true;
      });
      if (!have_state || link.t < 1.0) continue;
      const BlimpPredictedPose now = predictor.PoseAt(link.t);
      worst_now_m = std::max(worst_now_m, (now.position - link.blimp.position()).norm());
      worst_heading_rad = std::max(
          worst_heading_rad, std::abs(std::remainder(now.yaw - link.blimp.yaw(), 2.0 * M_PI)));
      worst_delayed_m = std::max(worst_delayed_m, (newest.position - link.blimp.position()).norm());
    }
    CAPTURE(worst_now_m, worst_heading_rad, worst_delayed_m,
            Percentile(predictor.errors_m(), 0.95));
    CHECK(predictor.one_way_delay_s() == Approx(delay_s));
    CHECK(predictor.errors_m().size() > 1000);
    // The model is the blimp's own: what is left is the link's single
    // precision and the rates taken from two states (millimetres, where the
    // blimp flies 4-8 m/s).
    CHECK(worst_now_m < 5e-3);
    CHECK(worst_heading_rad < 1e-4);
    CHECK(Percentile(predictor.errors_m(), 0.95) < 1e-3);
    // What the delayed state shows is a delay behind (the blimp flies at 4-8 m/s).
    CHECK(worst_delayed_m > delay_s * 4.0);
  }
}

TEST_CASE("A wrong delay or a misfitted airship model shows in the blimp's prediction error") {
  auto p95 = [](const AirshipConfig& model, double measured_rtt_s) {
    DelayedLink link(0.2);
    link.measured_rtt_s = measured_rtt_s;
    BlimpPredictor predictor(model, link.course, link.watchdog_s);
    while (link.t < 22.0) {
      link.Step(predictor, Commands(link.t),
                [&](const BlimpStateSample& s) { predictor.OnState(s); });
    }
    return Percentile(predictor.errors_m(), 0.95);
  };
  const AirshipConfig airship;
  const double fitted = p95(airship, 0.4);
  AirshipConfig weak = airship;
  weak.max_thrust *= 0.8;  // the motors are a fifth weaker in this model than on the blimp
  const double misfitted = p95(weak, 0.4);
  const double short_delay = p95(airship, 0.2);  // told half the round trip
  const double long_delay = p95(airship, 0.8);   // told twice
  CAPTURE(fitted, misfitted, short_delay, long_delay);
  CHECK(fitted < 1e-3);
  CHECK(misfitted > 10.0 * fitted);
  // (Told too short a delay, the states' own echoes still time the commands
  // up to each state right: only those on their way are early.)
  CHECK(short_delay > 5.0 * fitted);
  CHECK(long_delay > 10.0 * fitted);
}

TEST_CASE("States that a busy receiver takes late do not show as the blimp's prediction error") {
  DelayedLink link(0.2);
  link.receipt_jitter_s = 0.02;
  BlimpPredictor predictor(link.airship, link.course, link.watchdog_s);
  double worst_now_m = 0.0;
  while (link.t < 22.0) {
    link.Step(predictor, Commands(link.t),
              [&](const BlimpStateSample& s) { predictor.OnState(s); });
    if (link.t > 1.0)
      worst_now_m =
          std::max(worst_now_m, (predictor.PoseAt(link.t).position - link.blimp.position()).norm());
  }
  const double p95 = Percentile(predictor.errors_m(), 0.95);
  CAPTURE(worst_now_m, p95);
  // Taken at their arrival less the delay, states up to 20 ms late at 4-8 m/s
  // would be up to 15 cm off; their stamps say when they were sampled.
  CHECK(p95 < 0.01);
  CHECK(worst_now_m < 0.03);
}

TEST_CASE(
    "Resting on the ground, the predicted blimp stays on it; given power it lifts off a delay "
    "later") {
  DelayedLink link(0.3);
  BlimpPredictor predictor(link.airship, link.course, link.watchdog_s);
  for (int i = 0; i < 400; ++i) {  // 2 s on the ground, every channel at neutral
    link.Step(predictor, BlimpCommand{}, [&](const BlimpStateSample& s) { predictor.OnState(s); });
  }
  REQUIRE(predictor.ready());
  const Eigen::Vector3d rest = link.blimp.position();
  // Heavier than air by 40 g, it would sink through a ground not modelled.
  const BlimpPredictedPose later = predictor.PoseAt(link.t + 3.0);
  CHECK(later.contact);
  CHECK((later.position - rest).norm() < 0.01);

  BlimpCommand up;
  up.power = 1.0;
  up.helix = 1.0;  // thrust straight up
  std::vector<BlimpPredictedPose> path;
  predictor.PathAhead(link.t, 3.0, up, path, 0.1);
  REQUIRE(path.size() == 31);
  CHECK(path.front().t_s == Approx(link.t));
  CHECK(path.front().position.z() == Approx(rest.z()).margin(1e-3));
  CHECK(path[3].position.z() ==
        Approx(rest.z()).margin(1e-3));              // the command needs 0.3 s to get there
  CHECK(path.back().position.z() > rest.z() + 0.5);  // then it climbs
  CHECK_FALSE(path.back().contact);
  for (size_t i = 4; i < path.size(); ++i)
    CHECK(path[i].position.z() >= path[i - 1].position.z() - 1e-6);
}

TEST_CASE("When commands stop, the predicted blimp goes to neutral as its watchdog puts it") {
  DelayedLink link(0.2);
  BlimpPredictor predictor(link.airship, link.course, link.watchdog_s);
  BlimpCommand cruise;
  cruise.power = 0.8;
  cruise.helix = 0.3;
  cruise.rudder = 0.3;
  while (link.t < 10.0)
    link.Step(predictor, cruise, [&](const BlimpStateSample& s) { predictor.OnState(s); });
  const double t_last = link.t;
  // No command after t_last: the last reaches the blimp 0.2 s later, the
  // watchdog cuts the power 0.2 s after that, and it coasts on.
  link.sending = false;
  while (link.t < t_last + 0.05)
    link.Step(predictor, cruise, [&](const BlimpStateSample& s) { predictor.OnState(s); });
  const BlimpPredictedPose coasted = predictor.PoseAt(t_last + 4.0);
  while (link.t < t_last + 4.0 - 1e-9) link.Step(predictor, cruise, [](const BlimpStateSample&) {});
  CAPTURE(coasted.position, link.blimp.position());
  CHECK((coasted.position - link.blimp.position()).norm() < 0.05);
  CHECK(link.blimp.airship().state().thrust < 0.01 * link.airship.max_thrust);
}

TEST_CASE("A steady wind the file does not know: estimated, and the learnt model flies it") {
  AirshipConfig windy;
  windy.wind.mean = {1.5, -1.0, 0.0};  // m/s; the file the predictor has says calm
  auto late_p95 = [&](PredictionModel model, Eigen::Vector2d* wind, double* known_s) {
    DelayedLink link(0.2, windy);
    BlimpPredictor predictor(AirshipConfig{}, link.course, link.watchdog_s, model);
    while (link.t < 30.0) {
      link.Step(predictor, Commands(link.t),
                [&](const BlimpStateSample& s) { predictor.OnState(s); });
    }
    if (wind != nullptr) *wind = predictor.wind();
    if (known_s != nullptr) *known_s = predictor.wind_known_s();
    CHECK(predictor.shown().size() > 1000);
    // The last 10 s.
    const std::vector<double>& e = predictor.errors_m();
    return Percentile(std::vector<double>(e.end() - 500, e.end()), 0.95);
  };
  Eigen::Vector2d wind;
  double known_s = -1.0;
  const double learning = late_p95(PredictionModel::kLearn, &wind, &known_s);
  Eigen::Vector2d wind_seen_by_nominal;
  const double nominal = late_p95(PredictionModel::kNominal, &wind_seen_by_nominal, nullptr);
  CAPTURE(learning, nominal, wind.x(), wind.y(), known_s);
  CHECK(known_s > 0.0);
  CHECK(known_s < 15.0);
  CHECK(wind.x() == Approx(1.5).margin(0.15));
  CHECK(wind.y() == Approx(-1.0).margin(0.15));
  // The estimator runs with the nominal model too (to be reported).
  CHECK((wind_seen_by_nominal - wind).norm() < 0.3);
  CHECK(nominal > 0.02);
  CHECK(learning < 0.3 * nominal);
}

TEST_CASE(
    "Commands that reach the blimp late (a loaded machine) are not taken for wind: the twin's "
    "learnt wind stays calm") {
  DelayedLink link(0.4);
  link.command_jitter_s = 0.03;
  BlimpPredictor predictor(link.airship, link.course, link.watchdog_s, PredictionModel::kLearn);
  while (link.t < 20.0) {
    link.Step(predictor, Commands(link.t),
              [&](const BlimpStateSample& s) { predictor.OnState(s); });
  }
  const Eigen::Vector2d wind = predictor.wind();
  CAPTURE(wind.x(), wind.y(), predictor.wind_known_s(), Percentile(predictor.errors_m(), 0.95));
  // Each state's echo says when its command truly arrived: the model's run
  // up to it is the blimp's own, whatever the link did. (Timed by the delay
  // instead, the first state off the ground, which says almost nothing of
  // the wind, made a jitter's few mm/s a wind of metres a second.)
  CHECK(predictor.wind_known());
  CHECK(wind.norm() < 0.05);
  // What is left is the jitter of the commands still on their way.
  CHECK(Percentile(predictor.errors_m(), 0.95) < 0.1);
}

TEST_CASE("A stamped state is dated by its stamp, the clocks' offset from the fastest trips") {
  // The vehicle's clock 1000 s ahead of the operator's; states cross in
  // 0.2 s, one of them 0.1 s late (a busy receiver). The round trips are
  // 0.4 s at their fastest, but most take 0.6 s (a jittery link): the
  // blimp's predictor took the clocks' offset less half the median round
  // trip, and dated every state 0.1 s older than it was (at 6 m/s, 60 cm).
  StampDating dating;
  const double one_way_s = 0.3;  // half the median: what an unstamped state is dated by
  CHECK(dating.SampleTime(5.0, 1004.8, one_way_s) == Approx(4.7));  // no round trip yet
  for (const double rtt : {0.6, 0.4, 0.6, 0.6, 0.6}) dating.AddRoundTrip(rtt);
  dating.AddRoundTrip(std::nan(""));  // ignored
  for (int i = 1; i <= 20; ++i) {
    const double sampled = 10.0 + 0.02 * i;
    const double late = i == 15 ? 0.1 : 0.0;
    const double dated = dating.SampleTime(sampled + 0.2 + late, 1000.0 + sampled, one_way_s);
    CHECK(dated == Approx(sampled).margin(1e-9));
  }
  CHECK(dating.SampleTime(12.0, 0.0, one_way_s) == Approx(11.7));  // unstamped
}
