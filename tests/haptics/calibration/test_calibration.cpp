// Calibration: the fitting maths (glove, tracker, force), the apply helpers,
// the procedure on the sim device (unattended and attended) and the command line.
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <functional>
#include <optional>
#include <random>
#include <sstream>
#include <streambuf>

#include "alloc_counter.hpp"
#include "haptel/calibration/calibration.hpp"
#include "haptel/calibration/calibration_procedure.hpp"
#include "haptel/config/device.hpp"
#include "haptel/config/run.hpp"
#include "haptel/haptics/sim_device.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::haptics;
using Catch::Contains;

namespace {

using Sensors = std::array<double, kGloveJoints>;

/// A glove with known linear sensors: counts = (angle − offset) / gain,
/// unrounded unless asked. Sensor 5 is mounted reversed (negative gain).
struct SyntheticGlove {
  Sensors gain{};
  Sensors offset{};
  explicit SyntheticGlove(unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> g(0.004, 0.008);
    std::uniform_real_distribution<double> p(-0.3, 0.1);
    for (int j = 0; j < kGloveJoints; ++j) {
      gain[j] = g(rng) * (j == 5 ? -1.0 : 1.0);
      offset[j] = p(rng);
    }
  }
  Sensors Read(const Sensors& angles, bool rounded = false) const {
    Sensors raw{};
    for (int j = 0; j < kGloveJoints; ++j) {
      raw[j] = (angles[j] - offset[j]) / gain[j];
      if (rounded) raw[j] = std::round(raw[j]);
    }
    return raw;
  }
  Sensors Read(std::string_view posture, bool rounded = false) const {
    return Read(GlovePostures()[static_cast<size_t>(GlovePostureIndex(posture))].angles, rounded);
  }
};

bool Near(double a, double b, double relative) {
  return std::abs(a - b) <= relative * std::max(std::abs(a), std::abs(b));
}

/// An input stream whose lines are produced one at a time, when the reader
/// gets to them: the generator is the scripted operator acting on a prompt.
class ScriptedInput : public std::streambuf {
 public:
  void Add(std::function<std::string()> line) { lines_.push_back(std::move(line)); }
  void Add(const std::string& text) {
    lines_.push_back([text] { return text; });
  }
  size_t unread() const { return lines_.size() - next_; }

 protected:
  int_type underflow() override {
    if (gptr() != nullptr && gptr() < egptr()) return traits_type::to_int_type(*gptr());
    if (next_ >= lines_.size()) return traits_type::eof();
    current_ = lines_[next_++]() + "\n";
    setg(current_.data(), current_.data(), current_.data() + current_.size());
    return traits_type::to_int_type(*gptr());
  }

 private:
  std::vector<std::function<std::string()>> lines_;
  size_t next_ = 0;
  std::string current_;
};

/// Forwards to a SimDevice (without being one) and remembers the last wrist
/// command: a "real" device for the attended procedure.
class RecordingDevice final : public Device {
 public:
  explicit RecordingDevice(SimDevice& sim) : sim_(sim) {}
  const DeviceDescription& description() const override { return sim_.description(); }
  DeviceStatus ReadWrist(Side side, int64_t now_ns, WristRaw& out) override {
    return sim_.ReadWrist(side, now_ns, out);
  }
  DeviceStatus ReadGlove(Side side, int64_t now_ns, GloveRaw& out) override {
    return sim_.ReadGlove(side, now_ns, out);
  }
  DeviceStatus WriteWristForce(Side side, const Vec3d& command) override {
    last_command[Index(side)] = command;
    return sim_.WriteWristForce(side, command);
  }
  DeviceStatus WriteFingerForces(Side side, const std::array<double, kFingers>& command) override {
    return sim_.WriteFingerForces(side, command);
  }
  std::array<Vec3d, kSides> last_command{};

