#pragma once
/// @file `haptel replay FILE.mcap --drive`: the commands a session file
/// recorded, sent to a vehicle again at their recorded times — a simulated
/// robot spawned as the run spawned it (its vehicle file, its track, on
/// the run's domain or another), or one already running (--attach) — and
/// the lap timed from its states on the run's track, beside the lap the
/// file recorded. Open loop: what the operator did, not what he would do
/// now, so a simulated robot without noise drives the recorded lap again.
///
/// The recorded commands start counting when the recorded vehicle first
/// answered (its first state in the file: the run's commands before it
/// reached no one) and are sent from when this vehicle first answers this
/// sender: a state saying it heard the stopped commands sent until then (a
/// state alone may come before its command reader has matched the sender,
/// and the first commands would be lost).
#include <atomic>
#include <cstdint>
#include <string>

#include "haptel/mcap/reader.hpp"
#include "haptel/mediator/session.hpp"

namespace haptel::replay {

/// What the drive did, and what the file says the run did.
struct DriveReport {
  uint64_t commands_sent = 0;
  uint64_t commands_before_up = 0;  ///< recorded before the vehicle answered: not sent
  double commands_s = 0.0;          ///< the recorded commands' span
  int gates_total = 0;
  int gates_passed = 0;
  bool completed = false;
  double lap_time_s = 0.0;
  /// States in which the vehicle said its watchdog had stopped it while
  /// recorded commands were still due: the sender or the link starved past
  /// the vehicle's time-out, so this drive is not the record's (an open-loop
  /// path differs after it).
  uint64_t watchdog_stops = 0;
  /// The file's lap events (haptel/session/lap_events): gates and the
  /// finish; -1 when the file has no lap events.
  int recorded_gates = -1;
  bool recorded_completed = false;
  double recorded_lap_time_s = 0.0;
  /// The drive passed as many gates as the record (whether it also crossed
  /// the finish is said apart: open loop, the last metres drift most).
  bool Reproduced() const { return recorded_gates >= 0 && gates_passed == recorded_gates; }
};

/// The file's robot commands, states and lap events, read once. Throws
/// cli::InputError naming the file when it holds no robot commands sent or
/// no state received (a blimp's session is not driven again yet).
struct RecordedDrive {
  struct Command {
    uint64_t log_ns = 0;
    TreadCommand command;
  };
  std::vector<Command> commands;  ///< from the first recorded state on
  uint64_t commands_before_up = 0;
  uint64_t first_state_ns = 0;
  int gates = -1;
  bool completed = false;
  double lap_time_s = 0.0;
};
RecordedDrive ReadRecordedDrive(const mcap::Reader& reader);

/// Drives `setup`'s vehicle (spawned unless setup.attach) with `recorded`'s
/// commands and times its lap on setup's track. Ends after the last
/// command (and a second to settle), at the lap's finish, or when
/// `interrupted`. Throws std::runtime_error when the vehicle cannot be
/// linked or does not answer within its start-up timeout.
DriveReport DriveAgain(const RecordedDrive& recorded, const mediator::SessionSetup& setup,
                       const std::atomic<bool>& interrupted);

}  // namespace haptel::replay
