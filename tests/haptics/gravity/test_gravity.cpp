// Gravity compensation: the grid file, online interpolation and fade, the
// sampler's decision table, sampling on the sim device, and the drift the
// sampled grid removes. Everything runs in simulated time: no wall clock.
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <iostream>
#include <iterator>
#include <random>
#include <set>

#include "alloc_counter.hpp"
#include "gravity_bench.hpp"
#include "haptel/calibration/calibration_procedure.hpp"
#include "haptel/config/device.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/gravity_grid.hpp"
#include "haptel/config/run.hpp"
#include "haptel/gravity/gravity_sampler.hpp"
#include "haptel/haptics/sim_device.hpp"
#include "haptel/testing/gravity_on_sim.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::haptics;
using Catch::Contains;

namespace {

/// A grid over [-0.1, 0.3]×[-0.2, 0.2]×[-0.1, 0.2] with values from f.
template <typename F>
GravityGridData MakeGrid(std::array<int, 3> counts, F f) {
  GravityGridData g;
  g.min = {-0.1, -0.2, -0.1};
  g.max = {0.3, 0.2, 0.2};
  g.counts = counts;
  g.device = "test";
  g.force_z.resize(static_cast<size_t>(counts[0] * counts[1] * counts[2]));
  for (int k = 0; k < counts[2]; ++k) {
    for (int j = 0; j < counts[1]; ++j) {
      for (int i = 0; i < counts[0]; ++i) {
        const Vec3d p{g.min[0] + (g.max[0] - g.min[0]) * i / (counts[0] - 1),
                      g.min[1] + (g.max[1] - g.min[1]) * j / (counts[1] - 1),
                      g.min[2] + (g.max[2] - g.min[2]) * k / (counts[2] - 1)};
        g.force_z[GravityVertexIndex(counts, i, j, k)] = f(p);
      }
    }
  }
  return g;
}

/// A trilinear field: trilinear interpolation must reproduce it exactly.
double Trilinear(const Vec3d& p) {
  return 2.0 + 3.0 * p[0] - 1.5 * p[1] + 4.0 * p[2] + 7.0 * p[0] * p[1] - 5.0 * p[1] * p[2] +
         2.5 * p[0] * p[2] + 11.0 * p[0] * p[1] * p[2];
}

std::filesystem::path WriteFile(const std::filesystem::path& dir, const std::string& name,
                                const std::string& text) {
  const auto path = dir / name;
  std::ofstream(path) << text;
  return path;
}

std::string LoadError(const std::filesystem::path& file) {
  try {
    LoadGravityGrid(file);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "no error";
}

DeviceConfig SimConfig() { return LoadDevice("config/devices/sim.yaml"); }

/// The sampler box the bench uses: the workspace shrunk by 5 cm per side.
GravitySamplerConfig SamplerFor(const DeviceConfig& d, int counts) {
  GravitySamplerConfig c;
  for (int a = 0; a < 3; ++a) {
    c.box_min[a] = d.sim.workspace_min[a] + 0.05;
    c.box_max[a] = d.sim.workspace_max[a] - 0.05;
  }
  c.counts = {counts, counts, counts};
  c.device = d.name;
  return c;
}

/// Largest change of the sim's unbalanced weight over 1 mm anywhere in the
/// workspace, N (finite differences on a coarse scan): how much the weight
/// can differ between a vertex and where the arm held still within 1 mm.
double WeightChangePerMillimetre(const SimDevice& dev, const DeviceConfig& d) {
  double worst = 0.0;
  for (int s = 0; s <= 10; ++s) {
    for (int t = 0; t <= 10; ++t) {
      for (int u = 0; u <= 10; ++u) {
        Vec3d p{};
        const std::array<int, 3> n{s, t, u};
        for (int a = 0; a < 3; ++a) {
          p[a] = d.sim.workspace_min[a] +
                 (d.sim.workspace_max[a] - d.sim.workspace_min[a]) * n[a] / 10.0;
        }
        for (int a = 0; a < 3; ++a) {
          Vec3d q = p;
          q[a] += (q[a] + 1e-3 <= d.sim.workspace_max[a]) ? 1e-3 : -1e-3;
          worst = std::max(
              worst, std::abs(dev.UnbalancedMass(q) - dev.UnbalancedMass(p)) * SimDevice::kGravity);
        }
      }
    }
  }
  return worst;
}

/// Every sampled force is within friction (plus margin) of the true weight.
void CheckSampledForces(const SimDevice& dev, const DeviceConfig& d,
                        const GravitySamplerConfig& cfg, const GravitySampleReport& r) {
  REQUIRE(r.ok);
  INFO(r.error);
  REQUIRE(r.vertices.size() == static_cast<size_t>(cfg.counts[0] * cfg.counts[1] * cfg.counts[2]));
  // Margin: held still within 1 mm of the vertex, where the weight differs by
  // at most WeightChangePerMillimetre; and the sampler's damper may carry up to
  // z_damping·speed_tolerance while the arm creeps below 0.5 mm/s.
  const double margin =
      WeightChangePerMillimetre(dev, d) + cfg.z_damping_n_s_m * cfg.speed_tolerance_m_s + 1e-6;
  for (const GravityVertexReport& v : r.vertices) {
    INFO("vertex " << v.index[0] << "," << v.index[1] << "," << v.index[2]);
    CHECK(v.converged);
    CHECK(std::abs(v.z_error_m) <= cfg.position_tolerance_m);
    const double weight = dev.UnbalancedMass(v.target) * SimDevice::kGravity;
    CHECK(std::abs(v.force_n - weight) <= d.sim.coulomb_friction + margin);
    CHECK(r.grid.force_z[GravityVertexIndex(cfg.counts, v.index[0], v.index[1], v.index[2])] ==
          v.force_n);
  }
}

}  // namespace

// ------------------------------------------------------------ interpolation

TEST_CASE("the grid is exact at its vertices") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> force(0.5, 6.0);
  const GravityGridData data = MakeGrid({3, 4, 5}, [&](const Vec3d&) { return force(rng); });
  const GravityGrid grid(data);
  for (int k = 0; k < 5; ++k) {
    for (int j = 0; j < 4; ++j) {
      for (int i = 0; i < 3; ++i) {
        CHECK(grid.Evaluate(grid.Vertex(i, j, k)) ==
              Approx(data.force_z[GravityVertexIndex(data.counts, i, j, k)]).margin(1e-12));
      }
    }
  }
}

