#pragma once
/// @file A vehicle's control step, apart from its threads and DDS: the
/// command intake with its watchdog, the adapter stepped once a control
/// tick, and the state message every `state_rate_hz`. Written once over the
/// vehicle's family (families.hpp).
///
/// The vehicle node (vehicle_node.hpp) runs it with a DDS reader feeding
/// OnCommand and a periodic thread calling ControlTick; `haptel run
/// --simulated-time` runs the very same step in the operator's process, on
/// its simulated clock (no DDS, no thread), so the two cannot differ.
///
/// Threads: OnCommand may come from another thread than ControlTick (the
/// intake hands commands over through a seqlock); everything else is the
/// control thread's.
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "haptel/config/vehicle.hpp"
#include "haptel/vehicles/command_intake.hpp"
#include "haptel/vehicles/families.hpp"
#include "haptel/vehicles/truth_writer.hpp"

namespace haptel::vehicles {

template <class Family>
class VehicleCoreOf {
 public:
  using Adapter = typename Family::Adapter;
  using Command = typename Family::Command;

  /// Validates `config` (VehicleConfig::ValidateOrThrow: ConfigFieldError);
  /// `adapter` must not be null. The adapter starts at rest (Family::Prepare).
  /// With config.truth_file, the truth record is created there (a ConfigError
  /// when the adapter has no truth: hardware; std::runtime_error when the
  /// file cannot be written).
  VehicleCoreOf(const VehicleConfig& config, std::unique_ptr<Adapter> adapter);

  /// A command message from `writer` (as DDS gave it with the sample)
  /// received at `now_ns`: decoded, range-checked and offered to the intake
  /// (owner, sequence, watchdog).
  void OnCommand(const typename Family::CommandMsg& cmd, const link::WriterId& writer,
                 int64_t now_ns);
  /// The same from the one session that steps this vehicle in its own
  /// process (link::kInProcessWriter).
  void OnCommand(const typename Family::CommandMsg& cmd, int64_t now_ns) {
    OnCommand(cmd, link::kInProcessWriter, now_ns);
  }
  /// One control tick at `now_ns`: the watchdog (expired: made safe), else
  /// the newest command applied, then the adapter stepped (and its truth
  /// written, stamped `now_ns`, with a truth record). False when the
  /// adapter has lost its hardware (cli::HardwareLost; nothing more is
  /// driven; AdapterFailure says why).
  bool ControlTick(int64_t now_ns);
  /// Whether the tick just run is one that publishes a state (every
  /// sim_rate_hz / state_rate_hz ticks, from the first).
  bool state_due() const { return state_due_; }
  /// The state message at `now_ns`, the next in sequence: the adapter's
  /// state, the watchdog, the command it echoes, its owner, a fault. Its
  /// stamp is the vehicle's own clock when it measured (a simulator's
  /// reality offsets and drifts it from `now_ns`'s).
  typename Family::StateMsg& MakeState(int64_t now_ns);
  /// The end: made safe and stepped once (unless the hardware is gone).
  void MakeSafe();

  /// Set-up, before the first command: writers `bar` bars may not drive
  /// (the participants that hold one of its cameras); it must outlive the
  /// core.
  void SetDrivingBar(const DrivingBar* bar) { commands_.SetBar(bar); }

  const Adapter& adapter() const { return *adapter_; }
  /// The control thread's, between ticks (a further camera's aim).
  Adapter& adapter() { return *adapter_; }
  const CommandIntake<Command>& commands() const { return commands_; }
  const VehicleConfig& config() const { return config_; }
  /// See Node::AdapterFailure and Node::Fault. Any thread.
  std::string AdapterFailure() const;
  std::string Fault() const;

 private:
  VehicleConfig config_;
  std::unique_ptr<Adapter> adapter_;
  CommandIntake<Command> commands_;
  int64_t last_tick_ns_ = 0;
  uint64_t tick_count_ = 0;
  uint64_t state_seq_ = 0;
  int ticks_per_state_ = 1;
  bool state_due_ = false;
  std::atomic<bool> failed_{false};
  std::string failure_;  ///< written once before failed_ is set
  std::atomic<bool> faulted_{false};
  std::string fault_;  ///< written once before faulted_ is set
  typename Family::StateMsg state_msg_;
  std::unique_ptr<TruthWriter> truth_;
  /// The vehicle's clock: now + offset + drift × (now − first tick).
  int64_t clock_offset_ns_ = 0;
  double clock_drift_ = 0.0;
  int64_t first_tick_ns_ = 0;
};

using RobotCore = VehicleCoreOf<RobotFamily>;
using BlimpCore = VehicleCoreOf<BlimpFamily>;

extern template class VehicleCoreOf<RobotFamily>;
extern template class VehicleCoreOf<BlimpFamily>;

}  // namespace haptel::vehicles
