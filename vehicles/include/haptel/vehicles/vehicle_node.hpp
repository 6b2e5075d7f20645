#pragma once
/// @file A vehicle node, one for every kind: the command subscriber, the
/// adapter's control loop with the command watchdog, the state publisher
/// and the camera streamer of one vehicle. Written once over the vehicle's
/// family (families.hpp: the robot's treads or the blimp's channels).
///
/// Threads: DDS delivers commands (validated, then handed over through a
/// seqlock, CommandIntake); the control loop runs at `sim_rate_hz`, applies
/// the watchdog (no fresh command within `watchdog_timeout_s`: the vehicle
/// is made safe — motors stopped, every channel to neutral), steps the
/// adapter and publishes state at `state_rate_hz`; the camera loop grabs,
/// encodes and publishes on its own thread, so a slow or stalled camera never
/// delays the control loop or the watchdog.
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "haptel/config/vehicle.hpp"
#include "haptel/core/periodic_thread.hpp"
#include "haptel/core/seqlock.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/vehicles/command_intake.hpp"
#include "haptel/vehicles/families.hpp"
#include "haptel/vehicles/kind_report.hpp"
#include "haptel/vehicles/vehicle_core.hpp"
#include "haptel/video/camera_source.hpp"
#include "haptel/video/camera_streamer.hpp"

namespace haptel::vehicles {

struct NodeCounters {
  uint64_t commands_accepted = 0;
  uint64_t commands_malformed = 0;  ///< non-finite or out-of-range values: dropped
  uint64_t commands_stale = 0;      ///< older sequence than one already applied: dropped
  uint64_t commands_refused = 0;    ///< from a session that did not own the vehicle: dropped
  uint64_t watchdog_trips = 0;
  uint64_t states_published = 0;
  uint64_t frames_published = 0;
  uint64_t frames_failed = 0;  ///< grabbed but not encoded
  uint64_t grabs_failed = 0;   ///< the camera source delivered no frame
  uint64_t camera_stalls = 0;  ///< stretches of failed grabs long enough to count (GrabMonitor)
  bool camera_ended = false;   ///< a file source that does not loop has ended
  uint64_t link_queue_dropped = 0;        ///< received packets the link fault's rate queue dropped
  uint64_t link_queue_dropped_bytes = 0;  ///< their bytes
  uint64_t key_frame_requests = 0;        ///< the operator's, received (a video frame lost)
  uint64_t key_frames_sent = 0;           ///< frames published that decode alone
  uint64_t frames_skipped = 0;            ///< grabbed but skipped to fit the link
  uint64_t frames_passed_through = 0;     ///< a camera's own JPEGs sent undecoded
  uint32_t target_kbps = 0;  ///< the operator's last estimate of the link (0: none came)
  uint64_t video_feedback_refused =
      0;  ///< video feedback from another session than the owner: ignored
  bool watchdog_expired = true;
  // The further cameras' (every camera but the driven one), summed.
  uint64_t camera_commands_accepted = 0;
  uint64_t camera_commands_malformed = 0;  ///< wrong camera name, non-finite, out of range
  uint64_t camera_commands_refused = 0;    ///< from another writer than the camera's holder
  uint64_t camera_frames_published = 0;
};

/// A node's counters: its commands' and its camera's.
template <typename Command>
NodeCounters MakeNodeCounters(const CommandIntake<Command>& commands,
                              const video::CameraCounters& camera, uint64_t states_published) {
  NodeCounters c;
  c.commands_accepted = commands.accepted();
  c.commands_malformed = commands.malformed();
  c.commands_stale = commands.stale();
  c.commands_refused = commands.refused();
  c.watchdog_trips = commands.watchdog_trips();
  c.watchdog_expired = commands.watchdog_expired();
  c.states_published = states_published;
  c.frames_published = camera.frames_published;
  c.frames_failed = camera.frames_failed;
  c.grabs_failed = camera.grabs_failed;
  c.camera_stalls = camera.camera_stalls;
  c.camera_ended = camera.camera_ended;
  c.key_frame_requests = camera.key_frame_requests;
  c.key_frames_sent = camera.key_frames_sent;
  c.frames_skipped = camera.frames_skipped;
  c.frames_passed_through = camera.frames_passed_through;
  c.target_kbps = camera.target_kbps;
  c.video_feedback_refused = camera.feedback_refused;
  return c;
}

/// A running vehicle node, whatever its family.
class Node {
 public:
  virtual ~Node() = default;
  virtual void Start() = 0;
  /// Makes the vehicle safe, publishes a last state, stops every thread.
  virtual void Stop() = 0;
  virtual NodeCounters Counters() const = 0;
  /// The adapter lost its hardware in the loop (cli::HardwareLost: a serial
  /// port or CAN bus that vanished): its message, once; the node has stopped
  /// driving it. Empty: none.
  virtual std::string AdapterFailure() const = 0;
  /// The first fault the adapter reported in its state (a motor
  /// controller's error, a servo controller that cannot be trusted): the
  /// vehicle stopped itself and says so in its states. Empty: none.
  virtual std::string Fault() const = 0;
  /// How the watchdog and the end leave the vehicle: "motors stopped", ….
  virtual const char* MadeSafe() const = 0;
  virtual const char* AtRest() const = 0;
};

template <class Family>
class VehicleNodeOf : public Node {
 public:
  using Adapter = typename Family::Adapter;
  /// Validates `config` first (VehicleConfig::ValidateOrThrow:
  /// ConfigFieldError), before any DDS participant exists. `camera` (the
  /// opened source of its video) and `adapter` must not be null; `report`
  /// (the kind's own topic, over the adapter) may be.
  /// `extra_cameras`: the sources of config.extra_cameras, in their order
  /// (each its own stream, aimed by CameraCommands from its holder).
  VehicleNodeOf(const VehicleConfig& config, std::unique_ptr<video::CameraSource> camera,
                std::unique_ptr<Adapter> adapter, std::unique_ptr<KindReport> report = nullptr,
                std::vector<std::unique_ptr<video::CameraSource>> extra_cameras = {});
  ~VehicleNodeOf() override;
  VehicleNodeOf(const VehicleNodeOf&) = delete;
  VehicleNodeOf& operator=(const VehicleNodeOf&) = delete;