TEST_CASE("the grid reproduces a trilinear field anywhere inside the box") {
  const GravityGridData data = MakeGrid({4, 3, 6}, Trilinear);
  const GravityGrid grid(data);
  std::mt19937 rng(5);
  for (int n = 0; n < 500; ++n) {
    Vec3d p{};
    for (int a = 0; a < 3; ++a)
      p[a] = std::uniform_real_distribution<double>(data.min[a], data.max[a])(rng);
    CHECK(grid.Evaluate(p) == Approx(Trilinear(p)).margin(1e-12));
  }
  // A field that is not trilinear is not reproduced between vertices (the test can fail).
  const GravityGrid curved(MakeGrid({3, 3, 3}, [](const Vec3d& p) { return 10.0 * p[0] * p[0]; }));
  CHECK(std::abs(curved.Evaluate({0.0, 0.0, 0.0}) - 0.0) > 1e-3);
}

TEST_CASE("outside the box the force continues from the boundary and fades smoothly to zero") {
  const GravityGridData data =
      MakeGrid({3, 3, 3}, [](const Vec3d& p) { return 3.0 + 2.0 * p[0] + p[2]; });
  const double fade = 0.04;
  const GravityGrid grid(data, fade);
  CHECK(grid.fade_distance() == fade);
  // Boundary points on every face, and a corner.
  const std::vector<std::pair<Vec3d, Vec3d>> boundary_and_outward{
      {{0.3, 0.0, 0.05}, {1, 0, 0}},
      {{-0.1, 0.1, 0.0}, {-1, 0, 0}},
      {{0.1, 0.2, 0.1}, {0, 1, 0}},
      {{0.0, -0.2, 0.1}, {0, -1, 0}},
      {{0.2, 0.0, 0.2}, {0, 0, 1}},
      {{0.2, 0.1, -0.1}, {0, 0, -1}},
      {{0.3, 0.2, 0.2}, {1 / std::sqrt(3.0), 1 / std::sqrt(3.0), 1 / std::sqrt(3.0)}}};
  for (const auto& [b, n] : boundary_and_outward) {
    const double at = grid.Evaluate(b);
    REQUIRE(at > 1.0);
    auto along = [&](double d) {
      return grid.Evaluate({b[0] + d * n[0], b[1] + d * n[1], b[2] + d * n[2]});
    };
    // Continuous across the boundary: no jump from inside to outside.
    CHECK(along(-1e-9) == Approx(at).margin(1e-6));
    CHECK(along(1e-9) == Approx(at).margin(1e-6));
    // Half way: smoothstep(0.5) = 0.5.
    CHECK(along(fade / 2) == Approx(at / 2).epsilon(1e-9));
    // Zero from fade_distance on.
    CHECK(along(fade) == 0.0);
    CHECK(along(fade * 3) == 0.0);
    // Monotone, and small near the end (the slope of smoothstep is 0 at both ends).
    double previous = at;
    for (int s = 1; s <= 100; ++s) {
      const double v = along(fade * s / 100.0);
      CHECK(v <= previous + 1e-12);
      previous = v;
    }
    CHECK(along(fade * 0.99) < 1e-3 * at);
    CHECK(along(fade * 0.01) > 0.999 * at);
  }
  // Outside a face only the one coordinate is clamped: the value is the
  // interpolated one at the nearest boundary point, faded by distance.
  CHECK(grid.Evaluate({0.17, 0.22, 0.13}) ==
        Approx(grid.Evaluate({0.17, 0.2, 0.13}) * 0.5).epsilon(1e-9));
}

