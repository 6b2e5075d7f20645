// The predictor against a vehicle that is not its file, in simulated time
// (`haptel run --simulated-time`, every part in this process): the operator
// side reads nothing of the vehicle's truth. What the predictor consumed is
// exactly what crossed the link (the states the vehicle published, the
// commands it received); the reality shows only in the truth record, read
// after the run to score the prediction; and what the predictor learnt of
// the vehicle it learnt from those samples.
#include <atomic>
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "haptel/app/in_process_robot.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/mediator/in_process_vehicle.hpp"
#include "haptel/mediator/run_setup.hpp"
#include "haptel/record/truth_record.hpp"
#include "test_env.hpp"

using namespace haptel;

namespace {

/// The in-process robot, with every state it publishes and every command
/// that reaches it kept: the link's samples.
class Tap final : public mediator::InProcessRobot {
 public:
  Tap(std::unique_ptr<mediator::InProcessRobot> robot, std::vector<msg::VehicleState>& published,
      std::vector<msg::TreadCommand>& received)
      : robot_(std::move(robot)), published_(published), received_(received) {}
  double control_rate_hz() const override { return robot_->control_rate_hz(); }
  void OnCommand(const msg::TreadCommand& command, int64_t now_ns) override {
    received_.push_back(command);
    robot_->OnCommand(command, now_ns);
  }
  const msg::VehicleState* Tick(int64_t now_ns) override {
    const msg::VehicleState* state = robot_->Tick(now_ns);
    if (state != nullptr) published_.push_back(*state);
    return state;
  }
  void MakeSafe() override { robot_->MakeSafe(); }

 private:
  std::unique_ptr<mediator::InProcessRobot> robot_;
  std::vector<msg::VehicleState>& published_;
  std::vector<msg::TreadCommand>& received_;
};

}  // namespace

