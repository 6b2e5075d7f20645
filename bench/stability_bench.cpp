#include "stability_bench.hpp"

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "haptel/config/paths.hpp"
#include "haptel/config/physics.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/json.hpp"
#include "haptel/physics/world.hpp"
#include "haptel/testing/box_grip.hpp"
#include "haptel/testing/vec_math.hpp"
#include "plot.hpp"
#include "smoke.hpp"

namespace haptel::bench {

namespace {

using haptics::AxisAngle;
using haptics::Distance;
using haptics::HandSample;
using haptics::Side;
using physics::PhysicsWorld;
using physics::Vec3d;

double Norm(const btVector3& v) { return v.length(); }

uint64_t Resets(const PhysicsWorld& world) {
  const physics::PhysicsCounters c = world.Counters();
  return c.hand_resets + c.body_resets;
}

/// Deepest current contact (m, > 0 = overlap) between `a` and `b` (any other
/// body when `b` is null), from Bullet's contact manifolds.
double Penetration(PhysicsWorld& world, const btCollisionObject* a, const btCollisionObject* b) {
  btDispatcher& d = *world.bullet().getDispatcher();
  double worst = 0.0;
  for (int i = 0; i < d.getNumManifolds(); ++i) {
    const btPersistentManifold& m = *d.getManifoldByIndexInternal(i);
    const btCollisionObject* x = m.getBody0();
    const btCollisionObject* y = m.getBody1();
    const bool match = (x == a && (b == nullptr || y == b)) || (y == a && (b == nullptr || x == b));
    if (!match) continue;
    for (int k = 0; k < m.getNumContacts(); ++k)
      worst = std::max(worst, -m.getContactPoint(k).getDistance());
  }
  return worst;
}

/// Force (N) that the bodies of `hand` exert on `target` in the latest step:
/// the contact points' normal and friction impulses over the step.
btVector3 ContactForce(PhysicsWorld& world, physics::ProxyHand& hand,
                       const btCollisionObject* target) {
  std::vector<const btCollisionObject*> bodies{&hand.palm_body()};
  for (int f = 0; f < physics::kFingers; ++f) {
    for (int p = 0; p < physics::kPhalanges; ++p) bodies.push_back(&hand.phalanx_body(f, p));
  }
  btDispatcher& d = *world.bullet().getDispatcher();
  btVector3 impulse(0, 0, 0);
  for (int i = 0; i < d.getNumManifolds(); ++i) {
    const btPersistentManifold& m = *d.getManifoldByIndexInternal(i);
    const bool target_is_a = m.getBody0() == target;
    if (!target_is_a && m.getBody1() != target) continue;
    const btCollisionObject* other = target_is_a ? m.getBody1() : m.getBody0();
    if (std::find(bodies.begin(), bodies.end(), other) == bodies.end()) continue;
    for (int k = 0; k < m.getNumContacts(); ++k) {
      const btManifoldPoint& p = m.getContactPoint(k);
      // Impulses act on body A along +normal (the normal points from B to A).
      const btVector3 on_a = p.m_normalWorldOnB * p.getAppliedImpulse() +
                             p.m_lateralFrictionDir1 * p.m_appliedImpulseLateral1 +
                             p.m_lateralFrictionDir2 * p.m_appliedImpulseLateral2;
      impulse += target_is_a ? on_a : -on_a;
    }
  }
  return impulse / world.config().step_s;
}

/// Kinetic + gravitational energy of every dynamic body (hands included; a
/// body's own gravity, so a weightless proxy hand has kinetic energy only).
double MechanicalEnergy(PhysicsWorld& world) {
  double e = 0.0;
  const btCollisionObjectArray& objects = world.bullet().getCollisionObjectArray();
  for (int i = 0; i < objects.size(); ++i) {
    const btRigidBody* body = btRigidBody::upcast(objects[i]);
    if (body == nullptr || body->isStaticOrKinematicObject() || body->getInvMass() == 0.0) continue;
    const double m = 1.0 / body->getInvMass();
    const btVector3 v = body->getLinearVelocity();
    const btVector3 w = body->getAngularVelocity();
    const btVector3 iw = body->getInvInertiaTensorWorld().inverse() * w;
    e += 0.5 * m * v.length2() + 0.5 * w.dot(iw) -
         m * body->getGravity().dot(body->getWorldTransform().getOrigin());
  }
  return e;
}

// --------------------------------------------------------------- stiffness
struct StiffRun {
  double k = 0.0;
  bool stable = false;
  std::string why;         ///< the failed criterion, empty when stable
  double k_eff = 0.0;      ///< N/m measured under a 1 N push
  double max_error = 0.0;  ///< m
};

struct StiffRow {
  double step_s = 0.0;
  double k_max = 0.0;   ///< largest stable K (0: none)
  bool capped = false;  ///< no divergence up to the sweep's cap
  double k_eff_at_max = 0.0;
  double k_passive = 0.0;
  double k_clamp = 0.0;     ///< Bullet: k ≤ m/(16h²)
  double k_implicit = 0.0;  ///< the hand's soft lock from here on
  std::string first_failure;
  std::string regime_at_max;
  std::vector<StiffRun> runs;
};

constexpr double kStiffCap = 1.4e7;

StiffRun RunStiffness(const PhysicsConfig& base, double h, double k) {
  PhysicsConfig config = base;
  config.step_s = h;
  config.gravity = {0.0, 0.0, 0.0};
  config.hand.gravity = false;
  config.hand.coupling_linear_stiffness = k;
  PhysicsWorld world(config);
  physics::ProxyHand& hand = world.AddHand(Side::kRight);
  btRigidBody& palm = hand.palm_body();
  const double m = config.hand.palm_mass;
  StiffRun r;
  r.k = k;
  const long n = std::lround(2.0 / h);
  double e_hold_start = 0.0, e_hold_end = 0.0, offset_sum = 0.0;
  long offset_n = 0;
  const Vec3d home{0.0, 0.0, 0.2};
  for (long i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * h;
    Vec3d target = home;
    if (t >= 0.5) target[0] += 0.02;  // a 2 cm jump
    hand.SetTracked(haptics::TrackedHand(target));
    const bool push = t >= 1.0 && t < 1.5;
    if (push) {
      palm.activate();
      palm.applyCentralForce(btVector3(1.0, 0.0, 0.0));
    }
    world.Step();
    const Vec3d p = hand.ProxyWrist().position;
    const btVector3 e(p[0] - target[0], p[1] - target[1], p[2] - target[2]);
    r.max_error = std::max(r.max_error, Norm(e));
    if (!std::isfinite(r.max_error) || Resets(world) > 0) {
      r.why = "NaN reset";
      return r;
    }
    if (r.max_error > 0.10) {
      r.why = "error > 10 cm";
      return r;
    }
    if (push && t >= 1.3) {
      offset_sum += e.x();
      ++offset_n;
    }
    // Palm energy relative to the (now still) target while held free.
    const double energy = 0.5 * m * palm.getLinearVelocity().length2() + 0.5 * k * e.length2();
    if (t >= 1.5 && t < 1.6) e_hold_start = std::max(e_hold_start, energy);
    if (t >= 1.9) e_hold_end = std::max(e_hold_end, energy);
  }
  const double offset = offset_n > 0 ? offset_sum / static_cast<double>(offset_n) : 0.0;
  r.k_eff = offset > 0.0 ? 1.0 / offset : 0.0;
  if (e_hold_end > 1.01 * e_hold_start + 1e-9) {
    r.why = "energy growth";
    return r;
  }
  r.stable = true;
  return r;
}

std::string Regime(const PhysicsConfig& c, double h, double k) {
  const double m = c.hand.palm_mass, b = c.hand.coupling_linear_damping;
  if (m / (h * (h * k + b)) <= 0.5) return "implicit";
  if (std::sqrt(k / m) * h > 0.25 || b * h > m) return "bullet-clamped";
  return "bullet-spring";
}

/// The step sizes the stiffness sweep visits: all, or a smoke run's two.
const std::vector<double> kStiffSteps{0.25e-3, 0.5e-3, 1e-3, 2e-3, 4e-3};
const std::vector<double> kStiffStepsSmoke{1e-3, 4e-3};

std::vector<StiffRow> StiffnessSweep(const PhysicsConfig& config,
                                     const std::vector<double>& steps) {
  std::vector<StiffRow> rows;
  const double m = config.hand.palm_mass, b = config.hand.coupling_linear_damping;
  for (const double h : steps) {
    StiffRow row;
    row.step_s = h;
    row.k_passive = 2.0 * b / h;
    row.k_clamp = m / (16.0 * h * h);
    row.k_implicit = std::max(0.0, (2.0 * m / h - b) / h);
    row.capped = true;
    for (double k = 1e2; k <= kStiffCap; k *= 2.0) {
      StiffRun run = RunStiffness(config, h, k);
      row.runs.push_back(run);
      if (!run.stable) {
        row.capped = false;
        row.first_failure = run.why;
        break;
      }
      row.k_max = k;
      row.k_eff_at_max = run.k_eff;
    }
    row.regime_at_max = row.k_max > 0.0 ? Regime(config, h, row.k_max) : "-";
    rows.push_back(row);
  }
  return rows;
}

// -------------------------------------------------------------- mass ratio
struct MassRow {
  double light = 0.009, heavy = 0.0;
  double pen_rest = 0.0, pen_pressed = 0.0;
  double max_speed = 0.0;
  double spin_rest = 0.0, spin_pressed = 0.0;  ///< rad/s, max |ω| about the axis after settling
  uint64_t resets = 0;
  bool on_box = true;
  bool passed = false;
};
constexpr double kMassPenLimit = 0.003;
/// Pushed through its centre, the capsule feels no torque about its axis: any
/// roll is the solver's. 0.1 rad/s rolls the 8 mm capsule 0.8 mm/s, a creep the
/// operator sees within seconds (the contact without rolling friction reached
/// 0.6 rad/s resting and tens of rad/s pressed, then rolled off the box).
constexpr double kMassSpinLimit = 0.1;

MassRow RunMassRatio(const PhysicsConfig& config, double heavy) {
  MassRow r;
  r.heavy = heavy;
  PhysicsWorld world(config);
  world.AddStaticPlane({0, 0, 1}, 0.0);
  const double half = 0.1;
  const physics::BodyId box = world.AddDynamicBox({0, 0, half}, {half, half, half}, heavy);
  const double radius = config.hand.phalanx_radius;
  const double length = config.hand.phalanx_length[2];
  auto shape = std::make_unique<btCapsuleShapeX>(radius, length - 2.0 * radius);
  btVector3 inertia;
  shape->calculateLocalInertia(r.light, inertia);
  physics::Pose pose;
  pose.position = {0.0, 0.0, 2.0 * half + radius};
  // A distal phalanx: its shape, mass and the hand's material (rolling friction included).
  const physics::BodyId cap =
      world.AddRigidBody(std::move(shape), {}, r.light, {inertia.x(), inertia.y(), inertia.z()},
                         pose, config.hand.material);
  btRigidBody& c = world.body(cap);
  btRigidBody& bx = world.body(box);
  c.setActivationState(DISABLE_DEACTIVATION);
  bx.setActivationState(DISABLE_DEACTIVATION);
  const double h = config.step_s;
  const long n = std::lround(5.0 / h);
  for (long i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * h;
    const bool pressed = t >= 2.5;
    if (pressed) c.applyCentralForce(btVector3(0.0, 0.0, -5.0));
    world.Step();
    const double pen = Penetration(world, &c, &bx);
    (pressed ? r.pen_pressed : r.pen_rest) = std::max(pressed ? r.pen_pressed : r.pen_rest, pen);
    r.max_speed = std::max(r.max_speed, Norm(c.getLinearVelocity()));
    // Roll about the capsule's own axis, after the 0.5 s the first contact takes to settle.
    const double spin =
        std::abs(c.getAngularVelocity().dot(c.getWorldTransform().getBasis().getColumn(0)));
    if (t >= 0.5)
      (pressed ? r.spin_pressed : r.spin_rest) =
          std::max(pressed ? r.spin_pressed : r.spin_rest, spin);
    const Vec3d p = world.BodyPose(cap).position;
    const Vec3d q = world.BodyPose(box).position;
    if (!(std::abs(p[0] - q[0]) < half && std::abs(p[1] - q[1]) < half &&
          p[2] > q[2] + half - 0.01 && p[2] < q[2] + half + 0.05)) {
      r.on_box = false;
    }
  }
  r.resets = Resets(world);
  r.passed = r.resets == 0 && r.on_box && r.pen_rest < kMassPenLimit &&
             r.pen_pressed < kMassPenLimit && r.spin_rest < kMassSpinLimit &&
             r.spin_pressed < kMassSpinLimit;
  return r;
}

// ------------------------------------------------------------------ squash
struct SquashResult {
  double k = 0.0;
  double force_asked = 0.0;  ///< N, K·depth at the end of the ramp
  /// N, over the last 1 s (held at force_asked): mean and minimum of the
  /// squeeze each hand's contacts put on the box (along y, the smaller of the
  /// two hands), and the coupling spring's mean force K·(tracked − proxy).
  double contact_mean = 0.0, contact_min = 0.0, coupling_mean = 0.0;
  double speed_to_7n = 0.0, speed_to_50n = 0.0;
  double pen_to_7n = 0.0, pen_to_50n = 0.0;
  double box_drift = 0.0;  ///< max distance of the box from where it started
  bool between = true;
  uint64_t resets = 0;
  bool passed = false;
};
constexpr double kSquashSpeedLimit = 1.0;
constexpr double kSquashPenLimit = 0.01;
/// Held still, each weightless hand is in equilibrium between its coupling
/// spring and the box: the squeeze equals K·(tracked − proxy), which differs
/// from K·depth only by the palms' penetration and the box's drift (both
/// well under 1% of the 17 mm depth at 50 N). 2% leaves room for the solver's
/// residual, not for a grip that misses the box.
constexpr double kSquashForceTolerance = 0.02;

SquashResult RunSquash(const PhysicsConfig& config) {
  SquashResult r;
  PhysicsWorld world(config);
  const physics::BoxGrip grip(world);
  const double half = physics::BoxGrip::kHalf;
  const physics::BodyId box = grip.box;
  r.k = config.hand.coupling_linear_stiffness;
  const double z0 = 0.09, h = config.step_s;
  const btCollisionObject* bx = &world.body(box);
  physics::ProxyHand& left = *world.hand(Side::kLeft);
  physics::ProxyHand& right = *world.hand(Side::kRight);
  r.force_asked = 50.0;
  r.contact_min = 1e9;
  long held = 0;
  // Force equivalent F = K·depth: from −3 N (a gap) to 50 N in 4 s, then held 1 s.
  const long n = std::lround(5.0 / h);
  for (long i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * h;
    const double force = std::min(r.force_asked, -3.0 + 53.0 * t / 4.0);
    grip.Track(force / r.k, z0);
    world.Step();
    if (t >= 4.0) {
      // Left hand pushes the box towards +y, right hand towards −y.
      const double squeeze =
          std::min(ContactForce(world, left, bx).y(), -ContactForce(world, right, bx).y());
      const double coupling = 0.5 * r.k *
                              ((left.TrackedWrist().position[1] - left.ProxyWrist().position[1]) +
                               (right.ProxyWrist().position[1] - right.TrackedWrist().position[1]));
      r.contact_mean += squeeze;
      r.contact_min = std::min(r.contact_min, squeeze);
      r.coupling_mean += coupling;
      ++held;
    }
    const double speed = Norm(world.body(box).getLinearVelocity());
    const double pen = Penetration(world, bx, nullptr);  // palms, fingers and the floor
    if (force <= 7.0) {
      r.speed_to_7n = std::max(r.speed_to_7n, speed);
      r.pen_to_7n = std::max(r.pen_to_7n, pen);
    }
    r.speed_to_50n = std::max(r.speed_to_50n, speed);
    r.pen_to_50n = std::max(r.pen_to_50n, pen);
    const Vec3d p = world.BodyPose(box).position;
    const double yl = world.hand(Side::kLeft)->ProxyWrist().position[1];
    const double yr = world.hand(Side::kRight)->ProxyWrist().position[1];
    r.box_drift =
        std::max(r.box_drift, std::sqrt(p[0] * p[0] + p[1] * p[1] + (p[2] - half) * (p[2] - half)));
    if (!(p[1] > yl && p[1] < yr && std::abs(p[0]) < half && p[2] > 0.0 && p[2] < 0.3))
      r.between = false;
  }
  r.contact_mean /= static_cast<double>(std::max(held, 1L));
  r.coupling_mean /= static_cast<double>(std::max(held, 1L));
  r.resets = Resets(world);
  const bool pressed =
      std::abs(r.contact_mean - r.force_asked) <= kSquashForceTolerance * r.force_asked &&
      r.contact_min >= (1.0 - kSquashForceTolerance) * r.force_asked;
  r.passed = r.resets == 0 && r.between && pressed && r.speed_to_50n < kSquashSpeedLimit &&
             r.pen_to_50n < kSquashPenLimit;
  return r;
}

// ------------------------------------------------------------ grasp/release
struct GraspResult {
  double step_s = 0.0;
  double minutes = 0.0;
  double probe_wall_s = 0.0;  ///< wall time of the 5 s probe at 1 ms
  double wall_s = 0.0;
  int cycles = 0;
  int lifted = 0;              ///< cycles where the box rose ≥ 5 cm
  std::vector<double> energy;  ///< J, at the start of each cycle
  double drift = 0.0, max_excursion = 0.0;
  double max_box_offset = 0.0;  ///< m, horizontal, from the start
  uint64_t resets = 0;
  bool bounded = true;
  bool passed = false;
};
constexpr double kCycleS = 4.0;

/// One run of `seconds` at `step_s`; the grip follows the box's resting place
/// only through the palms (the tracked hands always aim at the origin).
GraspResult RunGrasp(const PhysicsConfig& base, double step_s, double seconds) {
  GraspResult r;
  PhysicsConfig config = base;
  config.step_s = step_s;
  r.step_s = step_s;
  r.minutes = seconds / 60.0;
  PhysicsWorld world(config);
  const physics::BoxGrip grip(world);
  const double half = physics::BoxGrip::kHalf;
  const physics::BodyId box = grip.box;
  const double z0 = 0.09, squeeze = 0.01, open = -0.02;
  const long per_cycle = std::lround(kCycleS / step_s);
  const long n = std::lround(seconds / step_s);
  double top = 0.0;
  const double t0 = NsToS(MonotonicNs());
  for (long i = 0; i < n; ++i) {
    const double tc = static_cast<double>(i % per_cycle) * step_s;  // time in the cycle
    if (i % per_cycle == 0) {
      if (r.cycles > 0 && top > half + 0.05) ++r.lifted;
      top = 0.0;
      r.energy.push_back(MechanicalEnergy(world));
      ++r.cycles;
    }
    // 0–0.5 open; 0.5–0.8 close; 0.8–1.0 hold; 1.0–2.0 lift 10 cm; 2.0–2.3 hold;
    // 2.3–2.4 open; 2.4–4.0 the box drops and settles, the hands go back down.
    double depth = open, z = z0;
    if (tc >= 0.5 && tc < 0.8) depth = open + (squeeze - open) * (tc - 0.5) / 0.3;
    if (tc >= 0.8 && tc < 2.3) depth = squeeze;
    if (tc >= 1.0 && tc < 2.0) z = z0 + 0.1 * (tc - 1.0);
    if (tc >= 2.0 && tc < 2.4) z = z0 + 0.1;
    if (tc >= 2.3 && tc < 2.4) depth = squeeze + (open - squeeze) * (tc - 2.3) / 0.1;
    if (tc >= 2.4 && tc < 3.4) z = z0 + 0.1 * (1.0 - (tc - 2.4));
    grip.Track(depth, z);
    world.Step();
    const Vec3d p = world.BodyPose(box).position;
    top = std::max(top, p[2]);
    r.max_box_offset = std::max(r.max_box_offset, std::hypot(p[0], p[1]));
    if (!(std::isfinite(p[2]) && std::hypot(p[0], p[1]) < 0.5 && p[2] > 0.0 && p[2] < 0.5))
      r.bounded = false;
  }
  if (top > half + 0.05) ++r.lifted;
  r.wall_s = NsToS(MonotonicNs()) - t0;
  r.resets = Resets(world);
  if (!r.energy.empty()) {
    r.drift = r.energy.back() - r.energy.front();
    for (double e : r.energy)
      r.max_excursion = std::max(r.max_excursion, std::abs(e - r.energy.front()));
  }
  // Bounded energy: the box's potential energy over 10 cm is 0.49 J.
  r.passed = r.resets == 0 && r.bounded && r.max_excursion < 0.1 && r.lifted == r.cycles;
  return r;
}

}  // namespace

int BenchStabilityMain(int argc, const char* const* argv) {
  bool json = false, smoke = false;
  double minutes = 10.0;
  PhysicsConfig config;
  try {
    const Args args(argc, argv, {"physics", "minutes"}, {"json", kSmokeFlag});
    json = args.Flag("json");
    smoke = args.Flag(kSmokeFlag);
    if (smoke) minutes = 2.0 * kCycleS / 60.0;  // two whole grasp/release cycles
    if (auto v = args.Number("minutes", 0.1, 60)) minutes = *v;
    config =
        LoadPhysics(args.Value("physics").value_or(ShippedFile("config/physics.yaml").string()));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel bench stability: %s\n", e.what());
    return 2;
  }
  config.realtime_priority = 0;  // stepped on this thread, never started
  const std::vector<double>& stiff_steps = smoke ? kStiffStepsSmoke : kStiffSteps;
  PrintSmokeNote("stability", smoke,
                 "stiffness at %zu step sizes, grasp_release %.2g simulated min",
                 stiff_steps.size(), minutes);
  const auto dir = OutputDir(smoke);
  const auto& hc = config.hand;
  std::printf("haptel bench stability: %s, configured step %.4g s, %d solver iterations\n\n",
              config.file.empty() ? "defaults" : config.file.c_str(), config.step_s,
              config.solver_iterations);

  // ---- stiffness
  const double t_stiff = NsToS(MonotonicNs());
  const std::vector<StiffRow> stiff = StiffnessSweep(config, stiff_steps);
  bool stiff_passed = true;  // the configured stiffness must be stable at the configured step
  std::printf(
      "[stiffness] palm (%.3g kg) coupled to a tracked wrist, damping b = %.3g N*s/m, K doubling "
      "from 1e2\n"
      "  to %.3g; diverged = NaN reset, error > 10 cm or energy growing while held (%.1f s wall)\n",
      hc.palm_mass, hc.coupling_linear_damping, kStiffCap, NsToS(MonotonicNs()) - t_stiff);
  std::printf("  %8s %12s %12s %12s %12s %12s %-16s %s\n", "T ms", "K_max", "K_eff@max", "2b/T",
              "m/(16T^2)", "K_implicit", "regime@K_max", "stopped by");
  for (const StiffRow& row : stiff) {
    std::printf("  %8.3g %12.4g %12.4g %12.4g %12.4g %12.4g %-16s %s\n", row.step_s * 1e3,
                row.k_max, row.k_eff_at_max, row.k_passive, row.k_clamp, row.k_implicit,
                row.regime_at_max.c_str(),
                row.capped ? "(nothing: sweep cap reached)" : row.first_failure.c_str());
    if (std::abs(row.step_s - config.step_s) < 1e-12 && row.k_max < hc.coupling_linear_stiffness)
      stiff_passed = false;
  }
  std::printf(
      "  K_eff@max: 1 N / static offset under a 1 N push. Bullet's spring (explicit) is clamped "
      "to\n"
      "  m/(16T^2) and the proxy hand switches to its implicit soft lock at K_implicit: between "
      "the\n"
      "  two the asked K is NOT what acts (compare K_eff), and the divergence the passivity bound\n"
      "  2b/T warns about is never reached by the Bullet formulation itself.\n");
  {
    std::ofstream csv(dir / "stability_stiffness.csv");
    csv << "step_ms,k,stable,why,k_eff,max_error_m,regime\n";
    for (const StiffRow& row : stiff) {
      for (const StiffRun& run : row.runs) {
        csv << row.step_s * 1e3 << "," << run.k << "," << (run.stable ? 1 : 0) << "," << run.why
            << "," << run.k_eff << "," << run.max_error << "," << Regime(config, row.step_s, run.k)
            << "\n";
      }
    }
  }
  {
    Series kmax{"K_max stable (sweep cap " + JsonNumber(kStiffCap) + ")", {}, {}};
    Series keff{"K_eff measured at K_max", {}, {}};
    Series pass{"passivity 2b/T", {}, {}};
    Series clamp{"Bullet clamp m/(16T^2)", {}, {}};
    for (const StiffRow& row : stiff) {
      const double t = row.step_s * 1e3;
      kmax.x.push_back(t), kmax.y.push_back(std::max(row.k_max, 1.0));
      keff.x.push_back(t), keff.y.push_back(std::max(row.k_eff_at_max, 1.0));
      pass.x.push_back(t), pass.y.push_back(row.k_passive);
      clamp.x.push_back(t), clamp.y.push_back(row.k_clamp);
    }
    PlotOptions o;
    o.title = "Palm coupling: largest stable stiffness vs step";
    o.x_label = "step T (ms)";
    o.y_label = "K (N/m)";
    o.log_y = true;
    try {
      PlotLines(dir / "stability_stiffness.png", {kmax, keff, pass, clamp}, o);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "haptel bench stability: %s\n", e.what());
    }
  }