 private:
  SimDevice& sim_;
};

DeviceConfig SimConfig(int seed) {
  DeviceConfig config = LoadDevice("config/devices/sim.yaml");
  if (seed != 0) config.sim.seed = seed;
  return config;
}

/// Asserts one arm's calibration against the sim's truth, within the worst
/// cases the physics of each measurement allows (see calibration_procedure.hpp).
void CheckAgainstTruth(const ArmCalibration& c, const SimArmTruth& t, const SimArmConfig& sim,
                       bool glove = true) {
  // Tracker: encoder quantisation r (≤ r/2 per reading) with references at
  // ±a about the centre: ε = |Δs/s| ≤ (r/2a)·(1 + 7r/4a)/(1 − r/a) (the exact
  // worst case of the least-squares ratio for the 7 default poses) and
  // |Δo| ≤ |c − o|·ε + (1 + ε)·r/2.
  const double r = sim.encoder_resolution;
  const double a = kReferenceHalfSpan;
  const double scale_bound = r / (2 * a) * (1 + 1.75 * r / a) / (1 - r / a);
  for (int i = 0; i < 3; ++i) {
    INFO("tracker axis " << i);
    const double scale_error = std::abs(c.tracker_scale[i] / t.tracker_scale[i] - 1.0);
    CHECK(scale_error <= scale_bound);
    const double offset_bound = std::abs(kReferenceCentre[i] - t.tracker_offset[i]) * scale_bound +
                                (1 + scale_bound) * r / 2;
    CHECK(std::abs(c.tracker_offset[i] - t.tracker_offset[i]) <= offset_bound);
    // The sim's gauge is exact: rounding only.
    CHECK(std::abs(c.force_slope[i] / t.force_slope[i] - 1.0) <= 1e-9);
  }
  CHECK(c.force_residual <= 1e-9);
  CHECK(c.finger_force_slope == 1.0);  // not measured: kept from the base
  if (!glove) return;
  // Glove: counts rounded (≤ 0.5 each) at the two postures furthest apart in
  // angle, N = Δθ/g counts apart: |Δg/g| ≤ 1/(N − 1), the angle over that
  // range within g/2, the offset within g·(|r_a| + |r_b| + 1)/(2(N − 1)).
  const auto& postures = GlovePostures();
  for (size_t j = 0; j < kGloveJoints; ++j) {
    INFO("glove sensor " << kGloveSensorNames[j]);
    double widest = 0.0;
    for (size_t p = 0; p < postures.size(); ++p) {
      for (size_t q = p + 1; q < postures.size(); ++q) {
        widest = std::max(widest, std::abs(postures[q].angles[j] - postures[p].angles[j]));
      }
    }
    const double g = std::abs(t.glove_gain[j]);
    double gain_bound = 0.0;
    double offset_bound = 0.0;
    double lo = 1e9;
    double hi = -1e9;
    for (size_t p = 0; p < postures.size(); ++p) {
      lo = std::min(lo, postures[p].angles[j]);
      hi = std::max(hi, postures[p].angles[j]);
      for (size_t q = p + 1; q < postures.size(); ++q) {
        if (std::abs(postures[q].angles[j] - postures[p].angles[j]) < widest - 1e-12) continue;
        const double ra = (postures[p].angles[j] - t.glove_offset[j]) / t.glove_gain[j];
        const double rb = (postures[q].angles[j] - t.glove_offset[j]) / t.glove_gain[j];
        const double n = std::abs(rb - ra);
        gain_bound = std::max(gain_bound, 1.0 / (n - 1.0));
        offset_bound =
            std::max(offset_bound, 0.5 * g * (std::abs(ra) + std::abs(rb) + 1.0) / (n - 1.0));
      }
    }
    CHECK(std::abs(c.glove_gain[j] / t.glove_gain[j] - 1.0) <= gain_bound + 1e-12);
    CHECK(std::abs(c.glove_offset[j] - t.glove_offset[j]) <= offset_bound + 1e-12);
    for (double angle : {lo, hi}) {
      const double raw = (angle - t.glove_offset[j]) / t.glove_gain[j];
      CHECK(std::abs(GloveToRadians(c, static_cast<int>(j), raw) - angle) <= 0.5 * g + 1e-12);
    }
  }
}

}  // namespace

// ---------------------------------------------------------------- glove ----

