#pragma once
/// @file The `mouse` device: a person's mouse and keys as the device's two
/// hands, the forces on them shown by pseudo-haptics (Lécuyer's
/// control/display ratio; H3DAPI's MouseHapticsDevice is the anchor for a
/// mouse as a haptic device). The map and its parameters: MouseDeviceConfig
/// (haptel/config/device.hpp); docs/haptics.md.
///
/// Each tick a side's target is where its input puts it: the pointer hand's
/// PointerTarget(DesktopPointer()), the key hand's StepKeyHand from its last
/// target. While the pointer is in an open window the hand H follows its
/// target T through the virtual coupling, pushed by the last force F written
/// to it:
///   dH/dt = (T − H)/τ + F/(τ·k_c),
/// stepped exactly for the tick with F held (the coupling itself never goes
/// unstable, whatever the tick's length); an open hand can so be brought to
/// a control before it closes on it. The person holds it (Presence kHeld,
/// the hand closed) while the grasp button is down too. With the pointer
/// out of the window it is free: dH/dt = F/(τ·k_c), so a centring field
/// pulls it back as an unheld arm would go.
/// A contact of the vehicle (the set-point's `contacts` count growing,
/// Hal::MarkContact) starts a shake of the shown pointer hand
/// (PseudoHaptics' `shake`, not the reading the interfaces drive with) in
/// the same tick, `shake_amplitude` m decaying over `shake_s`, along the
/// gesture's wall's normal where one is up, else backwards. Forces never
/// shake it: a driven control's coupling steps its force all the time.
///
/// The device reports metres and radians and takes newtons (its driver's
/// CalibrationSource::kSelf): without a calibration file the session gives
/// it the identity. Glove:
/// both hands close into the cockpit's grip posture while held.
///
/// Threads: each side's calls come from its own servo thread and touch only
/// that side's state; UseReport's figures are atomics. Nothing allocates
/// after construction.
#include <array>
#include <atomic>
#include <cstdint>

#include "haptel/config/device.hpp"
#include "haptel/haptics/device.hpp"
#include "haptel/haptics/pointer.hpp"

namespace haptel::haptics {

class MouseDevice final : public Device {
 public:
  static constexpr const char* kDriver = "mouse";
  /// A window for the mean's figure: the hand's displacement over the
  /// pointer's is taken over this long, several coupling time constants, so
  /// it measures the bend, not the coupling's lag.
  static constexpr double kGainWindowS = 0.25;
  /// The least pointer motion over a window that counts towards the mean
  /// (m): below it the ratio is noise.
  static constexpr double kGainFloorM = 0.005;
  /// The largest shake, m (MouseDeviceConfig::shake_amplitude's bound).
  static constexpr double kMaxShakeM = 0.01;

  /// `config.mouse` is the map; `pointer` the box the view stores into
  /// (DesktopPointer() in a run; a test passes its own).
  explicit MouseDevice(const DeviceConfig& config, const PointerBox& pointer = DesktopPointer());

  const DeviceDescription& description() const override { return description_; }
  DeviceStatus ReadWrist(Side side, int64_t now_ns, WristRaw& out) override;
  DeviceStatus ReadGlove(Side side, int64_t now_ns, GloveRaw& out) override;
  DeviceStatus WriteWristForce(Side side, const Vec3d& command) override;
  DeviceStatus WriteFingerForces(Side side, const std::array<double, kFingers>& command) override;
  void SetpointHint(Side side, const ForceSetpoint& setpoint) override;
  HandPresence Presence(Side side) override;
  DeviceUseReport UseReport() const override;
  bool PseudoHaptics(Side side, PseudoHapticReport& out) override;

  /// The grip posture a held hand closes into: the cockpit's (the four
  /// fingers' MCP, PIP, DIP at GripGeometry::flexion; the thumb open), so
  /// its controls feel the fingers round their bars.
  static std::array<double, kGloveJoints> ClosedGlove();

 private:
  struct Hand {
    bool pointer = false;  ///< the pointer moves it (else the keys)
    Vec3d target{};
    Vec3d hand{};
    Vec3d force{};
    std::array<double, 4> orientation{1, 0, 0, 0};
    bool coupled = false;  ///< the pointer is in an open window: the hand follows
    bool held = false;     ///< coupled, and the grasp button is down
    int64_t last_ns = 0;
    uint64_t contacts_seen = 0;  ///< the set-points' contact count, as last seen
    // The shake: started at shake_start_ns along shake_direction.
    uint64_t shakes = 0;
    bool shaking = false;
    int64_t shake_start_ns = 0;
    Vec3d shake_direction{};
    double shake_amplitude = 0.0;
    Vec3d shake{};
    // The gain's window: where hand and target were at its start.
    int64_t window_start_ns = 0;
    Vec3d window_hand{};
    Vec3d window_target{};
  };

  void Step(Hand& h, const PointerState& pointer, double dt_s);
  /// Starts a shake along the unit `direction` (none while one plays).
  void StartShake(Hand& h, const Vec3d& direction, double amplitude_m);
  void UpdateShake(Hand& h, int64_t now_ns);
  void MeasureGain(Hand& h, int64_t now_ns);

  MouseDeviceConfig config_;
  DeviceDescription description_;
  const PointerBox& pointer_box_;
  std::array<Hand, kSides> hands_{};
  std::array<PointerState, kSides> pointer_{};  ///< each side's last good read of the box
  std::array<double, kGloveJoints> closed_{};
  std::atomic<double> gain_sum_{0.0};
  std::atomic<uint64_t> gain_windows_{0};
  std::atomic<uint64_t> shakes_{0};
};

}  // namespace haptel::haptics
