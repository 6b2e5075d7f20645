// The simulated vehicles in a reality (config/reality.hpp): `none` is the
// twin bit for bit, `lab` ends measurably elsewhere on one command script
// and repeats exactly with one seed; the robot's state is its odometry, not
// the truth, stamped on its own clock; the truth goes only to the truth
// record; the blimp drifts in a steady wind with every channel at neutral.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "haptel/config/error.hpp"
#include "haptel/config/reality.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/record/truth_record.hpp"
#include "haptel/vehicles/blimp_adapters.hpp"
#include "haptel/vehicles/range_sensors.hpp"
#include "haptel/vehicles/sim_robot.hpp"
#include "haptel/vehicles/vehicle_core.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::vehicles;

namespace {

const VehicleConfig& Robot() {
  static const VehicleConfig robot = LoadVehicle("config/vehicles/sim-robot.yaml");
  return robot;
}
const Track& ShortTrack() {
  static const Track track(LoadTrack("config/tracks/test-short.yaml"));
  return track;
}
/// A square loop with a 3 m corridor: room to drive a script without a wall.
const Track& Arena() {
  static const Track track([] {
    TrackConfig t;
    t.name = "arena";
    t.centerline = {{0, 0}, {8, 0}, {8, 8}, {0, 8}};
    t.corridor_width = 3.0;
    t.gates = {{6.0, 1.0}};
    return t;
  }());
  return track;
}
DrawnReality Lab(uint64_t seed) {
  return DrawReality(LoadReality(RealityFile("lab")), seed, Robot(), &Arena());
}

/// One sample of a drive: what the state said and where the robot truly was.
struct Sample {
  AdapterState state;
  TruthRow truth;
};

/// 9 s of a fixed script at 200 Hz in the arena: ahead, a left arc, ahead
/// (no wall reached: the lab robot's skid is not hidden by a wall's push).
std::vector<Sample> DriveScript(SimRobot& robot) {
  std::vector<Sample> out;
  robot.Place(1.0, 0.0, 0.0);
  const struct {
    double until_s;
    models::MotorLevels levels;
  } script[] = {{2.0, {6, 6}}, {5.0, {3, 6}}, {9.0, {6, 6}}};
  double t = 0.0;
  for (const auto& step : script) {
    for (; t < step.until_s - 1e-9; t += 1.0 / 200) {
      robot.SetMotors(step.levels);
      robot.Update(1.0 / 200);
      Sample s{robot.State(), {}};
      REQUIRE(robot.Truth(&s.truth));
      REQUIRE_FALSE(s.state.bumper_left);
      REQUIRE_FALSE(s.state.bumper_right);
      out.push_back(s);
    }
  }
  return out;
}

double Distance(const TruthRow& a, const TruthRow& b) { return std::hypot(a.x - b.x, a.y - b.y); }

}  // namespace

TEST_CASE("in the reality none the robot is its twin bit for bit") {
  SimRobot twin(Arena(), Robot());
  VehicleConfig with_none = Robot();
  with_none.reality = RealityFile("none");
  SimRobot none(Arena(), with_none);
  const std::vector<Sample> a = DriveScript(twin);
  const std::vector<Sample> b = DriveScript(none);
  REQUIRE(a.size() == b.size());
  // Its scan is the file's track's, with the file's noise alone: no wall or
  // post moved, no false or missing echo.
  std::mt19937_64 file_noise(Robot().range_sensors.seed);
  ScanTrack(Arena(), 1.0, 0.0, 0.0, Robot().range_sensors, file_noise);  // Place's scan
  for (size_t i = 0; i < a.size(); ++i) {
    const RangeScan file = ScanTrack(Arena(), b[i].truth.x, b[i].truth.y, b[i].truth.heading,
                                     Robot().range_sensors, file_noise);
    CHECK(b[i].state.ranges.ranges == file.ranges);
    CHECK(a[i].state.x == b[i].state.x);
    CHECK(a[i].state.y == b[i].state.y);
    CHECK(a[i].state.heading == b[i].state.heading);
    CHECK(a[i].state.speed == b[i].state.speed);
    CHECK(a[i].state.ranges.ranges == b[i].state.ranges.ranges);
    // The twin reports the truth.
    CHECK(a[i].state.x == a[i].truth.x);
  }
}

