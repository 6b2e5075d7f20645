#pragma once
/// @file The haptic servo loop: device I/O and force computation at ~1 kHz.
///
/// Two-sided mode (the original's scheme): one thread per arm, the right arm's
/// schedule offset by half a period so the two sides' device I/O never hits a
/// shared link at the same instant, both meeting at a rendezvous at the end of
/// every cycle so they keep one rate. One-sided mode: both arms on one thread.
///
/// Each cycle, per arm: slow channels (glove, grasp strings) every N-th cycle;
/// the wrist tracker; forces from the latest set-point (interface field, proxy
/// coupling, direct force, finger forces) plus gravity compensation, through
/// ForceSafety; the commands to the device. A cycle allocates nothing, takes
/// no lock a slower thread can hold, and logs nothing: it counts.
///
/// The set-point is read with a bounded number of seqlock attempts
/// (Hal::TrySetpoint); when a feeder's store stays in progress through them
/// the tick uses the last good set-point and counts it.
///
/// With `servo.passivity` on, each wrist port — the interface's force field,
/// and the physics thread's proxy coupling with its direct force — has a
/// passivity observer and controller per axis (passivity.hpp) that adds just
/// the damping that keeps the port from generating energy. The fingers have
/// none: the loop has no finger velocity (the glove is read every N-th cycle
/// and the grasp strings report force), and their unilateral pulls come from
/// the physics thread's proxy fingers.
///
/// A device behind a link (Device::LinkPassivity: the udp driver's protocol
/// version 2, a server whose own servo.passivity is on) gets the two-port
/// instead (twoport.hpp): the loop observes its end of the channel (the
/// wrist force it commands against the arm's motion it is handed), sends
/// its report with the commands, while the server damps the arm on its
/// side. Its own deficit it charges to the arm's end (`servo.passivity_link:
/// charge`, the default) or dissipates on the virtual environment's port
/// (`admittance`: the position the force field and the coupling read is the
/// arm's plus the admittance controller's offset). With `servo.passivity` on the loop
/// always sends its report, so a server knows to run its end; until the
/// server reports back (a v1 server, or its passivity off) the one-port
/// ports act as for a local device.
#include <array>
#include <atomic>
#include <barrier>
#include <cstdint>
#include <memory>
#include <thread>

#include "haptel/config/calibration.hpp"
#include "haptel/config/device.hpp"
#include "haptel/core/loop_meter.hpp"
#include "haptel/core/seqlock.hpp"
#include "haptel/haptics/device.hpp"
#include "haptel/haptics/hal.hpp"
#include "haptel/haptics/safety.hpp"
#include "haptel/haptics/servo_passivity.hpp"
#include "haptel/haptics/servo_tap.hpp"

namespace haptel::haptics {

class GravityGrid;
class TraceWriter;

/// Events one arm's loop counts instead of logging.
struct ServoCounters {
  uint64_t cycles = 0;
  uint64_t slow_reads = 0;         ///< glove/grasp reads
  uint64_t device_lost_ticks = 0;  ///< cycles the arm reported kLost (forces zeroed)
  uint64_t no_data_ticks = 0;      ///< cycles without a fresh wrist reading
  uint64_t write_failures = 0;     ///< force commands the device did not take
  /// Ticks whose set-point read met a feeder's store in progress through every
  /// bounded attempt: the tick used the last good set-point.
  uint64_t setpoint_read_fallbacks = 0;
  uint64_t passivity_ticks = 0;         ///< ticks the passivity controller added damping
  double passivity_dissipated_j = 0.0;  ///< J it dissipated (predicted T·α·v², summed)
  double passivity_max_alpha = 0.0;     ///< N·s/m, the largest damping it added
  /// Two-port across a link (the loop's end counts in the three above: its
  /// ticks, and the energy its offset returned): the device end's, as its
  /// server reports them, summed over the link's restarts.
  uint64_t passivity_device_ticks = 0;         ///< ticks the device end's controller damped the arm
  double passivity_device_dissipated_j = 0.0;  ///< J it dissipated
  double passivity_device_max_alpha = 0.0;     ///< N·s/m, the largest damping it added
  uint64_t passivity_link_ticks = 0;           ///< ticks the two-port ran (the far end reporting)
  SafetyCounters safety;
};

class ServoLoop {
 public:
  /// `device`, `hal` and `gravity` (optional, may be null) must outlive the
  /// loop. Validates `config` and `calibration` first (ConfigFieldError).
  ServoLoop(Device& device, Hal& hal, const DeviceConfig& config,
            const DeviceCalibration& calibration, const GravityGrid* gravity = nullptr);
  ~ServoLoop();
  ServoLoop(const ServoLoop&) = delete;
  ServoLoop& operator=(const ServoLoop&) = delete;