TEST_CASE("a position that is not finite gets no force") {
  const GravityGrid grid(MakeGrid({2, 2, 2}, [](const Vec3d&) { return 2.0; }));
  CHECK(grid.Evaluate({std::nan(""), 0.0, 0.0}) == 0.0);
  CHECK(grid.Evaluate({0.0, INFINITY, 0.0}) == 0.0);
  CHECK(grid.Evaluate({0.0, 0.0, 0.0}) == 2.0);
}

TEST_CASE("evaluating the grid allocates nothing") {
  const GravityGrid grid(MakeGrid({5, 5, 5}, Trilinear));
  double sum = 0.0;
  const uint64_t before = haptel::test::ThreadAllocations();
  for (int n = 0; n < 10000; ++n) {
    const double s = n / 10000.0;
    sum += grid.Evaluate({-0.2 + 0.6 * s, -0.3 + 0.6 * s, -0.2 + 0.5 * s});  // inside and outside
  }
  const uint64_t after = haptel::test::ThreadAllocations();
  CHECK(after == before);
  CHECK(std::isfinite(sum));
  // The counter does see allocations on this thread (so the check above can fail).
  const GravityGrid copy(grid.data());
  CHECK(haptel::test::ThreadAllocations() > after);
}

TEST_CASE("an invalid grid is refused") {
  GravityGridData ok = MakeGrid({2, 2, 2}, [](const Vec3d&) { return 1.0; });
  CHECK_NOTHROW(GravityGrid(ok));
  GravityGridData g = ok;
  g.counts = {1, 2, 2};
  CHECK_THROWS_AS(GravityGrid(g), std::invalid_argument);
  g = ok;
  g.force_z.pop_back();
  CHECK_THROWS_WITH(GravityGrid(g), Contains("force_z") && Contains("expected 8"));
  g = ok;
  g.force_z[3] = std::nan("");
  CHECK_THROWS_WITH(GravityGrid(g), Contains("force_z[3]"));
  g = ok;
  g.max[1] = g.min[1];
  CHECK_THROWS_AS(GravityGrid(g), std::invalid_argument);
  CHECK_THROWS_AS(GravityGrid(ok, 0.0), std::invalid_argument);
  CHECK_THROWS_AS(GravityGrid(ok, std::nan("")), std::invalid_argument);
}

// -------------------------------------------------------------- grid file

TEST_CASE("a grid file round-trips bit for bit and its folders are created") {
  const auto dir = haptel::test::ScratchDir("gravity-file");
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> force(-1.0, 7.0);
  GravityGridData data = MakeGrid({3, 2, 4}, [&](const Vec3d&) { return force(rng); });
  data.min = {-0.123456789012345, -0.2, 0.1 / 3.0};
  data.force_z[5] = 1.0 / 3.0;
  const auto file = dir / "a" / "b" / "grid.yaml";
  SaveGravityGrid(file, data);
  const GravityGridData back = LoadGravityGrid(file);
  CHECK(back.device == data.device);
  CHECK(back.min == data.min);
  CHECK(back.max == data.max);
  CHECK(back.counts == data.counts);
  CHECK(back.force_z == data.force_z);  // exact: full precision

  // The device name is optional.
  data.device.clear();
  SaveGravityGrid(dir / "nameless.yaml", data);
  CHECK(LoadGravityGrid(dir / "nameless.yaml").device.empty());

  // An invalid grid is not written.
  data.counts = {3, 2, 5};
  CHECK_THROWS_AS(SaveGravityGrid(dir / "bad.yaml", data), std::invalid_argument);
  CHECK_FALSE(std::filesystem::exists(dir / "bad.yaml"));
}

