#pragma once
/// @file Hardware abstraction layer: the only place data crosses between the
/// servo threads and slower threads.
///
/// One component per channel and side — glove, wrist tracker, wrist force
/// set-point, grasp forces — each a seqlock (or, for the tracker history, a
/// ring of seqlocks): a servo thread never waits for anyone. Raw device values
/// are stored; calibrated values are computed in the accessors, only when a
/// slower thread asks. The tracker keeps its last 1000 samples; velocity and
/// mean acceleration are computed from them on demand, never in the loop.
#include <array>
#include <atomic>
#include <optional>
#include <span>

#include "haptel/config/calibration.hpp"
#include "haptel/core/seqlock.hpp"
#include "haptel/haptics/device.hpp"
#include "haptel/haptics/types.hpp"

namespace haptel::haptics {

/// One tracker sample as stored (raw device units).
struct TrackerSample {
  int64_t t_ns = 0;
  Vec3d raw{};
};

/// What was last commanded to an arm, in newtons.
struct AppliedForces {
  int64_t t_ns = 0;
  Vec3d wrist{};
  std::array<double, kFingers> fingers{};
};

class Hal {
 public:
  static constexpr int kTrackerHistory = 1000;

  /// Validates `calibration` first (DeviceCalibration::ValidateOrThrow: ConfigFieldError).
  explicit Hal(const DeviceCalibration& calibration = DeviceCalibration{});

  // --- Servo threads: one writer per side. Wait-free, allocation-free. ---
  void PublishWrist(Side side, const WristRaw& raw);
  void PublishGlove(Side side, const GloveRaw& raw);
  void PublishForces(Side side, const AppliedForces& forces);
  /// The device on `side` was lost (true) or answers again (false).
  void PublishLost(Side side, bool lost);
  bool lost(Side side) const { return lost_[Index(side)].load(std::memory_order_acquire); }
  /// What the device says of a person at `side` (Device::Presence), each tick.
  void PublishPresence(Side side, HandPresence presence) {
    presence_[Index(side)].store(presence, std::memory_order_release);
  }
  HandPresence presence(Side side) const {
    return presence_[Index(side)].load(std::memory_order_acquire);
  }
  /// What a device that bends its hand's motion shows of `side`, in metres
  /// and newtons (Device::PseudoHaptics), each tick; `shown` false until
  /// such a device publishes one.
  struct PseudoHaptics {
    bool shown = false;
    PseudoHapticReport report;
  };
  void PublishPseudoHaptics(Side side, const PseudoHapticReport& report) {
    pseudo_haptics_[Index(side)].Store({true, report});
  }
  PseudoHaptics pseudo_haptics(Side side) const { return pseudo_haptics_[Index(side)].Load(); }
  /// The combined set-point: the interface's field plus the physics thread's
  /// coupling, direct and finger forces. Its stamp is the older of the two
  /// feeders' stamps (a feeder that never wrote is ignored), so either one
  /// stalling fades the forces.
  ForceSetpoint Setpoint(Side side) const;
  /// Servo threads: Setpoint() with every seqlock read bounded to
  /// kSetpointReadAttempts attempts. True with `out` the set-point; false when
  /// a feeder's store stayed in progress through every attempt (its thread
  /// pre-empted mid-store), `out` then untouched: the caller keeps its last
  /// good set-point, whose stamp ages so that forces fade if the stall lasts.
  bool TrySetpoint(Side side, ForceSetpoint& out) const;
  /// A few attempts: a store takes tens of nanoseconds, so a store that
  /// outlasts them is a writer pre-empted mid-store, not one about to finish.
  static constexpr int kSetpointReadAttempts = 4;