TEST_CASE("The operator side reads nothing of the truth: the predictor's inputs are the link's",
          "[simulated-time]") {
  const auto dir = test::ScratchDir("prediction-truth");
  // A reality only the truth record reveals: the robot turns as one 1.5×
  // wider, its right tread is 10 % weaker, and its clock is 40 s ahead.
  const auto reality = dir / "hidden.yaml";
  std::ofstream(reality) << "name: hidden\nseed: 3\nrobot:\n"
                            "  track_width_factor: {mean: 1.5, sd: 0}\n"
                            "  tread_asymmetry: {mean: 0.1, sd: 0}\n"
                            "  odometry: true\n"
                            "clock:\n  offset_s: {mean: 40.0, sd: 0}\n";
  const auto truth_file = dir / "truth.csv";
  std::vector<std::string> words = {"run",
                                    "--track",
                                    "config/tracks/test-short.yaml",
                                    "--view",
                                    "none",
                                    "--quiet",
                                    "--database",
                                    (dir / "runs.db").string(),
                                    "--interface",
                                    "gesture",
                                    "--simulated-time",
                                    "--link-fault",
                                    "delay=200ms",
                                    "--predict",
                                    "learn",
                                    "--reality",
                                    reality.string(),
                                    "--truth",
                                    truth_file.string()};
  std::vector<const char*> argv;
  for (const std::string& w : words) argv.push_back(w.c_str());
  mediator::SessionSetup setup = mediator::RunSetupFromArgs(
      mediator::ParseRunArgs(static_cast<int>(argv.size()), argv.data()));
  setup.keep_predictor_inputs = true;

  std::vector<msg::VehicleState> published;
  std::vector<msg::TreadCommand> received;
  app::RegisterInProcessRobot();
  const mediator::InProcessRobotFactory robot = mediator::GetInProcessRobotFactory();
  mediator::SetInProcessRobotFactory([&](const VehicleConfig& v, const Track& t) {
    return std::make_unique<Tap>(robot(v, t), published, received);
  });
  record::Recorder recorder(setup.run.database);
  const std::atomic<bool> interrupted{false};
  const mediator::RecordedRun run = mediator::RunAndRecord(setup, recorder, interrupted);
  mediator::SetInProcessRobotFactory(robot);
  REQUIRE(run.result.outcome == mediator::Outcome::kCompleted);

  // Every state the predictor took is one the vehicle published, in order
  // and unchanged (as the link's floats carry it); none other.
  const mediator::RobotPredictorInputs& in = run.result.predictor_inputs;
  REQUIRE(in.states.size() > 500);
  size_t k = 0;
  for (const mediator::RobotStateSample& s : in.states) {
    while (k < published.size() && published[k].stamp_ns() * 1e-9 != s.stamp_s) ++k;
    REQUIRE(k < published.size());
    const msg::VehicleState& m = published[k];
    CHECK(s.x == m.x());
    CHECK(s.y == m.y());
    CHECK(s.heading == m.heading());
    CHECK(s.speed == m.speed());
    CHECK(s.yaw_rate == m.yaw_rate());
    CHECK(s.applied_left == m.motor_left_level());
    CHECK(s.applied_right == m.motor_right_level());
    // The range scan the localiser corrects the odometry with, too.
    REQUIRE(s.ranges.count == static_cast<int>(m.ranges().size()));
    CHECK(s.ranges.range_max == m.range_max());
    for (int i = 0; i < s.ranges.count; ++i)
      CHECK(s.ranges.ranges[static_cast<size_t>(i)] == m.ranges()[static_cast<size_t>(i)]);
  }
  CHECK(in.states.back().ranges.count > 0);
  // What is still on its way at the end is all that is missing.
  CHECK(in.states.size() + 20 >= published.size());
  // Every command the predictor replays is one the vehicle was sent, in
  // order; the vehicle got one more, the stop the run ends with.
  REQUIRE(received.size() > 300);
  REQUIRE(in.commands.size() + 1 >= received.size());
  for (size_t i = 0; i + 1 < received.size(); ++i) {
    CHECK(static_cast<float>(in.commands[i].left) == received[i].left());
    CHECK(static_cast<float>(in.commands[i].right) == received[i].right());
  }
  // Its round trips are the states' echoes (0.4 s: no shared clock needed).
  REQUIRE(!in.round_trips_s.empty());
  for (const double rtt : in.round_trips_s) CHECK(rtt == Approx(0.4).margin(0.03));
  // The states carry the vehicle's clock, 40 s off the operator's: the
  // predictor dates them by their arrival, never by a clock it cannot know.
  const double start_s = NsToS(run.result.started_ns);
  CHECK(in.states.back().stamp_s - (start_s + in.states.back().received_s) ==
        Approx(40.0 - 0.2).margin(0.05));

  // The reality is in the truth record, read after the run only: scored
  // there, and what the predictor learnt from the samples matches it.
  const record::TruthRecord truth = record::TruthRecord::Load(truth_file);
  CHECK(truth.reality() == "hidden");
  const double width = truth.params().effective_track_width;
  CHECK(width == Approx(1.5 * setup.vehicle.drive.track_width));
  CHECK(run.result.reality == "hidden");
  const record::RunRecord& r = run.result.record;
  CHECK(r.prediction_error_m_p95 >= 0.0);
  CHECK(r.prediction_error_odometry_m_p95 >= 0.0);
  // The robot was localised on the track from those scans, and scored.
  CHECK(r.localised);
  CHECK(r.localisation_error_m_p95 >= 0.0);
  CHECK(r.odometry_error_m_p95 >= 0.0);
  bool found = false;
  for (const record::EstimatedParameter& p : r.estimated) {
    if (p.name != "effective_track_width") continue;
    found = true;
    CHECK(p.truth == Approx(width));
    CHECK(p.estimate == Approx(width).epsilon(0.05));
    CHECK(p.known_s < 8.0);  // within the first lap (14 s)
  }
  CHECK(found);
}

