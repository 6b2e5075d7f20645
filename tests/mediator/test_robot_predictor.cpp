// The predictive display's robot model against the simulated robot itself:
// commands sent through a link of known delay, states coming back as late,
// and the predictor saying where the robot is now.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <deque>
#include <vector>

#include "haptel/mediator/robot_predictor.hpp"
#include "haptel/vehicles/sim_robot.hpp"

using namespace haptel;
using namespace haptel::mediator;

namespace {

/// Open ground: a 50 m square loop 20 m wide, its one gate far away.
TrackConfig OpenGround() {
  TrackConfig t;
  t.name = "open";
  t.centerline = {{0, 0}, {50, 0}, {50, 50}, {0, 50}};
  t.corridor_width = 20.0;
  t.gates = {{100.0, 0.6}};
  return t;
}

/// The simulated robot at the end of a link `delay_s` long each way: it
/// obeys the commands that have reached it, and its states reach the
/// operator as late. Everything on one clock stepped by `dt`.
struct DelayedLink {
  const Track track{OpenGround()};
  VehicleConfig vehicle;
  vehicles::SimRobot robot{track, vehicle};
  double delay_s;
  double dt = 0.01;
  double t = 0.0;
  struct Sent {
    double t;
    double left, right;
  };
  std::deque<Sent> in_flight;
  std::deque<RobotStateSample> states_in_flight;

  double measured_rtt_s;  ///< the round trip the predictor is told (a faulty measurement: not 2
                          ///< delay_s)

  explicit DelayedLink(double delay) : delay_s(delay), measured_rtt_s(2.0 * delay) {
    robot.Place(25.0, 0.0, 0.0);
  }
  /// A robot that drives as `drive` says, whatever its file says.
  DelayedLink(double delay, const TreadDriveConfig& drive)
      : vehicle(WithDrive(drive)), delay_s(delay), measured_rtt_s(2.0 * delay) {
    robot.Place(25.0, 0.0, 0.0);
  }
  static VehicleConfig WithDrive(const TreadDriveConfig& drive) {
    VehicleConfig v;
    v.drive = drive;
    return v;
  }

  /// One step: the operator sends (left, right); commands that arrived are
  /// applied; the robot moves; its state leaves now and arrives delay_s later.
  /// Calls on_state for each state arriving at the operator.
  template <typename OnState>
  void Step(RobotPredictor& predictor, double left, double right, OnState on_state) {
    predictor.OnCommand(t, left, right);
    in_flight.push_back({t, left, right});
    while (!in_flight.empty() && in_flight.front().t + delay_s <= t + 1e-9) {
      robot.SetMotors(
          {models::QuantiseCommand(in_flight.front().left, vehicle.drive.speed_levels),
           models::QuantiseCommand(in_flight.front().right, vehicle.drive.speed_levels)});
      in_flight.pop_front();
    }
    robot.Update(dt);
    t += dt;
    const vehicles::AdapterState s = robot.State();
    states_in_flight.push_back(
        {t + delay_s, s.x, s.y, s.heading, s.speed, s.yaw_rate, s.applied.left, s.applied.right});
    while (!states_in_flight.empty() && states_in_flight.front().received_s <= t + 1e-9) {
      predictor.OnRoundTrip(measured_rtt_s);
      on_state(states_in_flight.front());
      states_in_flight.pop_front();
    }
  }
};

/// A drive with turns both ways, stops and reversing: the commands a person gives.
std::pair<double, double> Commands(double t) {
  const double turn = 0.5 * std::sin(0.9 * t);
  const double speed = t < 4.0 ? 0.8 : (t < 5.0 ? 0.0 : (t < 6.0 ? -0.5 : 0.6));
  return {speed - turn, speed + turn};
}

double Percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(p * static_cast<double>(v.size() - 1))];
}

}  // namespace

TEST_CASE("With the delay known exactly, the predictor says where the simulated robot is now") {
  for (const double delay_s : {0.1, 0.4}) {
    CAPTURE(delay_s);
    DelayedLink link(delay_s);
    RobotPredictor predictor(link.vehicle.drive, 0.2, link.dt);
    double worst_now_m = 0.0;
    double worst_delayed_m = 0.0;
    RobotStateSample newest{};
    bool have_state = false;
    for (int i = 0; i < 900; ++i) {
      const auto [left, right] = Commands(link.t);
      link.Step(predictor, left, right, [&](const RobotStateSample& s) {
        predictor.OnState(s);
        newest = s;
        have_state = true;
      });
      if (!have_state || link.t < 1.0) continue;
      const vehicles::AdapterState truth = link.robot.State();
      const PredictedPose now = predictor.PoseAt(link.t);
      worst_now_m = std::max(worst_now_m, std::hypot(now.x - truth.x, now.y - truth.y));
      worst_delayed_m =
          std::max(worst_delayed_m, std::hypot(newest.x - truth.x, newest.y - truth.y));
    }
    CHECK(predictor.one_way_delay_s() == Approx(delay_s));
    // The model is the robot's own drive: what is left is the integration's rounding.
    CHECK(worst_now_m < 1e-3);
    CHECK(Percentile(predictor.errors_m(), 0.95) < 1e-3);
    CHECK(predictor.errors_m().size() > 700);
    // What the delayed state shows is a delay behind (the robot moves 0.24 m/s).
    CHECK(worst_delayed_m > delay_s * 0.2);
  }
}

