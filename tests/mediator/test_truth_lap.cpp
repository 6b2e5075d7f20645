// The lap judged again from a simulated vehicle's truth record: the live lap
// is judged from the odometry the vehicle reports, which drifts; where the
// truth is known, the run also says which gates the vehicle truly passed.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <numbers>
#include <string>

#include "haptel/config/blimp_course.hpp"
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

/// Appends the truth's row `t_s` after `started_ns`: at (x, y, z), heading
/// `heading`, at `speed` along it.
void WriteTruthRow(std::ofstream& out, int64_t started_ns, double t_s, double x, double y, double z,
                   double heading, double speed) {
  char line[256];
  const size_t n = FormatTruthRow(
      {started_ns + static_cast<int64_t>(std::llround(t_s * 1e9)), x, y, z, heading, speed, 0.0},
      line, sizeof line);
  REQUIRE(n > 0);
  out.write(line, static_cast<std::streamsize>(n));
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
      WriteTruthRow(out, started_ns, t, p.x(), p.y(), 0.0, 0.0, speed);
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
      WriteTruthRow(out, started_ns, t, p.x(), p.y(), 0.0, std::atan2(tangent.y(), tangent.x()),
                    speed);
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

TEST_CASE(
    "the blimp's lap judged on its truth: through the gate, down on the circle; or beside it") {
  // The hop (gate at (35, 0, 4), 12 m wide; the circle at (95, 10), 10 m
  // across): 2 s resting on the pad at 0.8 m, up to 4 m by x = 10 (the lap
  // starts 1 m up), along y = `off` through the gate's plane at 2 m/s, to
  // the circle's centre and down onto the ground there, slowly.
  const BlimpCourseConfig course = LoadBlimpCourse("config/tracks/blimp-hop.yaml");
  const int64_t started_ns = 2'000'000'000'000;
  const auto judge = [&](double off) {
    const auto file = test::ScratchDir("truth-lap") / "blimp_truth.csv";
    {
      std::ofstream out(file);
      out << TruthHeaderText(DrawnReality{});
      const auto row = [&](double t, double x, double y, double z, double speed) {
        WriteTruthRow(out, started_ns, t, x, y, z, 0.0, speed);
      };
      const double dt = 0.02;
      double t = 0.0;
      for (; t < 2.0; t += dt) row(t, 0.0, 0.0, 0.8, 0.0);
      for (double x = 0.0; x < 95.0; x += 2.0 * dt, t += dt) {  // climb, cruise, glide
        const double y =
            x < 50.0 ? off * std::min(1.0, x / 10.0) : off + (10.0 - off) * (x - 50.0) / 45.0;
        const double z = x < 10.0 ? 0.8 + 0.32 * x : x < 50.0 ? 4.0 : 4.0 - 3.0 * (x - 50.0) / 45.0;
        row(t, x, y, z, 2.0);
      }
      for (double z = 1.0; z > 0.8; z -= 0.2 * dt, t += dt) row(t, 95.0, 10.0, z, 0.0);
      for (int i = 0; i < 50; ++i, t += dt) row(t, 95.0, 10.0, 0.8, 0.0);  // landed
    }
    SessionResult result;
    result.started_ns = started_ns;
    JudgeLapOnTruth(record::TruthRecord::Load(file), course, result);
    return result.record.truth_lap;
  };
  const record::TruthLap through = judge(0.0);
  REQUIRE(through.judged);
  CHECK(through.completed);
  CHECK(through.gates_passed == 1);
  CHECK(through.gates_missed == 0);
  // Lifted 1 m (the course's takeoff_height) at x = 3.125 m, t = 3.5625 s;
  // through the gate at x = 35, t = 19.5 s; over the centre at 1 m at
  // t = 49.5 s, resting (within kBlimpRestingM of 0.8 m) 0.75 s later.
  REQUIRE(through.splits.size() == 1);
  CHECK(through.splits[0].split_s == Approx(19.5 - 3.5625).margin(0.03));
  CHECK(through.lap_time_s == Approx(50.25 - 3.5625).margin(0.03));

  const record::TruthLap beside = judge(8.0);  // 8 m off a 12 m gate's centre
  REQUIRE(beside.judged);
  CHECK(beside.gates_passed == 0);
  CHECK(beside.gates_missed == 1);
  CHECK(beside.completed);  // the landing counts after the last gate, passed or missed
}

TEST_CASE(
    "the truth is scored in the map's frame: the layout turned and shifted as a whole does not "
    "count, a post's own error does") {
  const Track& track = ShortTrack();
  REQUIRE(!track.round_obstacles().empty());
  // As built: the whole layout turned 0.5° about (1, 2) and shifted (3, -2) cm.
  const double turn = 0.5 * std::numbers::pi / 180.0;
  const Vec2 pivot(1.0, 2.0), shift(0.03, -0.02);
  const auto built = [&](const Vec2& p) -> Vec2 {
    const Vec2 v = p - pivot;
    return pivot +
           Vec2(std::cos(turn) * v.x() - std::sin(turn) * v.y(),
                std::sin(turn) * v.x() + std::cos(turn) * v.y()) +
           shift;
  };
  DrawnReality drawn;
  drawn.name = "turned";
  for (const Segment2& w : track.walls()) drawn.true_walls.push_back({built(w.a), built(w.b)});
  for (const CircleObstacle& c : track.round_obstacles())
    drawn.true_posts.push_back({built(c.center), c.radius});

  // The fit undoes the layout's motion exactly: no local error left.
  const RigidFit2 fit = FitAsBuiltToFile(drawn, track);
  CHECK(fit.features > static_cast<int>(track.round_obstacles().size()));
  CHECK(fit.rotation_rad == Approx(-turn).margin(1e-9));
  CHECK(fit.residual_m_rms < 1e-9);
  const Vec2 far = track.PointAt(track.length() / 2);
  CHECK((fit.Apply(built(far)) - far).norm() < 1e-9);

  // The robot truly drives the as-built centre line; the ghost shows it
  // exactly where the map puts it (a perfect localiser on the file's map).
  const int64_t started_ns = 3'000'000'000'000;
  const auto file = test::ScratchDir("truth-map-frame") / "truth.csv";
  SessionResult result;
  result.started_ns = started_ns;
  {
    std::ofstream out(file);
    out << TruthHeaderText(drawn);
    double t = 0.0;
    for (double s = 0.0; s <= track.length(); s += 0.01, t += 0.04) {
      const Vec2 p = built(track.PointAt(s));
      WriteTruthRow(out, started_ns, t, p.x(), p.y(), 0.0, 0.0, 0.25);
      const Vec2 shown = track.PointAt(s);
      result.shown.push_back({t, shown.x(), shown.y(), 0.0});
    }
  }
  ScorePrediction(record::TruthRecord::Load(file), &track, result);
  const RunRecord& r = result.record;
  CHECK(r.map_fit.features == fit.features);
  CHECK(r.map_fit.rotation_deg == Approx(-0.5).margin(1e-6));
  CHECK(r.prediction_error_m_p95 < 1e-4);  // in the map's frame: the ghost was right
  // In the world's, the layout's motion: at least its shift's 3.6 cm less the turn's share.
  CHECK(r.prediction_error_world_m_p95 > 0.02);

  // One post 4 cm from where the map says: the map's own error, left by the fit.
  drawn.true_posts[0].center += Vec2(0.04, 0.0);
  const RigidFit2 local = FitAsBuiltToFile(drawn, track);
  CHECK(local.residual_m_rms > 0.005);
  CHECK(local.rotation_rad == Approx(-turn).margin(0.01));

  // No map error: no fit, the frames are one.
  CHECK(FitAsBuiltToFile(DrawnReality{}, track).features == 0);
}

TEST_CASE("the truth's lap is judged at the gates as built, and the map learnt against them") {
  // Gate 2's posts stand 8 cm to the right of where the file has them; the
  // robot truly drives the centre line, and 0.2 m right of it at gate 2:
  // outside the file's posts (0.17 m from its centre, less a post's
  // radius), between the posts as built (0.12 m from theirs).
  const Track& track = ShortTrack();
  const double gate2 = track.config().gates[1].along;
  const Vec2 moved = Beside(track, gate2, -0.08) - track.PointAt(gate2);
  DrawnReality drawn;
  drawn.name = "moved-gate";
  drawn.true_posts = track.round_obstacles();
  drawn.true_posts[2].center += moved;
  drawn.true_posts[3].center += moved;
  const auto offset = [&](double s) {
    return -0.2 * std::min(std::clamp((s - (gate2 - 0.5)) / 0.5, 0.0, 1.0),
                           std::clamp((gate2 + 0.5 - s) / 0.5, 0.0, 1.0));
  };
  const int64_t started_ns = 4'000'000'000'000;
  const auto file = test::ScratchDir("truth-gates-built") / "truth.csv";
  LapTimer at_file(track);  // the same path at the file's gates
  {
    std::ofstream out(file);
    out << TruthHeaderText(drawn);
    double t = 0.0;
    for (double s = -track.config().start_behind; s <= track.length() + 0.2;
         s += 0.005, t += 0.02) {
      const Vec2 p = Beside(track, s, offset(s));
      at_file.Update(t, p);
      WriteTruthRow(out, started_ns, t, p.x(), p.y(), 0.0, 0.0, 0.25);
    }
  }
  REQUIRE(at_file.completed());
  CHECK(at_file.gates_passed() == 1);  // gate 2 missed where the file has it
  SessionResult result;
  result.started_ns = started_ns;
  const record::TruthRecord truth = record::TruthRecord::Load(file);
  JudgeLapOnTruth(truth, track, result);
  const record::TruthLap& lap = result.record.truth_lap;
  REQUIRE(lap.judged);
  CHECK(lap.completed);
  CHECK(lap.gates_passed == 2);  // passed where it stands

  // The localiser's map at the end: every feature where the file has it,
  // but gate 2's right post, learnt where it stands. Scored in the map's
  // frame (the fit takes a little of the two posts' 8 cm): learning one
  // post takes the map's error down.
  for (const Segment2& w : track.walls()) {
    for (const Vec2& p : {w.a, w.b}) {
      if (std::none_of(result.learnt_map.begin(), result.learnt_map.end(),
                       [&](const auto& f) { return f.first == p; }))
        result.learnt_map.emplace_back(p, p);
    }
  }
  const size_t corners = result.learnt_map.size();
  for (const CircleObstacle& c : track.round_obstacles())
    result.learnt_map.emplace_back(c.center, c.center);
  ScorePrediction(truth, &track, result);
  const double file_rms = FitAsBuiltToFile(drawn, track).residual_m_rms;
  CHECK(result.record.map_estimated.features == static_cast<int>(result.learnt_map.size()));
  CHECK(result.record.map_estimated.file_m_rms == Approx(file_rms));
  CHECK(result.record.map_estimated.learnt_m_rms == Approx(file_rms));  // nothing learnt
  result.learnt_map[corners + 3].second += moved;
  ScorePrediction(truth, &track, result);
  CHECK(result.record.map_estimated.file_m_rms == Approx(file_rms));
  CHECK(result.record.map_estimated.learnt_m_rms < 0.8 * file_rms);
}