TEST_CASE("the posture table determines every glove sensor") {
  const auto& postures = GlovePostures();
  REQUIRE(postures.size() == 4);
  for (size_t j = 0; j < kGloveJoints; ++j) {
    INFO(kGloveSensorNames[j]);
    double widest = 0.0;
    for (const auto& p : postures) {
      for (const auto& q : postures) widest = std::max(widest, std::abs(p.angles[j] - q.angles[j]));
    }
    CHECK(widest >= 0.3 - 1e-12);
  }
  CHECK(GlovePostureIndex("fist") == 1);
  CHECK(GlovePostureIndex("thumbs-up") == -1);
}

TEST_CASE("glove fit is exact on noiseless synthetic data") {
  const SyntheticGlove glove(11);
  GloveCalibrator calibrator;
  for (const auto& p : GlovePostures()) calibrator.Capture(p.name, glove.Read(p.angles));
  REQUIRE(calibrator.Ready());
  const GloveFit fit = calibrator.Fit();
  ArmCalibration arm;
  fit.ApplyTo(arm);
  for (int j = 0; j < kGloveJoints; ++j) {
    INFO(kGloveSensorNames[j]);
    CHECK(Near(arm.glove_gain[j], glove.gain[j], 1e-12));
    CHECK(std::abs(arm.glove_offset[j] - glove.offset[j]) <= 1e-12);
    CHECK(fit.sensors[j].check_error <= 1e-12);
    // A reading anywhere maps back to its angle.
    Sensors angles{};
    angles.fill(0.7);
    CHECK(std::abs(GloveToRadians(arm, j, glove.Read(angles)[j]) - 0.7) <= 1e-12);
  }
}

TEST_CASE("glove fit uses the two postures whose readings differ most") {
  const SyntheticGlove glove(12);
  Sensors flat = glove.Read("flat");
  Sensors fist = glove.Read("fist");
  const Sensors spread = glove.Read("spread");
  const Sensors bent = glove.Read("bent");
  // The operator's "flat" wrist was 25 counts off, and the thumb in the fist
  // 15 counts off: a fit through either would be wrong.
  constexpr int kPitch = 20;
  constexpr int kThumbAbduction = 3;
  flat[kPitch] += 25;
  fist[kThumbAbduction] -= 15;
  GloveCalibrator calibrator;
  calibrator.Capture("flat", flat);
  calibrator.Capture("fist", fist);
  calibrator.Capture("spread", spread);
  calibrator.Capture("bent", bent);
  const GloveFit fit = calibrator.Fit();

  // Wrist pitch: spread (−0.8 rad) ↔ bent (+0.9 rad), not flat ↔ anything.
  CHECK(fit.sensors[kPitch].posture_a == GlovePostureIndex("spread"));
  CHECK(fit.sensors[kPitch].posture_b == GlovePostureIndex("bent"));
  CHECK(Near(fit.sensors[kPitch].gain, glove.gain[kPitch], 1e-12));
  CHECK(fit.sensors[kPitch].check_error == Approx(25 * glove.gain[kPitch]).epsilon(1e-9));
  // A naive pair (the first two captured postures that differ in angle for
  // this sensor: flat ↔ spread) would have been off by percents.
  const double naive = (-0.8 - 0.0) / (spread[kPitch] - flat[kPitch]);
  CHECK(std::abs(naive / glove.gain[kPitch] - 1.0) > 0.05);

  // Thumb abduction: flat (0) ↔ spread (1.0 rad), not the fist (0.3 rad).
  CHECK(fit.sensors[kThumbAbduction].posture_a == GlovePostureIndex("flat"));
  CHECK(fit.sensors[kThumbAbduction].posture_b == GlovePostureIndex("spread"));
  CHECK(Near(fit.sensors[kThumbAbduction].gain, glove.gain[kThumbAbduction], 1e-12));
  CHECK(std::abs(fit.sensors[kThumbAbduction].offset - glove.offset[kThumbAbduction]) <= 1e-12);
}

