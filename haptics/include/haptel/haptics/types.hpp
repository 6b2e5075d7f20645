#pragma once
/// @file Plain data exchanged between the servo loop and slower threads.
///
/// All structs are trivially copyable so they cross threads through a
/// seqlock. Device frame: x forward (away from the operator), y left, z up;
/// metres, seconds, newtons.
#include <array>
#include <cstdint>

namespace haptel::haptics {

enum class Side : int { kLeft = 0, kRight = 1 };
constexpr int kSides = 2;
constexpr int Index(Side side) { return static_cast<int>(side); }

/// Joint angles a data glove reports per hand.
constexpr int kGloveJoints = 22;
/// Fingers of a grasp (string) device per hand.
constexpr int kFingers = 5;

using Vec3d = std::array<double, 3>;

/// One device reading for one hand, stamped on the servo thread.
struct HandSample {
  int64_t t_ns = 0;                                  ///< CLOCK_MONOTONIC
  bool valid = false;                                ///< false: no reading yet, or device lost
  Vec3d position{};                                  ///< wrist, m
  Vec3d velocity{};                                  ///< wrist, m/s
  std::array<double, 4> orientation{1, 0, 0, 0};     ///< wrist quaternion (w, x, y, z)
  std::array<double, kGloveJoints> finger_angles{};  ///< rad
  Vec3d force{};                                     ///< wrist force last commanded, N
};

/// A force field the interface sets and the servo loop evaluates every tick,
/// so forces refresh at the servo rate whatever rate the interface runs at.
/// Centring: F = -(k + k2·|d|)·d − b·v with d = p − neutral.
/// Wall: F = −(k_w·pen + b_w·max(0, v·n))·n when pen = (p − wall_point)·n > 0.
struct ForceField {
  bool enabled = false;
  Vec3d neutral{};
  double stiffness = 0.0;         ///< N/m
  double stiffness_growth = 0.0;  ///< N/m²
  double damping = 0.0;           ///< N·s/m
  bool wall_active = false;
  Vec3d wall_point{};
  Vec3d wall_normal{1, 0, 0};   ///< unit, pointing into the wall
  double wall_stiffness = 0.0;  ///< N/m
  double wall_damping = 0.0;    ///< N·s/m
  /// Haptic shared control's guidance (interfaces/shared_control.hpp): past
  /// the plane through `guidance_point` facing `guidance_normal` lie the
  /// commands that lead into an obstacle; a hand beyond it is pushed back by
  /// a spring that saturates at `guidance_max_force`, so the operator can
  /// always push through.
  bool guidance_active = false;
  Vec3d guidance_point{};
  Vec3d guidance_normal{1, 0, 0};   ///< unit, pointing towards the dangerous commands
  double guidance_stiffness = 0.0;  ///< N/m
  double guidance_max_force = 0.0;  ///< N, the most it ever pushes
};

/// A wrist tracker reading as the device reports it: position in device
/// units (calibration turns it into metres), orientation as a unit quaternion.
struct WristRaw {
  int64_t t_ns = 0;
  Vec3d position{};
  std::array<double, 4> orientation{1, 0, 0, 0};  ///< (w, x, y, z)
};

/// The slow channels as the device reports them: glove sensor values (device
/// units; calibration turns them into joint angles) and the grasp strings'
/// measured forces (device units).
struct GloveRaw {
  int64_t t_ns = 0;
  std::array<double, kGloveJoints> sensors{};
  std::array<double, kFingers> grasp{};
};

/// Everything slower threads ask of the servo loop for one side. The servo
/// loop turns it into forces every tick from the latest hand pose; when
/// `stamp_ns` grows old (the feeder stalled) the forces fade to zero.
struct ForceSetpoint {
  int64_t stamp_ns = 0;           ///< CLOCK_MONOTONIC time the feeder wrote it; 0 = never
  ForceField field;               ///< interface force field
  bool coupling_enabled = false;  ///< proxy coupling: F = k·(target − p) − b·v
  Vec3d coupling_target{};
  double coupling_stiffness = 0.0;               ///< N/m
  double coupling_damping = 0.0;                 ///< N·s/m
  Vec3d wrist_force{};                           ///< added as is, N
  std::array<double, kFingers> finger_forces{};  ///< N, pulling each finger back (≥ 0)
  /// The vehicle's contacts begun so far (Hal::MarkContact): a device that
  /// shows or plays a contact (a shake) does so when this grows.
  uint64_t contacts = 0;
};

}  // namespace haptel::haptics