TEST_CASE("a grid file is read strictly; errors name file, key and line") {
  const auto dir = haptel::test::ScratchDir("gravity-strict");
  const std::string good =
      "device: sim\n"
      "min: [0, 0, 0]\n"
      "max: [1, 1, 1]\n"
      "counts: [2, 2, 2]\n"
      "force_z: [1, 2, 3, 4, 5, 6, 7, 8]\n";
  const GravityGridData g = LoadGravityGrid(WriteFile(dir, "good.yaml", good));
  CHECK(g.force_z[GravityVertexIndex(g.counts, 1, 0, 1)] == 6.0);

  auto error_for = [&](const std::string& name, const std::string& text) {
    return LoadError(WriteFile(dir, name, text));
  };
  std::string e = error_for("unknown.yaml", good + "colour: blue\n");
  CHECK_THAT(e, Contains("unknown.yaml:6:") && Contains("'colour'") && Contains("unknown key"));

  e = error_for(
      "count.yaml",
      "min: [0, 0, 0]\nmax: [1, 1, 1]\ncounts: [2, 2, 2]\nforce_z: [1, 2, 3, 4, 5, 6, 7]\n");
  CHECK_THAT(e, Contains("count.yaml:4:") && Contains("'force_z'") && Contains("8 forces") &&
                    Contains("got 7"));

  e = error_for(
      "nan.yaml",
      "min: [0, 0, 0]\nmax: [1, 1, 1]\ncounts: [2, 2, 2]\nforce_z:\n  - 1\n  - 2\n  - .nan\n  - 4\n"
      "  - 5\n  - 6\n  - 7\n  - 8\n");
  CHECK_THAT(e, Contains("nan.yaml:7:") && Contains("'force_z[2]'") && Contains("finite number"));

  e = error_for(
      "word.yaml",
      "min: [0, 0, 0]\nmax: [1, 1, 1]\ncounts: [2, 2, 2]\nforce_z: [1, 2, x, 4, 5, 6, 7, 8]\n");
  CHECK_THAT(e, Contains("word.yaml:4:") && Contains("'force_z[2]'") && Contains("got 'x'"));

  e = error_for("one.yaml",
                "min: [0, 0, 0]\nmax: [1, 1, 1]\ncounts: [1, 2, 2]\nforce_z: [1, 2, 3, 4]\n");
  CHECK_THAT(e, Contains("one.yaml:3:") && Contains("'counts'") && Contains("[2, 1000]"));

  e = error_for("half.yaml",
                "min: [0, 0, 0]\nmax: [1, 1, 1]\ncounts: [2, 2.5, 2]\nforce_z: [1, 2, 3, 4]\n");
  CHECK_THAT(e, Contains("half.yaml:3:") && Contains("whole numbers"));

  e = error_for(
      "box.yaml",
      "min: [0, 0, 0]\nmax: [1, 0, 1]\ncounts: [2, 2, 2]\nforce_z: [1, 2, 3, 4, 5, 6, 7, 8]\n");
  CHECK_THAT(e, Contains("box.yaml:2:") && Contains("'max'") && Contains("greater than 'min'"));

  e = error_for("missing.yaml",
                "min: [0, 0, 0]\nmax: [1, 1, 1]\nforce_z: [1, 2, 3, 4, 5, 6, 7, 8]\n");
  CHECK_THAT(e, Contains("missing.yaml") && Contains("'counts'") && Contains("missing"));

  e = error_for("scalar.yaml", "min: [0, 0, 0]\nmax: [1, 1, 1]\ncounts: [2, 2, 2]\nforce_z: 3\n");
  CHECK_THAT(e,
             Contains("scalar.yaml:4:") && Contains("'force_z'") && Contains("a list of 8 forces"));

  CHECK_THAT(LoadError(dir / "absent.yaml"), Contains("absent.yaml") && Contains("cannot open"));
}

// ----------------------------------------------------------- decision table