  void Start() override;
  void Stop() override;
  NodeCounters Counters() const override;
  std::string AdapterFailure() const override;
  std::string Fault() const override;
  const char* MadeSafe() const override { return Family::kMadeSafe; }
  const char* AtRest() const override { return Family::kAtRest; }

 private:
  /// A further camera: its holder's commands (one writer at a time, as the
  /// driving owner: CommandIntake, whose watchdog is not used — a camera
  /// left alone stays where it was), its stream, its aim.
  struct CameraRig {
    size_t index = 0;  ///< in VehicleConfig::Cameras()
    CameraConfig config;
    CameraRange range;
    CommandIntake<CameraAim> commands{CommandOwner::kFreeAfter_s};
    std::unique_ptr<link::CameraCommandReader> reader;
    std::unique_ptr<video::CameraStreamer> streamer;
    Seqlock<CameraAim> shown;  ///< as the picture shows it (control thread writes)
    std::atomic<uint64_t> last_seq{0};
    std::atomic<int64_t> held_since_wall_ns{0};
    uint64_t holder_writer_hash = 0;  ///< status thread: who held it last
  };
  void ControlTick(int64_t now_ns);
  void PublishState(int64_t now_ns);
  void OnCameraCommand(CameraRig& rig, const msg::CameraCommand& cmd, const link::WriterId& writer);
  /// Control thread: each further camera's newest aim to the adapter (its
  /// servos), before the tick; after it, the picture's pose from where the
  /// adapter says it points.
  void AimCameras();
  void ShowCameras();
  void PublishCameras(int64_t now_ns);

  /// The control step (commands, watchdog, adapter, state): the same one a
  /// simulated-time run steps in the operator's process.
  VehicleCoreOf<Family> core_;
  std::atomic<uint64_t> states_{0};
  std::atomic<bool> stopped_{false};
  /// A participant that holds one of the further cameras (a camera
  /// station) may not drive: the driving intake's bar over the rigs' leases.
  struct CameraHolders final : DrivingBar {
    const std::vector<std::unique_ptr<CameraRig>>* rigs = nullptr;
    bool Bars(const link::WriterId& writer, int64_t now_ns) const override {
      for (const auto& r : *rigs) {
        if (r->commands.HeldByParticipantOf(writer, now_ns)) return true;
      }
      return false;
    }
  };
  CameraHolders camera_holders_;

  // Declared last: destroyed first, so no DDS callback outlives the rest.
  std::unique_ptr<link::Participant> participant_;
  std::unique_ptr<typename Family::StateWriter> state_writer_;
  std::unique_ptr<KindReport> report_;  ///< null: the kind has none
  std::unique_ptr<video::CameraStreamer> camera_;
  /// The cameras' shares of the link (only with further cameras).
  std::unique_ptr<video::LinkShare> share_;
  std::vector<std::unique_ptr<CameraRig>> rigs_;
  std::unique_ptr<link::CameraStatusWriter> camera_status_;
  msg::CameraStatus camera_status_msg_;
  uint64_t camera_status_seq_ = 0;
  int64_t camera_status_ns_ = 0;
  uint64_t camera_status_sum_ = 0;  ///< the last published cameras' seqs and holders, summed
  std::unique_ptr<typename Family::CommandReader> command_reader_;
  std::unique_ptr<PeriodicThread> control_;
};

using RobotNode = VehicleNodeOf<RobotFamily>;
using BlimpNode = VehicleNodeOf<BlimpFamily>;

extern template class VehicleNodeOf<RobotFamily>;
extern template class VehicleNodeOf<BlimpFamily>;

}  // namespace haptel::vehicles
