#pragma once
/// @file A blimp's vehicle node: the BlimpCommand subscriber, the adapter's
/// control loop with the command watchdog (every channel to neutral within
/// `watchdog_timeout_s`), the BlimpState publisher and the camera streamer.
/// The same threads and topics as the robot's VehicleNode.
#include <atomic>
#include <cstdint>
#include <memory>

#include "haptel/config/vehicle.hpp"
#include "haptel/core/periodic_thread.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/vehicles/blimp_adapter.hpp"
#include "haptel/vehicles/camera_streamer.hpp"
#include "haptel/vehicles/vehicle_node.hpp"

namespace haptel::vehicles {

class BlimpNode {
 public:
  /// Validates `config`; `camera` and `adapter` must not be null.
  BlimpNode(const VehicleConfig& config, std::unique_ptr<video::CameraSource> camera,
            std::unique_ptr<BlimpAdapter> adapter);
  ~BlimpNode();
  BlimpNode(const BlimpNode&) = delete;
  BlimpNode& operator=(const BlimpNode&) = delete;

  void Start();
  /// Every channel to neutral, a last state, every thread stopped.
  void Stop();
  NodeCounters Counters() const;
  /// The adapter lost its hardware in the loop (cli::HardwareLost: a serial port that vanished): its
  /// message, once; the node has stopped driving it. Empty: none.
  std::string AdapterFailure() const;

 private:
  void OnCommand(const msg::BlimpCommand& cmd);
  void ControlTick(int64_t now_ns);
  void PublishState(int64_t now_ns);

  VehicleConfig config_;
  std::unique_ptr<BlimpAdapter> adapter_;
  CommandIntake<BlimpCommand> commands_;
  int64_t last_tick_ns_ = 0;
  uint64_t tick_count_ = 0;
  uint64_t state_seq_ = 0;
  int ticks_per_state_ = 1;
  std::atomic<uint64_t> states_{0};
  std::atomic<bool> stopped_{false};
  std::atomic<bool> failed_{false};
  std::string failure_;  ///< written once before failed_ is set
  msg::BlimpState state_msg_;

  // Declared last: destroyed first, so no DDS callback outlives the rest.
  std::unique_ptr<link::Participant> participant_;
  std::unique_ptr<link::BlimpStateWriter> state_writer_;
  std::unique_ptr<CameraStreamer> camera_;
  std::unique_ptr<link::BlimpCommandReader> command_reader_;
  std::unique_ptr<PeriodicThread> control_;
};

}  // namespace haptel::vehicles