  // ---- mass ratio
  std::vector<MassRow> mass;
  for (const double heavy : {0.09, 0.9, 9.0, 10.0}) mass.push_back(RunMassRatio(config, heavy));
  bool mass_passed = true;
  std::printf(
      "\n[mass_ratio] 9 g capsule (a distal phalanx, the hand's material: rolling friction %.3g m) "
      "on a\n"
      "  20 cm box: 2.5 s resting, 2.5 s pressed with 5 N (limits: penetration %.0f mm, spin %.1f "
      "rad/s: max |w|\n"
      "  about its axis after 0.5 s)\n",
      hc.material.rolling_friction, kMassPenLimit * 1e3, kMassSpinLimit);
  std::printf("  %8s %10s %14s %14s %12s %13s %13s %7s %7s %s\n", "ratio", "heavy kg",
              "pen rest mm", "pen pressed mm", "max v m/s", "spin rest", "spin pressed", "on box",
              "resets", "ok");
  for (const MassRow& r : mass) {
    std::printf("  1:%-6.0f %10.3g %14.3f %14.3f %12.3g %9.3g r/s %9.3g r/s %7s %7llu %s\n",
                r.heavy / r.light, r.heavy, r.pen_rest * 1e3, r.pen_pressed * 1e3, r.max_speed,
                r.spin_rest, r.spin_pressed, r.on_box ? "yes" : "no",
                static_cast<unsigned long long>(r.resets), r.passed ? "ok" : "FAIL");
    mass_passed = mass_passed && r.passed;
  }
  {
    std::ofstream csv(dir / "stability_mass_ratio.csv");
    csv << "light_kg,heavy_kg,ratio,pen_rest_m,pen_pressed_m,max_speed,spin_rest_rad_s,spin_"
           "pressed_rad_s,on_box,"
           "resets,passed\n";
    for (const MassRow& r : mass) {
      csv << r.light << "," << r.heavy << "," << r.heavy / r.light << "," << r.pen_rest << ","
          << r.pen_pressed << "," << r.max_speed << "," << r.spin_rest << "," << r.spin_pressed
          << "," << r.on_box << "," << r.resets << "," << r.passed << "\n";
    }
  }