TEST_CASE("glove postures captured in any order give the same fit") {
  const SyntheticGlove glove(13);
  std::array<Sensors, 4> raw{};
  for (int p = 0; p < 4; ++p)
    raw[p] = glove.Read(GlovePostures()[p].angles, true);  // integer counts
  raw[0][20] += 7;                                         // a sloppy flat wrist
  std::array<int, 4> order{0, 1, 2, 3};
  std::optional<GloveFit> first;
  int orders = 0;
  do {
    GloveCalibrator calibrator;
    for (int p : order) calibrator.Capture(GlovePostures()[p].name, raw[p]);
    const GloveFit fit = calibrator.Fit();
    if (!first) first = fit;
    for (int j = 0; j < kGloveJoints; ++j) {
      CHECK(fit.sensors[j].gain == first->sensors[j].gain);
      CHECK(fit.sensors[j].offset == first->sensors[j].offset);
      CHECK(fit.sensors[j].posture_a == first->sensors[j].posture_a);
      CHECK(fit.sensors[j].posture_b == first->sensors[j].posture_b);
    }
    ++orders;
  } while (std::next_permutation(order.begin(), order.end()));
  CHECK(orders == 24);
}

TEST_CASE("recapturing a glove posture replaces it") {
  const SyntheticGlove glove(14);
  GloveCalibrator calibrator;
  Sensors half_fist{};
  for (int j = 0; j < kGloveJoints; ++j) half_fist[j] = 0.5 * GlovePostures()[1].angles[j];
  calibrator.Capture("flat", glove.Read("flat"));
  calibrator.Capture("fist", glove.Read(half_fist));  // fumbled: half a fist
  calibrator.Capture("spread", glove.Read("spread"));
  calibrator.Capture("bent", glove.Read("bent"));
  constexpr int kIndexMcp = 4;
  // Half the angle for the full fist's known angle: twice the gain.
  CHECK(Near(calibrator.Fit().sensors[kIndexMcp].gain, 2.0 * glove.gain[kIndexMcp], 1e-12));

  CHECK_THROWS_AS(calibrator.Capture("fist", glove.Read("fist")), CalibrationError);
  calibrator.Recapture("fist", glove.Read("fist"));
  const GloveFit fit = calibrator.Fit();
  for (int j = 0; j < kGloveJoints; ++j) CHECK(Near(fit.sensors[j].gain, glove.gain[j], 1e-12));

  GloveCalibrator fresh;
  CHECK_THROWS_WITH(fresh.Recapture("flat", glove.Read("flat")), Contains("never captured"));
  CHECK_THROWS_WITH(fresh.Capture("thumbs-up", glove.Read("flat")),
                    Contains("unknown glove posture 'thumbs-up'"));
  Sensors bad = glove.Read("flat");
  bad[9] = std::nan("");
  CHECK_THROWS_WITH(fresh.Capture("flat", bad), Contains("middle_dip"));
  CHECK_FALSE(fresh.Captured("flat"));
}

TEST_CASE("a glove sensor that barely changes is an error naming it") {
  const SyntheticGlove glove(15);
  std::array<Sensors, 4> raw{};
  for (int p = 0; p < 4; ++p) raw[p] = glove.Read(GlovePostures()[p].angles, true);
  for (int p = 0; p < 4; ++p) raw[p][7] = 512;  // middle_mcp stuck
  raw[2][18] = raw[0][18] + 4;                  // ring_pinky_abduction: 4 counts only
  GloveCalibrator calibrator;
  for (int p = 0; p < 4; ++p) calibrator.Capture(GlovePostures()[p].name, raw[p]);
  try {
    calibrator.Fit();
    FAIL("no error");
  } catch (const CalibrationError& e) {
    const std::string what = e.what();
    CHECK_THAT(what, Contains("middle_mcp (0 counts"));
    CHECK_THAT(what, Contains("ring_pinky_abduction (4 counts"));
    CHECK(what.find("index_mcp") == std::string::npos);
  }
}

TEST_CASE("the glove fit needs postures that determine every sensor") {
  const SyntheticGlove glove(16);
  GloveCalibrator calibrator;
  calibrator.Capture("fist", glove.Read("fist"));
  calibrator.Capture("flat", glove.Read("flat"));
  CHECK_FALSE(calibrator.Ready());
  const auto missing = calibrator.Undetermined();
  CHECK(std::find(missing.begin(), missing.end(), "wrist_pitch") != missing.end());
  CHECK(std::find(missing.begin(), missing.end(), "index_mcp") == missing.end());
  CHECK_THROWS_WITH(calibrator.Fit(), Contains("wrist_pitch") && Contains("capture: spread, bent"));
  calibrator.Capture("spread", glove.Read("spread"));  // three postures suffice
  CHECK(calibrator.Ready());
  CHECK_NOTHROW(calibrator.Fit());
}

