#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "haptel/haptics/force_field.hpp"
#include "haptel/testing/vec_math.hpp"

using namespace haptel::haptics;

namespace {
ForceField Centring(double k, double k2, double b) {
  ForceField f;
  f.enabled = true;
  f.neutral = {0.1, 0.0, 0.0};
  f.stiffness = k;
  f.stiffness_growth = k2;
  f.damping = b;
  return f;
}
}  // namespace

TEST_CASE("a disabled field exerts no force") {
  ForceField f = Centring(100, 100, 10);
  f.enabled = false;
  const Vec3d F = EvaluateForceField(f, {1, 2, 3}, {1, 1, 1});
  CHECK(Norm(F) == 0.0);
}

TEST_CASE("the centring field pulls toward neutral and grows faster than linearly") {
  const ForceField f = Centring(40, 300, 0);
  const Vec3d near = EvaluateForceField(f, {0.12, 0, 0}, {0, 0, 0});  // 2 cm ahead
  const Vec3d far = EvaluateForceField(f, {0.16, 0, 0}, {0, 0, 0});   // 6 cm ahead
  CHECK(near[0] < 0.0);
  CHECK(near[0] == Approx(-(40 + 300 * 0.02) * 0.02));
  CHECK(far[0] / near[0] > 3.0);  // 3x distance, more than 3x force
  const Vec3d at_neutral = EvaluateForceField(f, {0.1, 0, 0}, {0, 0, 0});
  CHECK(Norm(at_neutral) == Approx(0.0).margin(1e-12));
}

TEST_CASE("damping opposes velocity") {
  const ForceField f = Centring(0, 0, 5);
  const Vec3d F = EvaluateForceField(f, {0.1, 0, 0}, {0, 0.2, 0});
  CHECK(F[1] == Approx(-1.0));
}

TEST_CASE("a wall resists only penetration along its normal") {
  ForceField f = Centring(0, 0, 0);
  f.wall_active = true;
  f.wall_point = {0.15, 0, 0};
  f.wall_normal = {1, 0, 0};
  f.wall_stiffness = 1000;
  f.wall_damping = 0;
  CHECK(Norm(EvaluateForceField(f, {0.14, 0, 0}, {0, 0, 0})) == 0.0);  // in front of the wall
  const Vec3d F = EvaluateForceField(f, {0.155, 0.02, 0}, {0, 0, 0});  // 5 mm in
  CHECK(F[0] == Approx(-5.0));
  CHECK(F[1] == Approx(0.0).margin(1e-12));  // sliding along the wall is free
}

TEST_CASE("shared control's guidance pushes back past its plane, saturating at its bound") {
  ForceField f = Centring(0, 0, 0);
  f.guidance_active = true;
  f.guidance_point = {0.12, 0, 0};
  f.guidance_normal = {0, -1, 0};  // the dangerous commands lie to the right (-y)
  f.guidance_stiffness = 150;
  f.guidance_max_force = 3.0;
  CHECK(Norm(EvaluateForceField(f, {0.12, 0.01, 0}, {0, 0, 0})) == 0.0);  // on the safe side
  const Vec3d in = EvaluateForceField(f, {0.13, -0.01, 0}, {0, 0, 0});    // 1 cm past it
  CHECK(in[1] == Approx(1.5));
  CHECK(in[0] == Approx(0.0).margin(1e-12));  // along the plane nothing pushes
  // Far past it, no more than the bound: the operator can always push through.
  const Vec3d deep = EvaluateForceField(f, {0.12, -0.5, 0}, {0, 0, 0});
  CHECK(deep[1] == Approx(3.0));
  f.guidance_active = false;
  CHECK(Norm(EvaluateForceField(f, {0.12, -0.5, 0}, {0, 0, 0})) == 0.0);
}

TEST_CASE("LimitForce scales to the limit and zeroes non-finite forces") {
  Vec3d big{30, 40, 0};
  CHECK(LimitForce(big, 7.0));
  CHECK(Norm(big) == Approx(7.0));
  CHECK(big[0] / big[1] == Approx(0.75));  // direction kept
  Vec3d small{1, 1, 1};
  CHECK_FALSE(LimitForce(small, 7.0));
  CHECK(small[0] == 1.0);
  Vec3d bad{std::numeric_limits<double>::quiet_NaN(), 1, 1};
  CHECK(LimitForce(bad, 7.0));
  CHECK(Norm(bad) == 0.0);
  Vec3d inf{std::numeric_limits<double>::infinity(), 0, 0};
  CHECK(LimitForce(inf, 7.0));
  CHECK(Norm(inf) == 0.0);
}