  // ---- squash
  const SquashResult sq = RunSquash(config);
  std::printf(
      "\n[squash] two palms on a 0.5 kg box, coupling force K*depth (K = %.4g N/m) from -3 N to 50 "
      "N\n"
      "  in 4 s, held 1 s (limits: speed < %.1f m/s, penetration < %.0f mm, box between the "
      "palms)\n",
      sq.k, kSquashSpeedLimit, kSquashPenLimit * 1e3);
  std::printf("  %-12s %14s %16s\n", "force range", "max box m/s", "max pen mm");
  std::printf("  %-12s %14.4g %16.3f\n", "<= 7 N", sq.speed_to_7n, sq.pen_to_7n * 1e3);
  std::printf("  %-12s %14.4g %16.3f\n", "<= 50 N", sq.speed_to_50n, sq.pen_to_50n * 1e3);
  std::printf(
      "  squeeze reached over the last 1 s (asked %.0f N, tolerance %.0f%%): contact force per "
      "hand\n"
      "  mean %.2f N, min %.2f N; coupling K*(tracked - proxy) mean %.2f N\n",
      sq.force_asked, kSquashForceTolerance * 100.0, sq.contact_mean, sq.contact_min,
      sq.coupling_mean);
  std::printf("  box moved at most %.2f mm, between the palms: %s, resets: %llu -> %s\n",
              sq.box_drift * 1e3, sq.between ? "yes" : "no",
              static_cast<unsigned long long>(sq.resets), sq.passed ? "ok" : "FAIL");
  {
    std::ofstream csv(dir / "stability_squash.csv");
    csv << "k,speed_to_7n,pen_to_7n_m,speed_to_50n,pen_to_50n_m,box_drift_m,force_asked_n,contact_"
           "force_mean_n,"
           "contact_force_min_n,coupling_force_mean_n,between,resets,passed\n";
    csv << sq.k << "," << sq.speed_to_7n << "," << sq.pen_to_7n << "," << sq.speed_to_50n << ","
        << sq.pen_to_50n << "," << sq.box_drift << "," << sq.force_asked << "," << sq.contact_mean
        << "," << sq.contact_min << "," << sq.coupling_mean << "," << sq.between << "," << sq.resets
        << "," << sq.passed << "\n";
  }