// -------------------------------------------------------------- tracker ----

TEST_CASE("tracker scale and offset are recovered exactly from reference poses") {
  const Vec3d scale{0.0103, 0.0097, -0.0101};  // z reversed
  const Vec3d offset{0.02, -0.015, 0.005};
  std::vector<TrackerReference> refs;
  for (const Vec3d& m : DefaultTrackerReferences()) {
    refs.push_back({{(m[0] - offset[0]) / scale[0], (m[1] - offset[1]) / scale[1],
                     (m[2] - offset[2]) / scale[2]},
                    m});
  }
  const TrackerFit fit = FitTracker(refs);
  for (int i = 0; i < 3; ++i) {
    CHECK(fit.scale_fitted[i]);
    CHECK(Near(fit.scale[i], scale[i], 1e-12));
    CHECK(std::abs(fit.offset[i] - offset[i]) <= 1e-12);
    CHECK(fit.residual_rms[i] <= 1e-12);
  }
  ArmCalibration arm;
  fit.ApplyTo(arm);
  const Vec3d m = TrackerToMetres(arm, refs[3].raw);
  for (int i = 0; i < 3; ++i) CHECK(m[i] == Approx(refs[3].metres[i]).margin(1e-12));
}

TEST_CASE("one reference pose fits the offset with the default scale") {
  const TrackerReference ref{{4.0, -3.0, 12.0}, {0.10, -0.02, 0.15}};
  const TrackerFit fit = FitTracker({ref});
  for (int i = 0; i < 3; ++i) {
    CHECK_FALSE(fit.scale_fitted[i]);
    CHECK(fit.scale[i] == kDefaultTrackerScale);
    CHECK(fit.offset[i] == Approx(ref.metres[i] - 0.01 * ref.raw[i]).margin(1e-15));
  }
  // References along x only: x is fitted, y and z keep the default scale.
  std::vector<TrackerReference> refs;
  for (double x : {-0.1, 0.0, 0.1}) refs.push_back({{x / 0.0102 + 3.0, 1.0, 2.0}, {x, 0.0, 0.0}});
  const TrackerFit along_x = FitTracker(refs);
  CHECK(along_x.scale_fitted[0]);
  CHECK(along_x.scale[0] == Approx(0.0102).epsilon(1e-12));
  CHECK_FALSE(along_x.scale_fitted[1]);
  CHECK(along_x.scale[1] == kDefaultTrackerScale);
  CHECK(along_x.offset[1] == Approx(-0.01).margin(1e-15));
}

TEST_CASE("degenerate tracker references are errors naming the axis") {
  CHECK_THROWS_WITH(FitTracker({}), Contains("no reference pose"));
  std::vector<TrackerReference> refs;
  for (double v : {-0.1, 0.0, 0.1})
    refs.push_back({{v * 100, 7.0, v * 100}, {v, v, v}});  // y stuck
  CHECK_THROWS_WITH(FitTracker(refs), Contains("tracker axis y"));
  refs[0].raw[1] = std::nan("");
  CHECK_THROWS_WITH(FitTracker(refs), Contains("reference pose 1"));
}

// ---------------------------------------------------------------- force ----

TEST_CASE("force slopes and residual from noisy gauge readings") {
  const Vec3d slope{1.12, 0.87, 0.95};
  constexpr double kNoise = 0.05;  // N, gauge standard deviation
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> command(-5.0, 5.0);
  std::normal_distribution<double> noise(0.0, kNoise);
  std::vector<ForceSample> samples;
  Vec3d sum_c2{};
  for (int k = 0; k < 400; ++k) {
    ForceSample s;
    for (int i = 0; i < 3; ++i) {
      s.command[i] = command(rng);
      s.newtons[i] = slope[i] * s.command[i] + noise(rng);
      sum_c2[i] += s.command[i] * s.command[i];
    }
    samples.push_back(s);
  }
  const ForceFit fit = FitForce(samples);
  for (int i = 0; i < 3; ++i) {
    // Standard error of a slope through the origin: σ/√Σc²; 4 of them.
    CHECK(std::abs(fit.slope[i] - slope[i]) <= 4 * kNoise / std::sqrt(sum_c2[i]));
    // The RMS estimate of σ from n samples has relative spread 1/√(2n) = 3.5 %.
    CHECK(fit.residual_axis[i] == Approx(kNoise).epsilon(4 * 0.035));
  }
  CHECK(fit.residual == Approx(kNoise).epsilon(4 / std::sqrt(2.0 * 1200)));
  // Noiseless: exact, zero residual.
  for (auto& s : samples) {
    for (int i = 0; i < 3; ++i) s.newtons[i] = slope[i] * s.command[i];
  }
  const ForceFit exact = FitForce(samples);
  for (int i = 0; i < 3; ++i) CHECK(Near(exact.slope[i], slope[i], 1e-14));
  CHECK(exact.residual <= 1e-14);
}