TEST_CASE("A wrong delay or a wrong model shows in the prediction error") {
  auto p95 = [](const TreadDriveConfig& model, double measured_rtt_s) {
    DelayedLink link(0.2);
    link.measured_rtt_s = measured_rtt_s;
    RobotPredictor predictor(model, 0.2, link.dt);
    for (int i = 0; i < 600; ++i) {
      const auto [left, right] = Commands(link.t);
      link.Step(predictor, left, right, [&](const RobotStateSample& s) { predictor.OnState(s); });
    }
    return Percentile(predictor.errors_m(), 0.95);
  };
  const VehicleConfig vehicle;
  const double fitted = p95(vehicle.drive, 0.4);
  TreadDriveConfig even = vehicle.drive;
  even.right_gain = 1.0;  // the file says the right tread is 5 % weaker; this model forgets
  const double misfitted = p95(even, 0.4);
  const double wrong_delay = p95(vehicle.drive, 0.2);  // told half the round trip
  CAPTURE(fitted, misfitted, wrong_delay);
  CHECK(fitted < 1e-4);
  CHECK(misfitted > 10.0 * fitted);
  CHECK(misfitted > 5e-4);
  CHECK(wrong_delay > 5e-3);  // a tenth of a second at up to 0.24 m/s: millimetres to centimetres
}

TEST_CASE("A robot that is not its file: the learnt model predicts it, the file's does not") {
  // Weaker left tread, stronger right, and a skid that turns it as a 1.4×
  // wider one would (the simulated robot's own model, other numbers).
  const VehicleConfig file;
  TreadDriveConfig truth = file.drive;
  truth.left_gain = 0.9;
  truth.right_gain = 1.05;
  truth.track_width = 1.4 * file.drive.track_width;
  auto late_p95 = [&](PredictionModel model, RobotPredictor* out = nullptr) {
    DelayedLink link(0.2, truth);
    RobotPredictor predictor(file.drive, 0.2, link.dt, model);
    for (int i = 0; i < 1200; ++i) {
      const auto [left, right] = Commands(link.t);
      link.Step(predictor, left, right, [&](const RobotStateSample& s) { predictor.OnState(s); });
    }
    if (out != nullptr) *out = predictor;
    // The last 6 s: long after the estimate is known.
    const std::vector<double>& e = predictor.errors_m();
    return Percentile(std::vector<double>(e.end() - 600, e.end()), 0.95);
  };
  RobotPredictor learnt(file.drive);
  const double learning = late_p95(PredictionModel::kLearn, &learnt);
  const double nominal = late_p95(PredictionModel::kNominal);
  CAPTURE(learning, nominal);
  // A delay's extrapolation (0.2 s) with the file's numbers: millimetres;
  // with the learnt ones, the integration's rounding.
  CHECK(nominal > 1e-3);
  CHECK(learning < 0.01 * nominal);
  REQUIRE(learnt.estimator().width_known());
  CHECK(learnt.gains_known_s() < 3.0);
  CHECK(learnt.drive().left_gain == Approx(0.9).epsilon(0.01));
  CHECK(learnt.drive().right_gain == Approx(1.05).epsilon(0.01));
  CHECK(learnt.drive().track_width == Approx(truth.track_width).epsilon(0.01));
  // What the operator was shown, one pose a state.
  CHECK(learnt.shown().size() > 1000);
}

TEST_CASE("The path ahead runs on from now with the commands in flight, then the one being given") {
  DelayedLink link(0.2);
  RobotPredictor predictor(link.vehicle.drive, 0.2, link.dt);
  for (int i = 0; i < 200; ++i) {  // 2 s standing still
    link.Step(predictor, 0.0, 0.0, [&](const RobotStateSample& s) { predictor.OnState(s); });
  }
  std::vector<PredictedPose> path;
  predictor.PathAhead(link.t, 1.0, 1.0, 1.0, path, 0.1);
  REQUIRE(path.size() == 11);
  CHECK(path.front().t_s == Approx(link.t));
  CHECK(path.front().x == Approx(25.0).margin(1e-9));  // the command needs 0.2 s to get there
  CHECK(path[2].x == Approx(25.0).margin(1e-9));
  // Then it drives off, nearly straight (the right tread's 5 % less turns it right).
  CHECK(path.back().x > 25.0 + 0.15);
  CHECK(path.back().y < 0.0);
  CHECK(path.back().y > -0.05);
  for (size_t i = 1; i < path.size(); ++i) CHECK(path[i].x >= path[i - 1].x);
}