TEST_CASE("a lab robot ends measurably elsewhere than its twin, the same with one seed") {
  SimRobot twin(Arena(), Robot());
  SimRobot lab(Arena(), Robot(), Lab(5));
  SimRobot again(Arena(), Robot(), Lab(5));
  SimRobot other(Arena(), Robot(), Lab(6));
  const std::vector<Sample> t = DriveScript(twin);
  const std::vector<Sample> a = DriveScript(lab);
  const std::vector<Sample> b = DriveScript(again);
  const std::vector<Sample> c = DriveScript(other);
  // The effective track width alone turns the lab robot 1.2-1.5 times less.
  const double apart = Distance(a.back().truth, t.back().truth);
  INFO("lab seed 5 ends " << apart << " m from the twin; seed 6 "
                          << Distance(c.back().truth, t.back().truth) << " m");
  CHECK(apart > 0.10);
  CHECK(Distance(c.back().truth, a.back().truth) > 0.01);
  for (size_t i = 0; i < a.size(); ++i) {
    CHECK(a[i].truth.x == b[i].truth.x);
    CHECK(a[i].truth.y == b[i].truth.y);
    CHECK(a[i].state.x == b[i].state.x);
    CHECK(a[i].state.heading == b[i].state.heading);
  }
}

TEST_CASE("a reality's range noise is its seed's: two seeds differ and one repeats") {
  // A reality that draws nothing but its range noise (no spread, no false
  // or missing echo, the file's map): the scans differ by the noise alone.
  RealityConfig noisy;
  noisy.name = "noisy";
  noisy.robot.range_noise_sd = 0.03;
  const auto scan = [&](uint64_t seed) {
    SimRobot robot(Arena(), Robot(), DrawReality(noisy, seed, Robot(), &Arena()));
    robot.Place(2.0, 1.0, 0.0);  // 0.5 m from the corridor's outer wall
    return robot.State().ranges;
  };
  const RangeScan one = scan(1), again = scan(1), other = scan(2);
  int seen = 0, differ = 0;
  for (int i = 0; i < one.count; ++i) {
    if (!(one.ranges[i] < Robot().range_sensors.max_range)) continue;
    ++seen;
    if (one.ranges[i] != other.ranges[i]) ++differ;
  }
  REQUIRE(seen > 5);
  CHECK(differ == seen);  // seeded from the vehicle file alone, they were equal
  CHECK(one.ranges == again.ranges);
}

TEST_CASE("a lab robot's beams and bumper meet the posts where they truly stand") {
  const Track& track = ShortTrack();
  const DrawnReality lab = DrawReality(LoadReality(RealityFile("lab")), 2, Robot(), &track);
  REQUIRE(lab.true_posts.size() == track.round_obstacles().size());
  // Facing the first gate's left post from 0.25 m where the file has it: the
  // beam ahead reads the distance to where it truly is.
  const CircleObstacle& file = track.round_obstacles()[0];
  const CircleObstacle& real = lab.true_posts[0];
  const Vec2 from = file.center - Vec2(0.25, 0.0);
  SimRobot robot(track, Robot(), lab);
  robot.Place(from.x(), from.y(), 0.0);
  const RangeScan scan = robot.State().ranges;
  const double ahead = CastRay(lab.true_walls, lab.true_posts, from, Vec2(1.0, 0.0), 1.5);
  CHECK(ahead != Approx(0.25 - file.radius).margin(1e-3));  // not where the file says
  // Within the lab's noise and its false echoes (of which the beam ahead is
  // not one at this seed).
  CHECK(scan.ranges[15] == Approx(ahead).margin(0.04));
  // The body stops against the true post, not the file's.
  robot.Place(real.center.x() - Robot().body.radius - real.radius - 0.01, real.center.y(), 0.0);
  robot.SetMotors({8, 8});
  for (int i = 0; i < 100; ++i) robot.Update(0.005);
  TruthRow truth;
  REQUIRE(robot.Truth(&truth));
  CHECK((Vec2(truth.x, truth.y) - real.center).norm() >= Robot().body.radius + real.radius - 1e-6);
  CHECK((robot.State().bumper_left || robot.State().bumper_right));  // touching it
}

TEST_CASE("a lab robot's state is its odometry, which drifts from the truth") {
  SimRobot lab(Arena(), Robot(), Lab(5));
  const std::vector<Sample> a = DriveScript(lab);
  const Sample& end = a.back();
  const double drift = std::hypot(end.state.x - end.truth.x, end.state.y - end.truth.y);
  INFO("odometry " << drift << " m from the truth after 9 s");
  CHECK(drift > 0.005);
  CHECK(drift < 0.5);  // still the robot's estimate of itself
  CHECK(end.state.heading != end.truth.heading);
}