TEST_CASE("degenerate force data is rejected") {
  std::vector<ForceSample> samples;
  for (double c : {-2.0, 1.0, 3.0}) samples.push_back({{c, 0, 0}, {c, 0, 0}});
  CHECK_THROWS_WITH(FitForce(samples), Contains("force axis y") && Contains("got 0"));
  samples.clear();
  for (double c : {-2.0, 2.0}) samples.push_back({{c, c, c}, {c, 0.0, c}});
  CHECK_THROWS_WITH(FitForce(samples), Contains("force axis y: the gauge read no force"));
  samples[1].newtons[1] = std::numeric_limits<double>::infinity();
  CHECK_THROWS_WITH(FitForce(samples), Contains("sample 2 is not finite"));
  CHECK_THROWS(FitForce({}));
}

// ---------------------------------------------------------------- apply ----

TEST_CASE("apply helpers invert the device maps without allocating") {
  ArmCalibration c;
  c.tracker_scale = {0.0102, 0.0098, 0.0101};
  c.tracker_offset = {0.01, -0.02, 0.03};
  c.force_slope = {1.1, 0.9, 1.2};
  c.glove_gain[4] = 0.006;
  c.glove_offset[4] = -0.2;
  static_assert(noexcept(TrackerToMetres(c, Vec3d{})));
  static_assert(noexcept(NewtonsToCommand(c, Vec3d{})));
  static_assert(noexcept(GloveToRadians(c, 0, 0.0)));
  const uint64_t before = test::ThreadAllocations();
  Vec3d metres{};
  Vec3d command{};
  double angle = 0.0;
  for (int k = 0; k < 1000; ++k) {
    metres = TrackerToMetres(c, MetresToTracker(c, {0.1, -0.05, 0.2}));
    command = NewtonsToCommand(c, {2.2, -1.8, 3.6});
    angle = GloveToRadians(c, 4, 150.0);
  }
  CHECK(test::ThreadAllocations() == before);
  CHECK(metres[0] == Approx(0.1));
  CHECK(metres[1] == Approx(-0.05));
  CHECK(metres[2] == Approx(0.2));
  CHECK(command[0] == Approx(2.0));
  CHECK(command[1] == Approx(-2.0));
  CHECK(command[2] == Approx(3.0));
  CHECK(angle == Approx(0.006 * 150 - 0.2));
  CHECK(TrackerToMetres(c, {1.0, 0, 0})[0] == Approx(0.0102 + 0.01));
}

// ------------------------------------------------------------ procedure ----

TEST_CASE("unattended calibration recovers the sim device's hidden parameters") {
  for (int seed : {0, 2, 12345}) {  // 0: the shipped file's own seed
    const DeviceConfig config = SimConfig(seed);
    INFO("seed " << config.sim.seed);
    SimDevice sim(config, OperatorConfig{});
    CalibrationOptions options;
    options.auto_mode = true;
    options.user = "tester";
    options.seed = static_cast<unsigned>(seed + 3);
    std::ostringstream log;
    const DeviceCalibration c = RunCalibration(sim, options, log);
    CHECK(c.device == "sim");
    CHECK(c.user == "tester");
    CHECK_THAT(log.str(), Contains("fumbled") && Contains("redoing"));
    for (int s = 0; s < kSides; ++s) {
      INFO("side " << s);
      CheckAgainstTruth(c.arms[s], sim.truth(static_cast<Side>(s)), sim.config());
    }
  }
}