TEST_CASE("When commands stop, the predicted robot stops as its watchdog stops it") {
  DelayedLink link(0.1);
  RobotPredictor predictor(link.vehicle.drive, 0.2, link.dt);
  for (int i = 0; i < 200; ++i) {
    link.Step(predictor, 1.0, 1.0, [&](const RobotStateSample& s) { predictor.OnState(s); });
  }
  const double t_last = link.t;
  // No command after t_last: the last reaches the robot at t_last + 0.1 and
  // the watchdog stops it 0.2 s later; it coasts to rest on the motor lag.
  const PredictedPose at_stop = predictor.PoseAt(t_last + 0.3);
  const PredictedPose later = predictor.PoseAt(t_last + 2.0);
  const PredictedPose much_later = predictor.PoseAt(t_last + 5.0);
  CHECK(later.x - at_stop.x < 0.3 * 0.08 * 1.5);  // at most about one time constant at top speed
  CHECK(much_later.x == Approx(later.x).margin(1e-6));
}

TEST_CASE("The delay estimate follows a step in the round trip and ignores a single late packet") {
  DelayEstimate estimate;
  CHECK(estimate.one_way_s() == 0.0);
  for (int i = 0; i < 30; ++i) estimate.AddRoundTrip(0.1);
  CHECK(estimate.one_way_s() == Approx(0.05));
  estimate.AddRoundTrip(3.0);  // one packet held up
  CHECK(estimate.one_way_s() == Approx(0.05));
  for (int i = 0; i < 6; ++i) estimate.AddRoundTrip(0.4);
  CHECK(estimate.one_way_s() == Approx(0.05));  // not yet half the window
  estimate.AddRoundTrip(0.4);
  CHECK(estimate.one_way_s() == Approx(0.2));  // the link changed: followed within 7 states
  estimate.AddRoundTrip(std::nan(""));
  estimate.AddRoundTrip(-1.0);
  CHECK(estimate.one_way_s() == Approx(0.2));
}

TEST_CASE("a stamped state is dated by its stamp on the operator's clock, a late one too") {
  // The vehicle's clock 1000 s ahead of the operator's; states cross in
  // 0.2 s, one of them 0.1 s late (a loaded host), commands likewise.
  for (const bool stamped : {true, false}) {
    RobotPredictor predictor(VehicleConfig{}.drive);
    for (int i = 0; i < 5; ++i) predictor.OnRoundTrip(0.4);
    for (int i = 1; i <= 20; ++i) {
      const double sampled = 0.02 * i;
      const double late = i == 15 ? 0.1 : 0.0;
      RobotStateSample s{sampled + 0.2 + late, 0.01 * i, 0.0, 0.0, 0.5, 0.0, 4, 4};
      s.stamp_s = stamped ? 1000.0 + sampled : 0.0;
      predictor.OnState(s);
      // When the predictor takes this state to have been sampled.
      const double dated = predictor.located().back().t_s;
      CHECK(dated == Approx(stamped ? sampled : sampled + late).margin(1e-9));
    }
  }
}

TEST_CASE("a state sampled before the newest does not take the prediction back to it") {
  // States cross in 0.1 s; one arrives sampled 10 ms before the one ahead of
  // it (a vehicle's state jitter) and 5 cm off the line (its odometry's
  // noise). The model runs on from the newest sampled state, not the last
  // arrived: what is shown as now does not move.
  RobotPredictor predictor(VehicleConfig{}.drive);
  for (int i = 0; i < 5; ++i) predictor.OnRoundTrip(0.2);
  const auto state = [](double sampled, double late, double y) {
    RobotStateSample s{sampled + 0.1 + late, 0.5 * sampled, y, 0.0, 0.5, 0.0, 4, 4};
    s.stamp_s = 1000.0 + sampled;
    return s;
  };
  for (int i = 1; i <= 10; ++i) predictor.OnState(state(0.02 * i, 0.0, 0.0));
  const PredictedPose before = predictor.PoseAt(0.35);
  predictor.OnState(state(0.19, 0.02, 0.05));
  const PredictedPose after = predictor.PoseAt(0.35);
  CHECK(after.x == before.x);
  CHECK(after.y == before.y);
  CHECK(after.heading == before.heading);
}
