// The lap judged again from a simulated vehicle's truth record: the live lap
// is judged from the odometry the vehicle reports, which drifts; where the
// truth is known, the run also says which gates the vehicle truly passed.
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <string>

#include "haptel/config/truth_format.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/mediator/lap_timer.hpp"
#include "haptel/mediator/prediction_score.hpp"
#include "haptel/record/truth_record.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::mediator;

namespace {

const Track& ShortTrack() {
  static const Track track(LoadTrack("config/tracks/test-short.yaml"));
  return track;
}

/// Where the vehicle is at arc length `s`, `offset` m left of the centre line.
Vec2 Beside(const Track& track, double s, double offset) {
  const Vec2 tangent = track.TangentAt(s);
  return track.PointAt(s) + Vec2(-tangent.y(), tangent.x()) * offset;
}

}  // namespace

TEST_CASE("the truth judges the lap again: a gate the drifting odometry passed is truly missed") {
  const Track& track = ShortTrack();
  const double gate2 = track.config().gates[1].along;
  // The odometry follows the centre line at 0.25 m/s; the truth drifts to
  // the right from 0.5 m before gate 2, 0.25 m off at it (outside its posts,
  // 0.17 m from its centre, but inside the corridor), and stays there.
  const auto drift = [&](double s) {
    return -0.25 * std::clamp((s - (gate2 - 0.5)) / 0.5, 0.0, 1.0);
  };
  const int64_t started_ns = 1'000'000'000'000;
  const double speed = 0.25, dt = 0.02;
  const double from = -track.config().start_behind, to = track.length() + 0.2;

  LapTimer live(track);
  const auto file = test::ScratchDir("truth-lap") / "truth.csv";
  {
    DrawnReality drawn;
    drawn.name = "drifting";
    drawn.seed = 4;
    std::ofstream out(file);
    out << TruthHeaderText(drawn);
    double t = 0.0;
    for (double s = from; s <= to; s += speed * dt, t += dt) {
      live.Update(t, Beside(track, s, 0.0));
      const Vec2 p = Beside(track, s, drift(s));
      char line[256];
      const size_t n = FormatTruthRow({started_ns + static_cast<int64_t>(std::llround(t * 1e9)),
                                       p.x(), p.y(), 0.0, 0.0, speed, 0.0},
                                      line, sizeof line);
      REQUIRE(n > 0);
      out.write(line, static_cast<std::streamsize>(n));
    }
  }
  SessionResult result;
  result.started_ns = started_ns;
  result.record.splits = live.splits();
  REQUIRE(live.completed());
  REQUIRE(live.gates_passed() == 2);  // the odometry's lap: clean

  JudgeLapOnTruth(record::TruthRecord::Load(file), track, result);
  const record::TruthLap& truth = result.record.truth_lap;
  REQUIRE(truth.judged);
  CHECK(truth.completed);        // the start line spans the corridor
  CHECK_FALSE(truth.projected);  // the truth crossed the finish itself
  CHECK(truth.gates_passed == 1);
  CHECK(truth.gates_missed == 1);
  REQUIRE(truth.splits.size() == 2);
  CHECK(truth.splits[0].passed);
  CHECK_FALSE(truth.splits[1].passed);
  // Drifting sideways only, the truth crossed each line when the odometry did.
  CHECK(truth.lap_time_s == Approx(live.lap_time_s()).margin(2 * dt));
  const std::vector<std::string> lines = TruthLapDisagreements(result.record);
  REQUIRE(lines.size() == 1);
  CHECK(lines[0] == "gate 2: the odometry passed it, the vehicle truly missed it");
}

TEST_CASE("without truth rows the lap stays unjudged and nothing disagrees") {
  const auto file = test::ScratchDir("truth-lap-empty") / "truth.csv";
  DrawnReality drawn;
  drawn.name = "none";
  std::ofstream(file) << TruthHeaderText(drawn);
  SessionResult result;
  result.record.splits = {{0, true, 1.0}, {1, true, 5.0}};
  JudgeLapOnTruth(record::TruthRecord::Load(file), ShortTrack(), result);
  CHECK_FALSE(result.record.truth_lap.judged);
  CHECK_FALSE(result.record.truth_lap.projected);
  CHECK(std::isnan(result.record.truth_lap.lap_time_s));
  CHECK(TruthLapDisagreements(result.record).empty());
}

TEST_CASE(
    "the run ends as the odometry crosses the finish: a robot truly short of it is projected") {
  const Track& track = ShortTrack();
  // The odometry runs 0.1 m ahead of the truth along the centre line at
  // 0.25 m/s; the run (and the truth record) ends at the odometry's finish.
  const int64_t started_ns = 2'000'000'000'000;
  const double speed = 0.25, dt = 0.02, lead = 0.1;
  LapTimer live(track);
  const auto file = test::ScratchDir("truth-lap-projected") / "truth.csv";
  {
    DrawnReality drawn;
    drawn.name = "ahead";
    std::ofstream out(file);
    out << TruthHeaderText(drawn);
    double t = 0.0;
    for (double s = -track.config().start_behind; !live.completed(); s += speed * dt, t += dt) {
      live.Update(t, Beside(track, s + lead, 0.0));
      const Vec2 p = Beside(track, s, 0.0);
      const Vec2 tangent = track.TangentAt(s);
      char line[256];
      const size_t n =
          FormatTruthRow({started_ns + static_cast<int64_t>(std::llround(t * 1e9)), p.x(), p.y(),
                          0.0, std::atan2(tangent.y(), tangent.x()), speed, 0.0},
                         line, sizeof line);
      REQUIRE(n > 0);
      out.write(line, static_cast<std::streamsize>(n));
    }
  }
  SessionResult result;
  result.started_ns = started_ns;
  result.record.completed = true;
  result.record.approach_s = live.start_t_s();
  result.record.lap_time_s = live.lap_time_s();
  result.record.splits = live.splits();
  JudgeLapOnTruth(record::TruthRecord::Load(file), track, result);
  const record::TruthLap& truth = result.record.truth_lap;
  REQUIRE(truth.judged);
  CHECK(truth.completed);
  CHECK(truth.projected);  // an estimate, labelled as one
  CHECK(truth.gates_passed == 2);
  // Lagging by the same 0.1 m at the start and the finish: the same lap.
  CHECK(truth.lap_time_s == Approx(live.lap_time_s()).margin(0.05));
}