TEST_CASE("the truth goes to the truth record; the state's stamp is the vehicle's clock") {
  const auto dir = test::ScratchDir("vehicles-truth");
  VehicleConfig config = Robot();
  config.reality = RealityFile("lab");
  config.reality_seed = 9;
  config.truth_file = dir / "truth.csv";
  DrawnReality drawn = DrawReality(LoadReality(config.reality), 9, config, &ShortTrack());
  {
    RobotCore core(config, std::make_unique<SimRobot>(ShortTrack(), config));
    msg::TreadCommand command;
    command.session(1);
    command.seq(1);
    command.left(0.75);
    command.right(0.5);
    const int64_t t0 = 1'000'000'000;
    core.OnCommand(command, t0);
    int64_t now = t0;
    for (int i = 0; i < 400; ++i) {
      now = t0 + i * 5'000'000;
      if (i % 20 == 0) {
        command.seq(static_cast<uint32_t>(2 + i));
        core.OnCommand(command, now);
      }
      core.ControlTick(now);
    }
    const msg::VehicleState& state = core.MakeState(now);
    // The clock's offset and drift, and the state's own jitter (< 10 ms).
    const double offset_s = 1e-9 * static_cast<double>(state.stamp_ns() - now);
    CHECK(offset_s == Approx(drawn.clock_offset_s).margin(0.011));
    CHECK(drawn.clock_offset_s != 0.0);
    // The state says the odometry, which is not the truth.
    TruthRow truth;
    REQUIRE(core.adapter().Truth(&truth));
    CHECK(std::hypot(state.x() - truth.x, state.y() - truth.y) > 1e-4);
  }
  const record::TruthRecord record = record::TruthRecord::Load(config.truth_file);
  CHECK(record.reality() == "lab");
  CHECK(record.seed() == 9);
  CHECK(record.params().effective_track_width == drawn.effective_track_width);
  CHECK(record.params().left_gain == drawn.left_gain);
  CHECK(record.params().floor_patches.size() == drawn.floor_patches.size());
  REQUIRE(record.rows().size() == 400);
  // Stamped with the operator's clock, one row a control tick.
  CHECK(record.rows().front().operator_ns == 1'000'000'000);
  CHECK(record.rows()[1].operator_ns - record.rows()[0].operator_ns == 5'000'000);
  const TruthRow& r10 = record.rows()[10];
  const TruthRow& r11 = record.rows()[11];
  const TruthRow mid = record.PoseAt(1e-9 * static_cast<double>(r10.operator_ns + 2'500'000));
  CHECK(mid.x == Approx(0.5 * (r10.x + r11.x)).margin(1e-6));
  CHECK(mid.y == Approx(0.5 * (r10.y + r11.y)).margin(1e-6));
  CHECK(record.PoseAt(0.0).x == record.rows().front().x);
  CHECK(record.Covers(1.5));
  CHECK_FALSE(record.Covers(10.0));
}

TEST_CASE("a vehicle without a truth refuses a truth record") {
  VehicleConfig config = Robot();
  config.truth_file = test::ScratchDir("vehicles-no-truth") / "truth.csv";
  struct Hardware final : VehicleAdapter {
    void SetMotors(const models::MotorLevels&) override {}
    void Update(double) override {}
    AdapterState State() const override { return {}; }
  };
  CHECK_THROWS_AS(RobotCore(config, std::make_unique<Hardware>()), ConfigError);
}

TEST_CASE("the blimp drifts in a steady wind with every channel at neutral") {
  const VehicleConfig blimp = LoadVehicle("config/vehicles/sim-blimp.yaml");
  const BlimpCourseConfig course = LoadBlimpCourse(blimp.world);
  DrawnReality windy = NominalReality(blimp);
  windy.name = "windy";
  windy.seed = 1;
  windy.wind_x = 2.0;  // m/s towards +x
  SimBlimpAdapter twin(blimp.airship, course, NominalReality(blimp));
  SimBlimpAdapter blown(blimp.airship, course, windy);
  for (SimBlimpAdapter* a : {&twin, &blown}) {
    a->Failsafe();
    for (int i = 0; i < 10 * 200; ++i) a->Update(1.0 / 200);
  }
  TruthRow still, moved;
  REQUIRE(twin.Truth(&still));
  REQUIRE(blown.Truth(&moved));
  const BlimpAdapterState start = SimBlimpAdapter(blimp.airship, course, windy).State();
  INFO("the twin moved " << std::hypot(still.x - start.x, still.y - start.y) << " m, the blown one "
                         << moved.x - start.x << " m along the wind");
  CHECK(std::hypot(still.x - start.x, still.y - start.y) < 0.01);
  CHECK(moved.x - start.x > 0.5);
  // Its state says where it is, never the wind.
  CHECK(blown.State().x == moved.x);
}