TEST_CASE("the decision table nudges the force towards holding the arm on target") {
  // Moving away from the target: a lot against the motion.
  CHECK(Decide(ZPosition::kAbove, ZMotion::kUp) == ForceStep::kLowerALot);
  CHECK(Decide(ZPosition::kBelow, ZMotion::kDown) == ForceStep::kRaiseALot);
  // Stuck off target: a little towards it.
  CHECK(Decide(ZPosition::kAbove, ZMotion::kStill) == ForceStep::kLowerALittle);
  CHECK(Decide(ZPosition::kBelow, ZMotion::kStill) == ForceStep::kRaiseALittle);
  // Drifting back by itself: leave it.
  CHECK(Decide(ZPosition::kAbove, ZMotion::kDown) == ForceStep::kHold);
  CHECK(Decide(ZPosition::kBelow, ZMotion::kUp) == ForceStep::kHold);
  // On target: a little against any motion, hold when still.
  CHECK(Decide(ZPosition::kAt, ZMotion::kUp) == ForceStep::kLowerALittle);
  CHECK(Decide(ZPosition::kAt, ZMotion::kDown) == ForceStep::kRaiseALittle);
  CHECK(Decide(ZPosition::kAt, ZMotion::kStill) == ForceStep::kHold);
  // Above the target the force never rises, below it never falls.
  for (const ZMotion m : {ZMotion::kUp, ZMotion::kStill, ZMotion::kDown}) {
    CHECK(StepNewtons(Decide(ZPosition::kAbove, m), 0.02, 0.25) <= 0.0);
    CHECK(StepNewtons(Decide(ZPosition::kBelow, m), 0.02, 0.25) >= 0.0);
  }
  CHECK(StepNewtons(ForceStep::kLowerALot, 0.02, 0.25) == -0.25);
  CHECK(StepNewtons(ForceStep::kRaiseALittle, 0.02, 0.25) == 0.02);
  CHECK(StepNewtons(ForceStep::kHold, 0.02, 0.25) == 0.0);
}

TEST_CASE("the arm's state is classified with the sampling tolerances") {
  CHECK(ClassifyPosition(0.0011, 1e-3) == ZPosition::kAbove);
  CHECK(ClassifyPosition(0.001, 1e-3) == ZPosition::kAt);
  CHECK(ClassifyPosition(-0.001, 1e-3) == ZPosition::kAt);
  CHECK(ClassifyPosition(-0.0011, 1e-3) == ZPosition::kBelow);
  CHECK(ClassifyMotion(0.0005, 0.5e-3) == ZMotion::kUp);
  CHECK(ClassifyMotion(0.0004, 0.5e-3) == ZMotion::kStill);
  CHECK(ClassifyMotion(-0.0004, 0.5e-3) == ZMotion::kStill);
  CHECK(ClassifyMotion(-0.0005, 0.5e-3) == ZMotion::kDown);
}

// ------------------------------------------------------------------ sampler

TEST_CASE(
    "the sampler converges at every vertex of the sim arm, within friction of the true weight") {
  const DeviceConfig d = SimConfig();
  SimDevice dev(d, OperatorConfig{});
  const ArmCalibration cal = bench::SimTruthCalibration(dev, Side::kRight);
  const GravitySamplerConfig cfg = SamplerFor(d, 3);
  const GravitySampleReport r = SampleGravityOnSim(dev, Side::kRight, cal, cfg);
  CheckSampledForces(dev, d, cfg, r);
  CHECK(r.error.empty());
  CHECK(r.grid.device == "sim");
  CHECK_NOTHROW(r.grid.ValidateOrThrow());
  double total = 0.0;
  for (const GravityVertexReport& v : r.vertices) {
    CHECK(v.sim_time_s >= cfg.hold_s);  // the 1 s hold is part of every vertex
    total += v.sim_time_s;
  }
  CHECK(r.sim_time_s == Approx(total).margin(0.01 * r.vertices.size()));
  // Snake order: each vertex is a neighbour of the one before; all are visited once.
  std::set<std::array<int, 3>> seen;
  for (size_t n = 0; n < r.vertices.size(); ++n) {
    seen.insert(r.vertices[n].index);
    if (n == 0) continue;
    int steps = 0;
    for (int a = 0; a < 3; ++a)
      steps += std::abs(r.vertices[n].index[a] - r.vertices[n - 1].index[a]);
    CHECK(steps == 1);
  }
  CHECK(seen.size() == 27);
  // Each vertex after the first starts from the force found at the one before.
  for (size_t n = 1; n < r.vertices.size(); ++n)
    CHECK(r.vertices[n].start_force_n == r.vertices[n - 1].force_n);
  CHECK(r.vertices[0].start_force_n == cfg.initial_force_n);
}