TEST_CASE("On harsh, what is learnt is known within the first lap and predicts better",
          "[simulated-time]") {
  // harsh's grand prix, seed 1, 400 ms each way: the nominal model's lap and
  // the learning one's (each ~1-2 s of CPU). The states jitter (one in
  // eleven is older than the one before), the motors lag 1.4× the file's,
  // the floor has patches and the battery fades.
  const auto dir = test::ScratchDir("prediction-harsh");
  app::RegisterInProcessRobot();
  const auto lap = [&](const char* model) {
    const std::string truth = (dir / (std::string(model) + ".csv")).string();
    const std::vector<std::string> words = {"run",
                                            "--track",
                                            "config/tracks/grand-prix.yaml",
                                            "--view",
                                            "none",
                                            "--quiet",
                                            "--database",
                                            (dir / "runs.db").string(),
                                            "--simulated-time",
                                            "--link-fault",
                                            "delay=400ms",
                                            "--predict",
                                            model,
                                            "--reality",
                                            "harsh",
                                            "--reality-seed",
                                            "1",
                                            "--truth",
                                            truth};
    std::vector<const char*> argv;
    for (const std::string& w : words) argv.push_back(w.c_str());
    const mediator::SessionSetup setup = mediator::RunSetupFromArgs(
        mediator::ParseRunArgs(static_cast<int>(argv.size()), argv.data()));
    record::Recorder recorder(setup.run.database);
    const std::atomic<bool> interrupted{false};
    return mediator::RunAndRecord(setup, recorder, interrupted).result;
  };
  const mediator::SessionResult nominal = lap("nominal");
  const mediator::SessionResult learn = lap("learn");
  REQUIRE(nominal.outcome == mediator::Outcome::kCompleted);
  REQUIRE(learn.outcome == mediator::Outcome::kCompleted);
  const double lap_s = learn.record.lap_time_s;
  REQUIRE(lap_s > 60.0);
  // Each estimate known within the first lap's first tenth, and near the
  // truth (the gains' truths as the battery left them at the end).
  REQUIRE(learn.record.estimated.size() == 3);
  for (const record::EstimatedParameter& p : learn.record.estimated) {
    CAPTURE(p.name, p.estimate, p.truth, p.known_s);
    CHECK(p.known_s < 0.1 * lap_s);
    CHECK(p.estimate == Approx(p.truth).epsilon(p.name == "effective_track_width" ? 0.05 : 0.03));
  }
  // The prediction against the poses it predicts (the localised states that
  // came): learning's is below the nominal model's at p50 and p95 (on this
  // seed: p50 1.6 against 13.2 mm, p95 17.8 against 28.2).
  CAPTURE(
      learn.record.prediction_error_odometry_m_p50, nominal.record.prediction_error_odometry_m_p50,
      learn.record.prediction_error_odometry_m_p95, nominal.record.prediction_error_odometry_m_p95);
  CHECK(learn.record.prediction_error_odometry_m_p50 <
        nominal.record.prediction_error_odometry_m_p50);
  CHECK(learn.record.prediction_error_odometry_m_p95 <
        nominal.record.prediction_error_odometry_m_p95);
  // Against where the robot truly was, in the map's frame: below at p50 (on
  // this seed 27 against 40 mm). Not asserted at p95: that tail is the
  // localised pose's on harsh's displaced map (since the localiser takes a
  // correction the map's own error can explain slowly, 104 against 97 mm,
  // the nominal model's lap driven on other ghosts); docs/benchmarks.md has
  // it over seeds.
  CAPTURE(learn.record.prediction_error_m_p50, nominal.record.prediction_error_m_p50,
          learn.record.prediction_error_m_p95, nominal.record.prediction_error_m_p95);
  CHECK(learn.record.prediction_error_m_p50 < nominal.record.prediction_error_m_p50);
}