  // ---- grasp and release
  const double seconds = minutes * 60.0;
  const double t_probe = NsToS(MonotonicNs());
  RunGrasp(config, 1e-3, 5.0);
  const double probe = NsToS(MonotonicNs()) - t_probe;
  const double grasp_step = probe * seconds / 5.0 > 60.0 ? 2e-3 : 1e-3;
  GraspResult gr = RunGrasp(config, grasp_step, seconds);
  gr.probe_wall_s = probe;
  std::printf(
      "\n[grasp_release] %.1f simulated min, %.0f s cycles (close, lift 10 cm, open, drop, "
      "settle),\n"
      "  step %.4g ms (5 s probe at 1 ms took %.2f s wall: %.0f s projected%s), %.1f s wall\n",
      gr.minutes, kCycleS, gr.step_s * 1e3, probe, probe * seconds / 5.0,
      grasp_step > 1e-3 ? " > 60 s, so 2 ms" : "", gr.wall_s);
  std::printf(
      "  cycles %d, lifted %d, energy at cycle start: first %.6f J, last %.6f J, drift %.3g J,\n"
      "  max excursion %.3g J (limit 0.1 J), box wandered %.1f mm, bounded: %s, resets: %llu -> "
      "%s\n",
      gr.cycles, gr.lifted, gr.energy.empty() ? 0.0 : gr.energy.front(),
      gr.energy.empty() ? 0.0 : gr.energy.back(), gr.drift, gr.max_excursion,
      gr.max_box_offset * 1e3, gr.bounded ? "yes" : "no",
      static_cast<unsigned long long>(gr.resets), gr.passed ? "ok" : "FAIL");
  {
    std::ofstream csv(dir / "stability_grasp_release.csv");
    csv << "cycle,energy_j\n";
    for (size_t i = 0; i < gr.energy.size(); ++i) csv << i << "," << gr.energy[i] << "\n";
  }