TEST_CASE("both calibrated arms report the same point in one frame") {
  SimDevice sim(SimConfig(0), OperatorConfig{});
  CalibrationOptions options;
  options.auto_mode = true;
  options.glove = false;
  std::ostringstream log;
  const DeviceCalibration c = RunCalibration(sim, options, log);
  const Vec3d point{0.13, -0.07, 0.09};  // not one of the references
  std::array<Vec3d, kSides> calibrated{};
  std::array<Vec3d, kSides> uncalibrated{};
  for (int s = 0; s < kSides; ++s) {
    const Side side = static_cast<Side>(s);
    sim.Dock(side, point);  // fixed there (a hand holding it would shake)
    WristRaw raw;
    REQUIRE(sim.ReadWrist(side, 1'000'000'000'000, raw) == DeviceStatus::kOk);
    calibrated[s] = TrackerToMetres(c.arms[s], raw.position);
    uncalibrated[s] = TrackerToMetres(ArmCalibration{}, raw.position);
  }
  // Each within quantisation (r/2) plus the scale and offset bounds:
  // |ε|·|p − o| + (1 + ε)·r/2 + |Δo| per axis, about 0.15 mm here.
  const double r = sim.config().encoder_resolution;
  const double eps = r / (2 * kReferenceHalfSpan) * 1.002;
  for (int i = 0; i < 3; ++i) {
    double total = 0.0;
    for (int s = 0; s < kSides; ++s) {
      const double o = sim.truth(static_cast<Side>(s)).tracker_offset[i];
      const double offset_bound = std::abs(kReferenceCentre[i] - o) * eps + (1 + eps) * r / 2;
      const double bound = eps * std::abs(point[i] - o) + (1 + eps) * r / 2 + offset_bound;
      CHECK(std::abs(calibrated[s][i] - point[i]) <= bound);
      total += bound;
    }
    CHECK(std::abs(calibrated[0][i] - calibrated[1][i]) <= total);
  }
  // Without calibration the arms disagree by centimetres (hidden offsets).
  double apart = 0.0;
  for (int i = 0; i < 3; ++i)
    apart = std::max(apart, std::abs(uncalibrated[0][i] - uncalibrated[1][i]));
  CHECK(apart > 0.005);
}

TEST_CASE("attended calibration follows the operator's answers") {
  SimDevice sim(SimConfig(0), OperatorConfig{});
  RecordingDevice device(sim);  // not a SimDevice: the procedure prompts
  ScriptedInput script;
  const std::vector<Vec3d> refs = DefaultTrackerReferences();
  for (int s = 0; s < kSides; ++s) {
    const Side side = static_cast<Side>(s);
    auto make = [&sim, side](int posture, double formed) {
      return [&sim, side, posture, formed] {
        Sensors angles{};
        for (int j = 0; j < kGloveJoints; ++j)
          angles[j] = formed * GlovePostures()[posture].angles[j];
        sim.SetGlovePosture(side, angles);
        return std::string();
      };
    };
    // Glove: the postures in table order, the fist fumbled, then redone.
    script.Add(make(0, 1.0));
    script.Add(make(1, 0.6));
    script.Add(make(2, 1.0));
    script.Add(make(3, 1.0));
    script.Add("thumbs-up");  // no such posture: asked again
    script.Add("fist");
    script.Add(make(1, 1.0));
    script.Add("");  // done redoing
    // Tracker: the wrist goes into the jig at each reference.
    for (const Vec3d& ref : refs) {
      script.Add([&sim, side, ref] {
        sim.Dock(side, ref);
        return std::string();
      });
    }
    // Force: the operator reads the gauge for the command on the device.
    bool typo = true;
    for (int k = 0; k < 24; ++k) {
      if (typo) {
        script.Add("about three");  // not a number: asked again
        typo = false;
      }
      script.Add([&sim, &device, side] {
        const Vec3d command = device.last_command[Index(side)];
        const Vec3d newtons = sim.MeasureForce(side, command);
        int axis = 0;
        for (int i = 0; i < 3; ++i) {
          if (command[i] != 0.0) axis = i;
        }
        std::ostringstream out;
        out.precision(17);
        out << newtons[axis];
        return out.str();
      });
    }
  }
  std::istream in(&script);
  std::ostringstream log;
  CalibrationOptions options;
  const DeviceCalibration c = RunCalibration(device, options, log, in);
  CHECK(script.unread() == 0);
  CHECK_THAT(log.str(), Contains("posture 'fist'") && Contains("Hold it and press Enter"));
  CHECK_THAT(log.str(), Contains("no posture 'thumbs-up'"));
  CHECK_THAT(log.str(), Contains("Put the right wrist in the jig"));
  CHECK_THAT(log.str(), Contains("not a number: 'about three'"));
  for (int s = 0; s < kSides; ++s) {
    INFO("side " << s);
    CheckAgainstTruth(c.arms[s], sim.truth(static_cast<Side>(s)), sim.config());
  }
}