TEST_CASE("the sampler converges over a range of arm physics") {
  struct Variant {
    const char* name;
    double friction, mass, encoder;
  };
  for (const Variant& v :
       {Variant{"little friction", 0.05, 0.8, 60e-6}, Variant{"heavy arm", 0.3, 2.0, 60e-6},
        Variant{"coarse encoder", 0.3, 0.8, 200e-6}, Variant{"much friction", 0.6, 0.8, 60e-6}}) {
    INFO(v.name);
    DeviceConfig d = SimConfig();
    d.sim.coulomb_friction = v.friction;
    d.sim.arm_mass = v.mass;
    d.sim.encoder_resolution = v.encoder;
    SimDevice dev(d, OperatorConfig{});
    const GravitySamplerConfig cfg = SamplerFor(d, 3);
    const GravitySampleReport r =
        SampleGravityOnSim(dev, Side::kLeft, bench::SimTruthCalibration(dev, Side::kLeft), cfg);
    CheckSampledForces(dev, d, cfg, r);
  }
}

TEST_CASE("a vertex the device cannot hold fails clearly after its timeout") {
  DeviceConfig d = SimConfig();
  d.sim.force_limit = 1.0;  // well below the arm's weight anywhere
  SimDevice dev(d, OperatorConfig{});
  GravitySamplerConfig cfg = SamplerFor(d, 2);
  cfg.vertex_timeout_s = 5.0;
  const GravitySampleReport r =
      SampleGravityOnSim(dev, Side::kRight, bench::SimTruthCalibration(dev, Side::kRight), cfg);
  CHECK_FALSE(r.ok);
  CHECK_THAT(r.error, Contains("vertex 1 of 8") && Contains("(0,0,0)") &&
                          Contains("did not hold still within 5.0 s"));
  REQUIRE(r.vertices.size() == 1);
  CHECK_FALSE(r.vertices[0].converged);
  CHECK(r.sim_time_s == Approx(5.0).margin(0.01));
  CHECK(dev.TruePosition(Side::kRight)[2] ==
        Approx(d.sim.workspace_min[2]));  // it fell to the floor
}

TEST_CASE("a lost device stops the sampler with zero force") {
  const DeviceConfig d = SimConfig();
  SimDevice dev(d, OperatorConfig{});
  const ArmCalibration cal = bench::SimTruthCalibration(dev, Side::kRight);
  GravitySampler sampler(dev, Side::kRight, cal, SamplerFor(d, 2), [&](const Vec3d& v) {
    dev.Place(Side::kRight, v);
    dev.Release(Side::kRight);
  });
  int64_t now = 1'000'000;
  for (int i = 0; i < 100; ++i, now += 1'000'000) REQUIRE(sampler.Tick(now));
  dev.SetLost(Side::kRight, true);
  CHECK_FALSE(sampler.Tick(now));
  CHECK(sampler.finished());
  CHECK_FALSE(sampler.report().ok);
  CHECK_THAT(sampler.report().error, Contains("lost") && Contains("vertex 1 of 8"));
  dev.SetLost(Side::kRight, false);
  CHECK_FALSE(sampler.Tick(now + 1'000'000));
  // Nothing holds the arm any more: it falls.
  const double z = dev.TruePosition(Side::kRight)[2];
  WristRaw raw;
  for (int i = 2; i <= 200; ++i) dev.ReadWrist(Side::kRight, now + i * 1'000'000, raw);
  CHECK(dev.TruePosition(Side::kRight)[2] < z - 0.005);
}

