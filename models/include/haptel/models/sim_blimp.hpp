#pragma once
/// @file The simulated blimp on its course: the airship model (airship.hpp)
/// plus its contacts with the world — the ground it rests on at the start
/// and lands on, and the buildings it may hit.
///
/// Contact is a penalty model evaluated inside the integrator's every
/// derivative evaluation (AirshipContact): a spring-damper along the normal
/// (never pulling) and a Coulomb-like friction (viscous below sliding,
/// capped at μ times the normal force) at each contact feature. The hull
/// is a row of spheres on its axis, each of the spheroid's local radius,
/// and the gondola's keel is a small sphere below the envelope; the world
/// is the ground plane z = 0 and the course's buildings as boxes.
///
/// Stiffness against the step: the lightest mode a single contact drives is
/// the hull pitching (or rolling) about its centre of gravity, an effective
/// mass of about 4.4 kg at the nose (the transverse added mass and inertia
/// included); 10 kN/m gives ω ≈ 48 rad/s, ω·h ≈ 0.24 at the 5 ms RK4 step
/// (RK4 is stable to 2.8): the configured step stays. Even all eight
/// features on the ground at once under the heaviest vertical mode keep
/// ω·h below 0.3.
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "haptel/config/airship.hpp"
#include "haptel/config/blimp_course.hpp"
#include "haptel/core/blimp_command.hpp"
#include "haptel/models/airship.hpp"

namespace haptel::models {

/// The contact model's parameters (per contact feature).
struct BlimpContactConfig {
  double stiffness = 1.0e4;  ///< N/m along the normal
  /// N·s/m along the normal: damping ratio 0.4 against the hull's axial
  /// mass (a head-on bounce keeps about a quarter of its speed), 0.7 against
  /// the light pitching mode.
  double damping = 300.0;
  double friction = 0.6;            ///< Coulomb coefficient (envelope fabric, gondola skids)
  double friction_damping = 300.0;  ///< N·s/m: the viscous slope below sliding
  /// m: the gondola's keel below the centre of gravity. The envelope's
  /// bottom is diameter/2 − cg_below_cb below it (0.6 m for the thesis's
  /// blimp); the gondola hangs 0.2 m lower and carries the blimp at rest.
  double gondola_below_cg = 0.8;
  double gondola_radius = 0.1;  ///< m
  /// m: a feature counts as clear of an obstacle again once this far from
  /// it (no chatter of contact onsets while resting).
  double release_distance = 0.01;

  void ValidateOrThrow() const;
};

/// A sphere fixed to the body: the contact features.
struct ContactSphere {
  Eigen::Vector3d centre_body = Eigen::Vector3d::Zero();  ///< m, from the centre of gravity
  double radius = 0.0;                                    ///< m
};

/// The contact load of the hull and gondola against the ground and the
/// course's buildings (what SimBlimp hands its Airship).
class BlimpWorldContact : public AirshipContact {
 public:
  BlimpWorldContact(const AirshipConfig& airship, const BlimpCourseConfig& course,
                    const BlimpContactConfig& config);

  void Loads(const AirshipState& state, Eigen::Vector3d* force_body,
             Eigen::Vector3d* moment_body) const override;

  /// One feature against one obstacle (0: the ground, 1 + i: building i).
  struct Touch {
    int obstacle = 0;
    double depth = 0.0;          ///< m, > 0: penetrating; < 0: the gap
    Eigen::Vector3d normal;      ///< world, out of the obstacle
    Eigen::Vector3d point;       ///< world, the feature's deepest point
    double closing_speed = 0.0;  ///< m/s along -normal (> 0: approaching)
  };
  /// Calls `visit(const Touch&)` for every feature–obstacle pair whose gap
  /// is at most `max_gap` m. Allocation-free.
  template <typename Visit>
  void ForEach(const AirshipState& state, double max_gap, Visit&& visit) const;

  int obstacles() const { return 1 + static_cast<int>(boxes_.size()); }
  const std::vector<ContactSphere>& spheres() const { return spheres_; }
  const BlimpContactConfig& config() const { return config_; }
  /// How far the lowest feature hangs below the centre of gravity, upright (m).
  double lowest_below_cg() const { return lowest_below_cg_; }

 private:
  struct Box {
    Eigen::Vector2d centre;
    double cos_yaw, sin_yaw;
    Eigen::Vector3d half;  ///< half sizes: x, y in the box's frame, z (height / 2)
    double reach;          ///< horizontal half diagonal, for a quick rejection
  };
  bool BoxTouch(const Box& box, const Eigen::Vector3d& centre, double radius, double max_gap,
                Eigen::Vector3d* normal, double* depth) const;