  const bool passed = stiff_passed && mass_passed && sq.passed && gr.passed;
  std::printf(
      "\n  stiffness %s (configured K = %.4g N/m stable at the configured step), mass_ratio %s, "
      "squash %s,\n"
      "  grasp_release %s -> %s\n  wrote "
      "%s/stability_{stiffness,mass_ratio,squash,grasp_release}.csv, "
      "stability_stiffness.png\n",
      stiff_passed ? "ok" : "FAIL", hc.coupling_linear_stiffness, mass_passed ? "ok" : "FAIL",
      sq.passed ? "ok" : "FAIL", gr.passed ? "ok" : "FAIL", passed ? "PASSED" : "FAILED",
      dir.c_str());

  if (json) {
    std::ostringstream o;
    o << "{\"passed\":" << (passed ? "true" : "false") << ",\"tests\":{";
    o << "\"stiffness\":{\"passed\":" << (stiff_passed ? "true" : "false")
      << ",\"damping\":" << JsonNumber(hc.coupling_linear_damping)
      << ",\"sweep_cap\":" << JsonNumber(kStiffCap) << ",\"steps\":[";
    for (size_t i = 0; i < stiff.size(); ++i) {
      const StiffRow& row = stiff[i];
      o << (i ? "," : "") << "{\"step_ms\":" << JsonNumber(row.step_s * 1e3)
        << ",\"k_max\":" << JsonNumber(row.k_max)
        << ",\"capped\":" << (row.capped ? "true" : "false")
        << ",\"k_eff_at_max\":" << JsonNumber(row.k_eff_at_max)
        << ",\"k_passive\":" << JsonNumber(row.k_passive)
        << ",\"k_bullet_clamp\":" << JsonNumber(row.k_clamp)
        << ",\"k_implicit\":" << JsonNumber(row.k_implicit) << ",\"regime_at_max\":\""
        << row.regime_at_max << "\"}";
    }
    o << "]},\"mass_ratio\":{\"passed\":" << (mass_passed ? "true" : "false") << ",\"ratios\":[";
    for (size_t i = 0; i < mass.size(); ++i) {
      const MassRow& r = mass[i];
      o << (i ? "," : "") << "{\"heavy_kg\":" << JsonNumber(r.heavy)
        << ",\"ratio\":" << JsonNumber(r.heavy / r.light)
        << ",\"pen_rest_mm\":" << JsonNumber(r.pen_rest * 1e3)
        << ",\"pen_pressed_mm\":" << JsonNumber(r.pen_pressed * 1e3)
        << ",\"max_speed\":" << JsonNumber(r.max_speed)
        << ",\"spin_rest_rad_s\":" << JsonNumber(r.spin_rest)
        << ",\"spin_pressed_rad_s\":" << JsonNumber(r.spin_pressed)
        << ",\"on_box\":" << (r.on_box ? "true" : "false") << ",\"resets\":" << r.resets
        << ",\"passed\":" << (r.passed ? "true" : "false") << "}";
    }
    o << "]},\"squash\":{\"passed\":" << (sq.passed ? "true" : "false")
      << ",\"max_speed_7n\":" << JsonNumber(sq.speed_to_7n)
      << ",\"max_speed_50n\":" << JsonNumber(sq.speed_to_50n)
      << ",\"pen_7n_mm\":" << JsonNumber(sq.pen_to_7n * 1e3)
      << ",\"pen_50n_mm\":" << JsonNumber(sq.pen_to_50n * 1e3)
      << ",\"force_asked_n\":" << JsonNumber(sq.force_asked)
      << ",\"contact_force_mean_n\":" << JsonNumber(sq.contact_mean)
      << ",\"contact_force_min_n\":" << JsonNumber(sq.contact_min)
      << ",\"coupling_force_mean_n\":" << JsonNumber(sq.coupling_mean)
      << ",\"box_drift_mm\":" << JsonNumber(sq.box_drift * 1e3)
      << ",\"between\":" << (sq.between ? "true" : "false") << ",\"resets\":" << sq.resets << "}";
    o << ",\"grasp_release\":{\"passed\":" << (gr.passed ? "true" : "false")
      << ",\"minutes\":" << JsonNumber(gr.minutes) << ",\"step_ms\":" << JsonNumber(gr.step_s * 1e3)
      << ",\"wall_s\":" << JsonNumber(gr.wall_s) << ",\"cycles\":" << gr.cycles
      << ",\"lifted\":" << gr.lifted
      << ",\"energy_first_j\":" << JsonNumber(gr.energy.empty() ? 0.0 : gr.energy.front())
      << ",\"energy_drift_j\":" << JsonNumber(gr.drift)
      << ",\"energy_max_excursion_j\":" << JsonNumber(gr.max_excursion)
      << ",\"resets\":" << gr.resets << "}}}";
    std::printf("%s\n", JsonLine(o.str(), smoke).c_str());
  }
  return passed ? 0 : 1;
}

}  // namespace haptel::bench
