#pragma once
/// @file The session's link to its vehicle: the vehicle process it spawns
/// (or none, for a vehicle that runs elsewhere), the DDS participant, the
/// command writer, the state inbox and the video receiver.
///
/// Threads: DDS callbacks push states into the inbox (a short lock) and
/// frames into the video receiver; the session thread drains the inbox,
/// sends commands and asks whether the vehicle is still there.
#include <cstdint>
#include <deque>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>

#include "haptel/config/link.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/core/blimp_command.hpp"
#include "haptel/core/child_process.hpp"
#include "haptel/core/histogram.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/mediator/video_receiver.hpp"

namespace haptel::mediator {

/// What the operator side can tell of the link and the vehicle's health from
/// the states alone (the vehicle counts malformed and stale commands apart,
/// in its own stop summary; a state carries only how many it accepted).
struct LinkCounts {
  /// States that never arrived: gaps in their sequence numbers.
  uint64_t states_missed = 0;
  /// Times the vehicle's command watchdog tripped after commands had driven it.
  uint64_t watchdog_trips = 0;
  /// Commands the vehicle did not accept — lost on the way, malformed or
  /// stale — up to the last one it applied: the sequence numbers it echoed
  /// minus the commands it counted as accepted, from the first state that
  /// echoes one (commands sent before it listened are not counted).
  uint64_t commands_dropped = 0;
};

/// Vehicle states as they arrive (DDS thread), drained by the session loop.
/// Measures the command round trip from the echo each state carries, and
/// counts what the states show (LinkCounts). One for each vehicle type's
/// state: msg::VehicleState (the robot) and msg::BlimpState.
template <typename State>
class StateInboxOf {
 public:
  struct Entry {
    State state;
    int64_t received_ns;
  };
  void Push(const State& s);
  std::deque<Entry> Drain();
  int64_t last_received_ns() const;
  /// Round trip of echoed commands minus their wait at the vehicle, µs
  /// (the histogram is safe to read while the DDS thread records).
  const Histogram& Rtt() const { return rtt_; }
  /// Forgets the round trips so far (a benchmark's warm-up).
  void ResetRtt() { rtt_.Reset(); }
  LinkCounts Counts() const;

 private:
  mutable std::mutex mutex_;
  std::deque<Entry> entries_;
  int64_t last_received_ns_ = 0;
  uint64_t last_echo_seq_ = 0;
  LinkCounts counts_;
  bool have_state_ = false;
  uint64_t last_state_seq_ = 0;
  bool watchdog_was_tripped_ = true;
  // The baseline of commands_dropped: the first state echoing an applied command.
  bool have_baseline_ = false;
  uint64_t first_echo_seq_ = 0;
  uint64_t first_accepted_ = 0;
  uint64_t dropped_before_ = 0;  ///< counted against earlier baselines
  Histogram rtt_{10.0, 200000};  // 10 µs bins up to 2 s (a faulted link: 400 ms each way and more)
};
using StateInbox = StateInboxOf<msg::VehicleState>;
using BlimpStateInbox = StateInboxOf<msg::BlimpState>;

struct VehicleLinkOptions {
  VehicleConfig vehicle;
  LinkConfig link;
  /// The track the spawned simulator drives on.
  std::filesystem::path track_file;
  /// haptel-vehicle to spawn; empty: the vehicle runs elsewhere.
  std::filesystem::path program;
  /// Decode the video (only when something shows or records it).
  bool decode_video = true;
};

class VehicleLink {
 public:
  /// Spawns the vehicle (if a program is given) and joins the DDS domain.
  /// Throws std::runtime_error when either cannot be done.
  explicit VehicleLink(const VehicleLinkOptions& options);
  /// Stops the vehicle: a zero command, then the spawned process ends.
  ~VehicleLink();
  VehicleLink(const VehicleLink&) = delete;
  VehicleLink& operator=(const VehicleLink&) = delete;

  /// Whether the vehicle is a blimp (BlimpCommand and BlimpState on the
  /// link) rather than the robot (DriveCommand and VehicleState).
  bool blimp() const { return blimp_commands_ != nullptr; }
  /// Sends a motor command (each in [-1, 1]) stamped now; the robot only.
  void Send(double left, double right);
  /// Sends a blimp command stamped now; a blimp only.
  void Send(const BlimpCommand& command);
  /// Zero command, then ends the spawned process. Safe to call twice.
  void Stop();

  StateInbox& inbox() { return inbox_; }
  const StateInbox& inbox() const { return inbox_; }
  BlimpStateInbox& blimp_inbox() { return blimp_inbox_; }
  /// The round trip, whichever vehicle it is.
  const Histogram& Rtt() const { return blimp() ? blimp_inbox_.Rtt() : inbox_.Rtt(); }
  void ResetRtt() { blimp() ? blimp_inbox_.ResetRtt() : inbox_.ResetRtt(); }
  int64_t last_received_ns() const { return blimp() ? blimp_inbox_.last_received_ns() : inbox_.last_received_ns(); }
  LinkCounts Counts() const { return blimp() ? blimp_inbox_.Counts() : inbox_.Counts(); }
  const VideoReceiver& video() const { return *video_; }
  /// False once a spawned vehicle process has exited (always true for a
  /// vehicle that runs elsewhere).
  bool ProcessAlive();
  /// The spawned process's pid (0: none) and how it ended.
  int pid() const;
  std::string ExitDescription() const;
  const std::string& name() const { return options_.vehicle.name; }
  int domain() const { return options_.link.domain_id; }

  /// This run's operator session (random, never 0): every command carries
  /// it and the operator's name ("haptel run, user@host pid N"), and the
  /// vehicle obeys one session at a time (its state names the owner). The
  /// last command, in Stop, releases the vehicle.
  uint64_t session() const { return session_; }
  /// How many vehicles answer under this name: the participants writing its
  /// state or reading its commands (DDS discovery). More than one is a
  /// conflict: two vehicles named alike on one domain.
  int VehiclesOnTopic() const;

 private:
  VehicleLinkOptions options_;
  std::unique_ptr<ChildProcess> process_;
  StateInbox inbox_;
  BlimpStateInbox blimp_inbox_;
  std::unique_ptr<link::Participant> participant_;
  std::unique_ptr<link::CommandWriter> commands_;
  std::unique_ptr<link::StateReader> states_;
  std::unique_ptr<link::BlimpCommandWriter> blimp_commands_;
  std::unique_ptr<link::BlimpStateReader> blimp_states_;
  msg::BlimpCommand blimp_command_;
  std::unique_ptr<VideoReceiver> video_;
  msg::DriveCommand command_;
  uint64_t seq_ = 0;
  uint64_t session_ = 0;
  bool stopped_ = false;
};

}  // namespace haptel::mediator