TEST_CASE("an unusable sampler configuration is refused") {
  const DeviceConfig d = SimConfig();
  SimDevice dev(d, OperatorConfig{});
  const ArmCalibration cal = bench::SimTruthCalibration(dev, Side::kRight);
  auto make = [&](const GravitySamplerConfig& c) {
    GravitySampler s(dev, Side::kRight, cal, c, [](const Vec3d&) {});
  };
  GravitySamplerConfig c = SamplerFor(d, 3);
  CHECK_NOTHROW(make(c));
  c.counts[1] = 1;
  CHECK_THROWS_AS(make(c), std::invalid_argument);
  c = SamplerFor(d, 3);
  c.box_max[2] = c.box_min[2];
  CHECK_THROWS_AS(make(c), std::invalid_argument);
  c = SamplerFor(d, 3);
  c.vertex_timeout_s = 0.5;  // shorter than the 1 s hold
  CHECK_THROWS_AS(make(c), std::invalid_argument);
  c = SamplerFor(d, 3);
  c.large_step_n = c.small_step_n / 2;
  CHECK_THROWS_AS(make(c), std::invalid_argument);
  ArmCalibration bad = cal;
  bad.force_slope[2] = 0.0;
  CHECK_THROWS_AS(GravitySampler(dev, Side::kRight, bad, SamplerFor(d, 3), [](const Vec3d&) {}),
                  std::invalid_argument);
  CHECK_THROWS_AS(GravitySampler(dev, Side::kRight, cal, SamplerFor(d, 3), nullptr),
                  std::invalid_argument);
}

// -------------------------------------------------------- the whole point

TEST_CASE("with the sampled grid a released arm drifts far less than without") {
  const DeviceConfig d = SimConfig();
  SimDevice dev(d, OperatorConfig{});
  const ArmCalibration cal = bench::SimTruthCalibration(dev, Side::kRight);
  const GravitySamplerConfig cfg = SamplerFor(d, 3);
  const GravitySampleReport r = SampleGravityOnSim(dev, Side::kRight, cal, cfg);
  REQUIRE(r.ok);
  const GravityGrid grid(r.grid);
  std::mt19937 rng(7);
  int64_t now = r.end_ns;
  double off = 0.0, on = 0.0;
  for (int n = 0; n < 6; ++n) {
    Vec3d p{};
    for (int a = 0; a < 3; ++a)
      p[a] = std::uniform_real_distribution<double>(cfg.box_min[a], cfg.box_max[a])(rng);
    const double drift_off = bench::MeasureDrift(dev, Side::kRight, cal, nullptr, p, 1.0, now);
    const double drift_on = bench::MeasureDrift(dev, Side::kRight, cal, &grid, p, 1.0, now);
    INFO("point " << n << ": off " << drift_off * 1e3 << " mm/s, on " << drift_on * 1e3 << " mm/s");
    CHECK(drift_off > 0.01);  // uncompensated, the arm falls
    off += drift_off;
    on += drift_on;
  }
  INFO("mean off " << off / 6 * 1e3 << " mm/s, mean on " << on / 6 * 1e3 << " mm/s");
  CHECK(on * 5.0 < off);
  // A grid of zeros compensates nothing (the comparison above can fail).
  GravityGridData zero = r.grid;
  std::fill(zero.force_z.begin(), zero.force_z.end(), 0.0);
  const GravityGrid none(zero);
  const Vec3d p{0.05, 0.0, 0.05};
  CHECK(bench::MeasureDrift(dev, Side::kRight, cal, &none, p, 1.0, now) ==
        Approx(bench::MeasureDrift(dev, Side::kRight, cal, nullptr, p, 1.0, now)));
}

TEST_CASE("haptel bench gravity refuses bad usage") {
  const char* unknown[] = {"gravity", "--frobnicate"};
  CHECK(bench::BenchGravityMain(2, unknown) == 2);
  const char* zero_points[] = {"gravity", "--points", "0"};
  CHECK(bench::BenchGravityMain(3, zero_points) == 2);
  const char* no_file[] = {"gravity", "--device", "no/such/device.yaml"};
  CHECK(bench::BenchGravityMain(3, no_file) == 2);
}

TEST_CASE("an invalid grid is refused with the key GravityGridData::ValidateOrThrow names") {
  GravityGridData g = MakeGrid({2, 2, 2}, [](const Vec3d&) { return 1.0; });
  g.counts = {2, 1, 2};
  CHECK_THROWS_AS(GravityGrid(g), ConfigFieldError);
  CHECK_THROWS_WITH(GravityGrid(g),
                    Contains("counts: expected a list of 3 whole numbers in [2, 1000]"));
}

// ------------------------------------------- haptel calibrate --gravity