  /// Records every device reading into `trace` (null: none). Before Start.
  void SetTrace(TraceWriter* trace) { trace_ = trace; }
  /// Tells `tap` every tick of each arm (null: none; a session file's
  /// recorder), the forces zero on a tick that computed none. Before Start.
  void SetTap(ServoTap* tap) { tap_ = tap; }
  void Start();
  void Stop();
  bool running() const { return running_.load(); }

  /// One cycle of one arm at `now_ns`. Called by the loop threads; public so
  /// tests can drive it deterministically. Each side from one thread only.
  void Tick(Side side, int64_t now_ns);

  /// Rate and period statistics of an arm's thread (in one-sided mode both
  /// sides report the single thread).
  LoopStats Stats(Side side) const;
  /// Stats of the loop as a whole: the slower of the arms.
  LoopStats Stats() const;
  const Histogram& period_histogram(Side side) const;
  /// The periods of the ticks that rendered a cue (Hal::SetCue: a fleet's
  /// switch), start-to-start, of the same thread as period_histogram: the
  /// loop's timing while the cue plays, apart from the rest of the run.
  const Histogram& cue_period_histogram(Side side) const;
  /// Counters of one arm. Safe to read while the loop runs.
  ServoCounters Counters(Side side) const;
  bool memory_locked() const { return memory_locked_; }
  const DeviceConfig& config() const { return config_; }

 private:
  struct Arm {
    explicit Arm(ForceSafety s) : safety(s) {}
    ForceSafety safety;
    bool connected = false;
    bool have_previous = false;
    Vec3d previous_position{};
    int64_t previous_ns = 0;
    Vec3d velocity{};          ///< low-pass filtered, m/s
    Vec3d displacement{};      ///< m, since the previous tick (0 without a fresh reading)
    int64_t last_tick_ns = 0;  ///< 0: no previous tick to take a period from
    ForceSetpoint setpoint;    ///< the last good set-point read
    ArmPassivity passivity;    ///< the one-port ports and the link's two-port end
    uint64_t cycle = 0;
    WristRaw wrist{};
    GloveRaw glove{};
    bool cue_felt = false;             ///< the last tick added a cue's force
    ServoCounters counters;            ///< the arm's thread only
    Seqlock<ServoCounters> published;  ///< copy for readers, every cycle
  };
  /// Runs once per cycle while both arms wait at the rendezvous: advances the
  /// shared schedule, re-anchors it when hopelessly behind, latches stop.
  struct Completion {
    ServoLoop* loop;
    void operator()() noexcept { loop->EndCycle(); }
  };
  void EndCycle() noexcept;
  void RunThread(int thread_index);
  // Tick's steps, in its order.
  void ReadSlowChannels(Arm& arm, Side side, int64_t now_ns);
  void OnArmLost(Arm& arm, Side side);
  void TrackWrist(Arm& arm, Side side, int64_t now_ns);
  void WriteForces(Arm& arm, Side side, int64_t now_ns, const Vec3d& wrist,
                   const std::array<double, kFingers>& fingers);

  Device& device_;
  Hal& hal_;
  DeviceConfig config_;
  DeviceCalibration calibration_;
  const GravityGrid* gravity_;
  /// Passivity on and a device behind a link (Device::HasLink): only then
  /// does each tick observe the link's port and report it.
  bool observe_link_;
  TraceWriter* trace_ = nullptr;
  ServoTap* tap_ = nullptr;
  std::array<std::unique_ptr<Arm>, kSides> arms_;
  std::array<LoopMeter, kSides> meters_;
  /// Per thread, as meters_: the periods of the ticks that felt a cue.
  std::array<Histogram, kSides> cue_periods_{{{10.0, 2000}, {10.0, 2000}}};
  std::unique_ptr<std::barrier<Completion>> rendezvous_;
  std::array<std::thread, kSides> threads_;
  std::atomic<bool> running_{false};
  std::atomic<bool> stop_requested_{false};
  // Written only in the completion step (or before the threads start); the
  // barrier orders those writes before every arm's next read.
  bool stop_latched_ = false;
  int64_t anchor_ns_ = 0;  ///< schedule origin
  uint64_t cycle_ = 0;     ///< cycles since the anchor
  int64_t period_ns_ = 0;
  bool two_threads_ = false;
  bool memory_locked_ = false;
};

}  // namespace haptel::haptics