  // --- Slower threads. Each slot has one writer: the interface (session)
  // thread writes fields, the physics thread writes the rest. ---
  /// The hand, calibrated now: position (m), velocity (m/s, second-order
  /// backward difference over the history), glove angles (rad), last forces.
  HandSample LatestSample(Side side) const;
  /// Interface thread: the force field, stamped `now_ns` (default: now).
  void SetField(Side side, const ForceField& field);
  void SetField(Side side, const ForceField& field, int64_t now_ns);
  /// Physics thread: coupling, direct wrist force and finger forces of
  /// `setpoint` (its `field` is ignored), stamped `now_ns`.
  void SetSetpoint(Side side, ForceSetpoint setpoint, int64_t now_ns);
  /// Interface thread: disables the fields: their forces go to zero at the
  /// next servo tick. (The physics thread clears its own part when it stops.)
  void ZeroForces();
  /// A short force the hands feel whatever the set-point asks (a cue: the
  /// fleet's switch to another vehicle). The servo loop adds `force` (N) to
  /// the wrist's set-point force until `until_ns` (CLOCK_MONOTONIC), under
  /// the same safety limits; stamped apart from the set-point's feeders so
  /// their stores never overwrite it.
  struct Cue {
    Vec3d force{};
    int64_t until_ns = 0;
  };
  /// Session thread: the cue on `side` (a later one replaces it).
  void SetCue(Side side, const Cue& cue);
  /// Servo threads: the cue on `side`, read with at most
  /// kSetpointReadAttempts attempts; false (no cue this tick) when its
  /// store stayed in progress through them.
  bool TryCue(Side side, Cue& out) const;

  /// Session thread: the vehicle began a contact (a bumper touched). Every
  /// side's set-point carries the count from the next servo tick on
  /// (ForceSetpoint::contacts), so a device shakes the hand on the contact
  /// itself, not on whatever force it brings.
  void MarkContact() { contacts_begun_.fetch_add(1, std::memory_order_relaxed); }
  uint64_t contacts_begun() const { return contacts_begun_.load(std::memory_order_relaxed); }

  /// Session thread: scales every force the set-points ask for (fields,
  /// coupling, direct and finger forces) by `scale` in [0, 1] — ramped by the
  /// session when it switches interfaces, so the hands feel no jolt.
  void SetForceScale(double scale);
  double force_scale() const { return force_scale_.load(std::memory_order_relaxed); }

  /// Copies up to out.size() newest tracker samples, oldest first; returns the count.
  size_t TrackerHistory(Side side, std::span<TrackerSample> out) const;
  /// Velocity (m/s) by second-order backward difference on the newest three samples.
  std::optional<Vec3d> TrackerVelocity(Side side) const;
  /// Mean acceleration (m/s²) over the last `window_s`: velocity change over the window.
  std::optional<Vec3d> MeanAcceleration(Side side, double window_s) const;

  const ArmCalibration& calibration(Side side) const { return calibration_.arms[Index(side)]; }
  uint64_t wrist_samples(Side side) const { return wrist_count_[Index(side)].load(); }
  uint64_t glove_samples(Side side) const { return glove_count_[Index(side)].load(); }

 private:
  /// Tests hold a feeder's store half done through this.
  friend struct HalTestAccess;
  Vec3d ToMetres(Side side, const Vec3d& raw) const;
  /// Combines the two feeders' parts and applies the force scale.
  ForceSetpoint Combine(ForceSetpoint contacts, const ForceField& latest_field,
                        int64_t field_stamp_ns) const;

  DeviceCalibration calibration_;
  std::array<Seqlock<WristRaw>, kSides> wrist_;
  std::array<Seqlock<GloveRaw>, kSides> glove_;
  std::array<Seqlock<AppliedForces>, kSides> forces_;
  struct StampedField {
    int64_t stamp_ns = 0;
    ForceField field;
  };
  std::array<Seqlock<StampedField>, kSides> fields_;
  std::array<Seqlock<ForceSetpoint>, kSides> contacts_;
  std::array<Seqlock<Cue>, kSides> cues_;
  std::array<std::atomic<bool>, kSides> lost_{};
  std::array<std::atomic<HandPresence>, kSides> presence_{};
  std::array<Seqlock<PseudoHaptics>, kSides> pseudo_haptics_;
  std::atomic<double> force_scale_{1.0};
  std::atomic<uint64_t> contacts_begun_{0};
  std::array<std::atomic<uint64_t>, kSides> wrist_count_{};
  std::array<std::atomic<uint64_t>, kSides> glove_count_{};
  std::array<std::array<Seqlock<TrackerSample>, kTrackerHistory>, kSides> history_;
};

}  // namespace haptel::haptics