namespace {
/// `haptel calibrate` with these words; its stderr, when `err` is given.
int Calibrate(std::vector<std::string> words, std::string* err = nullptr) {
  words.insert(words.begin(), "haptel");
  std::vector<const char*> argv;
  for (const std::string& w : words) argv.push_back(w.c_str());
  const auto capture = test::ScratchDir("calibrate-gravity-stderr") / "stderr.txt";
  std::fflush(stderr);
  const int saved = dup(2);
  const int file = open(capture.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  dup2(file, 2);
  const int code = CalibrateMain(static_cast<int>(argv.size()), argv.data());
  std::fflush(stderr);
  std::cerr.flush();
  dup2(saved, 2);
  close(saved);
  close(file);
  if (err != nullptr) {
    std::ifstream in(capture);
    *err = std::string(std::istreambuf_iterator<char>(in), {});
  }
  return code;
}
}  // namespace

TEST_CASE(
    "haptel calibrate --gravity samples the sim device's grid and writes it where the device file "
    "names it; the grid loads and compensates") {
  const auto dir = test::ScratchDir("calibrate-gravity");
  const auto grid_file = dir / "grids" / "sim-gravity.yaml";
  std::ifstream shipped("config/devices/sim.yaml");
  const std::string sim_yaml(std::istreambuf_iterator<char>(shipped), {});
  const auto device_file =
      test::WriteFile(dir / "sim.yaml", sim_yaml + "gravity: " + grid_file.string() + "\n");
  std::string err;
  REQUIRE(Calibrate({"calibrate", "--gravity", "--auto", "--device", device_file.string(),
                     "--counts", "2"},
                    &err) == 0);
  INFO(err);
  const GravityGridData data = LoadGravityGrid(grid_file);
  CHECK(data.counts == std::array<int, 3>{2, 2, 2});
  CHECK(data.device == "sim");

  // As haptel bench gravity checks it: released in the box, the arm drifts
  // far less with the grid's force than with none.
  const DeviceConfig d = LoadDevice(device_file);
  SimDevice dev(d, OperatorConfig{});
  const ArmCalibration cal = bench::SimTruthCalibration(dev, Side::kRight);
  const GravityGrid grid(data);
  int64_t now = 1'000'000;
  double off = 0.0, on = 0.0;
  for (const Vec3d& p : {Vec3d{0.0, -0.1, 0.0}, Vec3d{0.15, 0.1, 0.1}, Vec3d{0.05, 0.0, -0.05}}) {
    off += bench::MeasureDrift(dev, Side::kRight, cal, nullptr, p, 1.0, now);
    on += bench::MeasureDrift(dev, Side::kRight, cal, &grid, p, 1.0, now);
  }
  INFO("drift off " << off / 3 * 1e3 << " mm/s, on " << on / 3 * 1e3 << " mm/s");
  CHECK(off > 0.03);
  CHECK(on * 5.0 < off);

  // --out writes elsewhere, whatever the device file names.
  const auto elsewhere = dir / "elsewhere.yaml";
  REQUIRE(Calibrate({"calibrate", "--gravity", "--auto", "--counts", "2", "--out",
                     elsewhere.string()}) == 0);
  CHECK(LoadGravityGrid(elsewhere).counts == std::array<int, 3>{2, 2, 2});
}

TEST_CASE("haptel calibrate --gravity says which key is missing, and refuses bad usage") {
  const auto dir = test::ScratchDir("calibrate-gravity-bad");
  std::string err;
  // The shipped sim.yaml names no grid file: nothing to write to.
  CHECK(Calibrate({"calibrate", "--gravity", "--auto"}, &err) == 2);
  CHECK_THAT(err, Contains("sim.yaml: key 'gravity'") && Contains("--out"));
  CHECK(Calibrate({"calibrate", "--gravity", "--auto", "--counts", "1", "--out",
                   (dir / "g.yaml").string()},
                  &err) == 2);
  CHECK(Calibrate({"calibrate", "--auto", "--counts", "3"}, &err) == 2);
  CHECK_THAT(err, Contains("--counts goes with --gravity"));
  // A real device is sampled through its measured calibration: none named.
  const auto udp = test::WriteFile(dir / "udp.yaml",
                                   "name: exo\ndriver: udp\ngravity: " + (dir / "g.yaml").string() +
                                       "\nudp:\n  left: {port: 5000}\n  right: {port: 5001}\n");
  CHECK(Calibrate({"calibrate", "--gravity", "--device", udp.string()}, &err) != 0);
  CHECK_THAT(err, Contains("key 'calibration'"));
  CHECK_FALSE(std::filesystem::exists(dir / "g.yaml"));
}