  BlimpContactConfig config_;
  std::vector<ContactSphere> spheres_;
  std::vector<Box> boxes_;
  double lowest_below_cg_ = 0.0;
};

/// The simulated blimp: an airship on the course, resting on the ground at
/// the course's start, stepped with semantic commands.
class SimBlimp {
 public:
  /// Validates all three (ConfigFieldError). Starts resting on the ground at
  /// the course's start, facing its heading, motors off.
  SimBlimp(const AirshipConfig& airship, const BlimpCourseConfig& course,
           const BlimpContactConfig& contact = {});
  SimBlimp(const SimBlimp&) = delete;
  SimBlimp& operator=(const SimBlimp&) = delete;
  SimBlimp(SimBlimp&&) = default;
  SimBlimp& operator=(SimBlimp&&) = default;

  /// Clamps the command (Clamped), maps it to the actuators (the camera's
  /// pan and tilt are only stored) and advances dt seconds in steps of at
  /// most the airship's step_s, tracking contact onsets after each step.
  /// Allocation-free.
  void Step(double dt, const BlimpCommand& command);

  /// Puts the blimp at rest on the ground at (x, y), facing `heading` (rad),
  /// motors off; the contact state says "resting", not a new contact.
  void RestOnGround(double x, double y, double heading);
  /// Puts the blimp in `state` with `applied` in effect (as the operator's
  /// predictor starts from a reported state): a feature touching an
  /// obstacle there is in an ongoing contact, not a new one. The count of
  /// contact onsets carries on.
  void Place(const AirshipState& state, const BlimpCommand& applied);

  double time_s() const { return airship_.time_s(); }
  /// Of the centre of gravity, world (x east, y north, z up), m.
  Eigen::Vector3d position() const { return airship_.state().position; }
  double yaw() const { return airship_.YawPitchRoll().x(); }
  double pitch() const { return airship_.YawPitchRoll().y(); }
  double roll() const { return airship_.YawPitchRoll().z(); }
  /// Ground velocity, world frame, m/s.
  Eigen::Vector3d ground_velocity() const {
    return airship_.state().attitude * airship_.state().velocity;
  }
  /// Speed through the air, m/s.
  double airspeed() const { return airship_.Airspeed().norm(); }

  /// Touching the ground or a building (with a release distance: see
  /// BlimpContactConfig).
  bool in_contact() const;
  /// Touching the ground.
  bool on_ground() const { return touching_[0] != 0; }
  /// The normal closing speed at the onset of the latest contact (of the
  /// features near the obstacle just before the step that began it), m/s.
  double last_impact_speed() const { return last_impact_speed_; }
  /// Contact onsets so far (with the ground or any building; resting at
  /// the start is none).
  int contacts() const { return contacts_; }
  /// Obstacle of the latest onset: 0 the ground, 1 + i building i; -1 none yet.
  int last_obstacle() const { return last_obstacle_; }

  /// As commanded (rad), clamped to the camera's range.
  double camera_pan() const { return applied_.camera_pan; }
  double camera_tilt() const { return applied_.camera_tilt; }
  /// The command as applied (clamped).
  const BlimpCommand& applied() const { return applied_; }

  const Airship& airship() const { return airship_; }
  Airship& airship() { return airship_; }
  const BlimpWorldContact& contact_model() const { return *contact_; }

 private:
  void TrackContacts();

  std::unique_ptr<BlimpWorldContact> contact_;  ///< on the heap: the airship points at it
  Airship airship_;
  AirshipState previous_;  ///< before the step in progress
  BlimpCommand applied_;
  std::vector<char> touching_;   ///< per obstacle
  std::vector<char> scratch_;    ///< per obstacle, this step
  std::vector<double> closing_;  ///< per obstacle, this step
  int contacts_ = 0;
  double last_impact_speed_ = 0.0;
  int last_obstacle_ = -1;
};

// ---------------------------------------------------------------------------

template <typename Visit>
void BlimpWorldContact::ForEach(const AirshipState& s, double max_gap, Visit&& visit) const {
  const Eigen::Matrix3d rotation = s.attitude.toRotationMatrix();
  const Eigen::Vector3d rates_world = rotation * s.rates;
  const Eigen::Vector3d velocity_world = rotation * s.velocity;
  for (const ContactSphere& sphere : spheres_) {
    const Eigen::Vector3d offset = rotation * sphere.centre_body;
    const Eigen::Vector3d centre = s.position + offset;
    const auto emit = [&](int obstacle, const Eigen::Vector3d& normal, double depth) {
      Touch t;
      t.obstacle = obstacle;
      t.depth = depth;
      t.normal = normal;
      t.point = centre - sphere.radius * normal;
      const Eigen::Vector3d v = velocity_world + rates_world.cross(t.point - s.position);
      t.closing_speed = -v.dot(normal);
      visit(t);
    };
    // The ground plane.
    const double ground_depth = sphere.radius - centre.z();
    if (ground_depth >= -max_gap) emit(0, Eigen::Vector3d::UnitZ(), ground_depth);
    // The buildings.
    for (size_t i = 0; i < boxes_.size(); ++i) {
      Eigen::Vector3d normal;
      double depth = 0.0;
      if (BoxTouch(boxes_[i], centre, sphere.radius, max_gap, &normal, &depth)) {
        emit(1 + static_cast<int>(i), normal, depth);
      }
    }
  }
}

}  // namespace haptel::models