TEST_CASE("the procedure stops on a lost device, a non-sim device in auto mode, or ended input") {
  SimDevice sim(SimConfig(0), OperatorConfig{});
  std::ostringstream log;
  CalibrationOptions options;
  options.auto_mode = true;
  sim.SetLost(Side::kLeft, true);
  CHECK_THROWS_WITH(RunCalibration(sim, options, log), Contains("left arm stopped answering"));
  sim.SetLost(Side::kLeft, false);

  RecordingDevice other(sim);
  CHECK_THROWS_WITH(RunCalibration(other, options, log), Contains("needs the sim device"));

  options.auto_mode = false;
  std::istringstream empty("");
  CHECK_THROWS_WITH(RunCalibration(other, options, log, empty), Contains("input ended"));
}

// ---------------------------------------------------------- command line ----

namespace {
int Calibrate(std::vector<const char*> args) {
  args.insert(args.begin(), "haptel");
  return CalibrateMain(static_cast<int>(args.size()), args.data());
}

/// Runs in another working directory for the scope.
struct InDirectory {
  explicit InDirectory(const std::filesystem::path& dir) : saved(std::filesystem::current_path()) {
    std::filesystem::current_path(dir);
  }
  ~InDirectory() { std::filesystem::current_path(saved); }
  std::filesystem::path saved;
};
}  // namespace

TEST_CASE("haptel calibrate writes a file the loader accepts") {
  const auto dir = test::ScratchDir("calibrate-cli");
  const std::string out = (dir / "alice" / "sim.yaml").string();
  REQUIRE(Calibrate({"calibrate", "--auto", "--user", "alice", "--out", out.c_str()}) == 0);
  const DeviceCalibration c = LoadCalibration(out);
  CHECK(c.user == "alice");
  CHECK(c.device == "sim");
  SimDevice sim(SimConfig(0), OperatorConfig{});
  for (int s = 0; s < kSides; ++s)
    CheckAgainstTruth(c.arms[s], sim.truth(static_cast<Side>(s)), sim.config());

  // Default output: calibration/<device>.yaml under the working directory.
  const std::string device = std::filesystem::absolute("config/devices/sim.yaml").string();
  {
    InDirectory here(dir);
    REQUIRE(Calibrate({"--auto", "--device", device.c_str()}) == 0);
  }
  CHECK(LoadCalibration(dir / "calibration" / "sim.yaml").user == "default");
}

TEST_CASE("haptel calibrate rejects bad arguments and configuration with status 2") {
  const auto dir = test::ScratchDir("calibrate-cli-bad");
  CHECK(Calibrate({"calibrate", "--auto", "--colour", "red"}) == 2);
  CHECK(Calibrate({"calibrate", "--auto", "extra"}) == 2);
  CHECK(Calibrate({"calibrate"}) == 2);  // the sim needs --auto
  CHECK(Calibrate({"calibrate", "--auto", "--device", (dir / "absent.yaml").c_str()}) == 2);
  std::ofstream(dir / "udp.yaml")
      << "name: exo\ndriver: udp\nudp:\n  left: {port: 5000}\n  right: {port: 5001}\n";
  CHECK(Calibrate({"calibrate", "--auto", "--device", (dir / "udp.yaml").c_str()}) == 2);
  CHECK_FALSE(std::filesystem::exists(dir / "calibration"));
}
