#pragma once
/// @file Device traces: what a session's device reported, recorded from the
/// servo loop and played back by the `replay` driver at its original timing.
///
/// File format (little-endian): the 8 bytes "HAPTRC01", then records of
/// {u8 kind, u8 side, 6 bytes zero, i64 t_ns, f64 values[27]} — a wrist record
/// carries position (3, device units) and orientation (w, x, y, z); a glove
/// record carries the 22 sensors and the 5 grasp values; a shake record (a
/// device that shows its forces, Device::PseudoHaptics: one each time a
/// contact's shake starts, stamped with its start) carries the report in
/// metres and newtons: target, hand, force, shake (3 each), held (0/1) and
/// the side's shakes so far; an engaged record (one per side, from the
/// session each time it changes, and once when the trace starts) carries
/// whether the session let the hands drive (values[0], 0/1). Replay plays
/// wrists and gloves, and says the hand is held or released as the engaged
/// records say; a shake is for whoever times it (`haptel bench hands`).
#include <array>
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <thread>
#include <vector>

#include "haptel/core/spsc_ring.hpp"
#include "haptel/haptics/device.hpp"

namespace haptel::haptics {

struct TraceRecord {
  enum Kind : uint8_t { kWrist = 1, kGlove = 2, kShake = 3, kEngaged = 4 };
  uint8_t kind = kWrist;
  uint8_t side = 0;
  uint8_t reserved[6] = {};
  int64_t t_ns = 0;
  std::array<double, kGloveJoints + kFingers> values{};

  static TraceRecord FromWrist(Side side, const WristRaw& raw);
  static TraceRecord FromGlove(Side side, const GloveRaw& raw);
  /// At `report.shake_start_ns`.
  static TraceRecord FromShake(Side side, const PseudoHapticReport& report);
  static TraceRecord Engaged(Side side, int64_t t_ns, bool engaged);
  WristRaw ToWrist() const;
  GloveRaw ToGlove() const;
  PseudoHapticReport ToShake() const;
};

/// Records a trace: the servo loop pushes (wait-free), a writer thread drains
/// the ring to the file. Push drops (and counts) when the ring is full.
class TraceWriter {
 public:
  /// Creates the file (and its folder). Throws std::runtime_error naming it.
  explicit TraceWriter(const std::filesystem::path& file, size_t ring_capacity = 1 << 14);
  /// Drains what is left and closes the file.
  ~TraceWriter();
  TraceWriter(const TraceWriter&) = delete;
  TraceWriter& operator=(const TraceWriter&) = delete;

  /// Servo thread(s): one producer per side, so each side has its own ring.
  /// While not recording, records are let go (not counted as dropped).
  bool Push(const TraceRecord& record);
  /// Session thread (the one producer of its own ring): whether the session
  /// let the hands drive from `t_ns` on, for both sides.
  void PushEngaged(int64_t t_ns, bool engaged);
  /// Starts or pauses recording (default: recording). A session starts its
  /// trace when the vehicle answers, so that a replay begun at that moment
  /// lines up with the vehicle.
  void SetRecording(bool recording) { recording_.store(recording, std::memory_order_release); }
  uint64_t written() const { return written_.load(); }
  uint64_t dropped() const { return dropped_.load(); }

 private:
  void Drain();
  std::filesystem::path file_;
  std::FILE* out_ = nullptr;
  /// One ring per side (the servo threads), and the session thread's last.
  std::array<std::unique_ptr<SpscRing<TraceRecord>>, kSides + 1> rings_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> recording_{true};
  std::atomic<uint64_t> written_{0};
  std::atomic<uint64_t> dropped_{0};
  std::thread thread_;
};

/// Reads a whole trace. Throws std::runtime_error naming the file and the
/// record on a bad header, a truncated record or an unknown kind.
std::vector<TraceRecord> ReadTrace(const std::filesystem::path& file);

/// The `replay` driver: plays a trace back at its original timing, relative to
/// the first read — or, when made to hold, relative to Begin, reporting the
/// trace's first readings until then. Force commands are accepted and ignored
/// (counted). At the end of the trace it loops, or keeps the last sample (kNoData).
class ReplayDevice final : public Device {
 public:
  ReplayDevice(std::vector<TraceRecord> records, const DeviceDescription& description, bool loop);

  /// Holds the first readings until Begin (before the servo loop starts).
  void HoldUntilBegin() { holding_.store(true); }
  /// Plays from the top from `now_ns` on. Any thread.
  void Begin(int64_t now_ns) {
    start_ns_.store(now_ns);
    holding_.store(false, std::memory_order_release);
  }
  /// The trace has been played to its end (never, when looping).
  bool finished(int64_t now_ns) const;
  const DeviceDescription& description() const override { return description_; }
  DeviceStatus ReadWrist(Side side, int64_t now_ns, WristRaw& out) override;
  DeviceStatus ReadGlove(Side side, int64_t now_ns, GloveRaw& out) override;
  DeviceStatus WriteWristForce(Side side, const Vec3d&) override;
  DeviceStatus WriteFingerForces(Side side, const std::array<double, kFingers>&) override;
  /// A trace with engaged records says what the recorded session decided:
  /// kHeld while it let the hands drive, kReleased while not, and kReleased
  /// once a trace that does not loop has played to its end (the recorded
  /// hand is gone). Judging again from the replayed motion would not repeat
  /// the recording: a replay read late on a loaded machine loses tremor
  /// reversals, and a hand judged gone mid-lap waits for a rest the open-loop
  /// replay never comes back to. A trace without them (recorded before
  /// they were, or written by hand) leaves it to the session to judge from
  /// the motion (kUnknown), as for a live arm, after kHeldAtStart_s of kHeld:
  /// it needs half a second of motion to see a hand (mediator/engagement.hpp).
  HandPresence Presence(Side side) override;
  static constexpr double kHeldAtStart_s = 1.0;

  uint64_t commands_ignored(Side side) const { return ignored_[Index(side)].load(); }

 private:
  /// Index of the newest record of `kind` for `side` due at `now_ns`, or -1.
  long Due(Side side, TraceRecord::Kind kind, int64_t now_ns, size_t& cursor, int64_t& round);

  std::vector<TraceRecord> records_;
  DeviceDescription description_;
  bool loop_;
  int64_t trace_start_ns_ = 0;
  int64_t trace_span_ns_ = 1;
  std::atomic<int64_t> start_ns_{0};
  std::atomic<bool> holding_{false};
  std::array<size_t, kSides> wrist_cursor_{};
  std::array<size_t, kSides> glove_cursor_{};
  std::array<int64_t, kSides> wrist_round_{};
  std::array<int64_t, kSides> glove_round_{};
  bool has_engaged_ = false;  ///< the trace has engaged records
  std::array<size_t, kSides> engaged_cursor_{};
  std::array<int64_t, kSides> engaged_round_{};
  std::array<bool, kSides> engaged_{true, true};  ///< the newest engaged record played
  std::array<std::atomic<uint64_t>, kSides> ignored_{};
  std::array<int64_t, kSides> last_read_ns_{};  ///< the servo thread's, per side
};

}  // namespace haptel::haptics
