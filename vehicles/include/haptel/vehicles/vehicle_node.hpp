#pragma once
/// @file A vehicle node: the command subscriber, the adapter's control loop,
/// the state publisher and the camera streamer of one vehicle.
///
/// Threads: DDS delivers commands (validated, then handed over through a
/// seqlock); the control loop runs at `sim_rate_hz`, applies the watchdog and
/// quantisation, steps the adapter and publishes state at `state_rate_hz`;
/// the camera loop grabs a frame from the camera source (synthetic, device or
/// file), JPEG-encodes and publishes it — on its own thread, so a slow or
/// stalled camera never delays the control loop or the watchdog.
#include <atomic>
#include <cstdint>
#include <memory>

#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/core/periodic_thread.hpp"
#include "haptel/core/seqlock.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/vehicles/adapter.hpp"
#include "haptel/vehicles/camera_streamer.hpp"
#include "haptel/vehicles/command_intake.hpp"
#include "haptel/video/camera_source.hpp"

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
  bool watchdog_expired = true;
};

/// A node's counters: its commands' and its camera's.
template <typename Command>
NodeCounters MakeNodeCounters(const CommandIntake<Command>& commands, const CameraCounters& camera,
                              uint64_t states_published) {
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
  return c;
}

/// The adapter a vehicle file's kind names: "sim-robot" the simulated tank;
/// "can-robot" the robot on SocketCAN (config.can.interface; throws
/// CanUnavailable when the bus cannot be opened); "can-robot-sim" the
/// simulated tank behind emulated CAN nodes. The CAN kinds log their bus
/// traffic to config.can.log_dir/<name>-<UTC>.log (candump -L) when set.
std::unique_ptr<VehicleAdapter> MakeVehicleAdapter(const VehicleConfig& config, const Track& track);

class VehicleNode {
 public:
  /// `track` (the simulated world) must outlive the node. `camera` is the
  /// opened source of its video (video::MakeCameraSource), made before the
  /// node so that a camera that cannot open stops the vehicle before it
  /// publishes anything; must not be null. Validates `config` first
  /// (VehicleConfig::ValidateOrThrow: ConfigFieldError).
  /// `adapter`: made by the caller (to open a bus before anything else), or
  /// null for MakeVehicleAdapter's.
  VehicleNode(const VehicleConfig& config, const Track& track,
              std::unique_ptr<video::CameraSource> camera, std::unique_ptr<VehicleAdapter> adapter = nullptr);
  ~VehicleNode();

  void Start();
  /// Stops the motors, publishes a last state, stops every thread.
  void Stop();
  NodeCounters Counters() const;

 private:
  struct Wheels {
    float left = 0.0F;
    float right = 0.0F;
  };
  void OnCommand(const msg::DriveCommand& cmd);
  void ControlTick(int64_t now_ns);
  void PublishState(int64_t now_ns);

  VehicleConfig config_;
  std::unique_ptr<VehicleAdapter> adapter_;
  CommandIntake<Wheels> commands_;
  int64_t last_tick_ns_ = 0;
  uint64_t tick_count_ = 0;
  uint64_t state_seq_ = 0;
  int ticks_per_state_ = 1;
  std::atomic<uint64_t> states_{0};
  std::atomic<bool> stopped_{false};
  msg::VehicleState state_msg_;

  // Declared last: destroyed first, so no DDS callback outlives the rest.
  std::unique_ptr<link::Participant> participant_;
  std::unique_ptr<link::StateWriter> state_writer_;
  std::unique_ptr<CameraStreamer> camera_;
  std::unique_ptr<link::CommandReader> command_reader_;
  std::unique_ptr<PeriodicThread> control_;
};

}  // namespace haptel::vehicles
