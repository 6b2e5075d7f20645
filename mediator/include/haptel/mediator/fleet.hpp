#pragma once
/// @file One operator, several vehicles (`haptel run --fleet FILE`, issue 30).
///
/// One session holds every vehicle of a fleet file: each vehicle's link
/// (its own process, or one already running), its family's part (track or
/// course, lap timer, interface, the operator's view of it) and its health,
/// over one haptic device. One vehicle is driven at a time; every other is
/// held safe at every tick (the family's safe command: the robot stopped,
/// the blimp at neutral with its helix level and its engines off), never
/// left to its own watchdog.
///
/// Who commands each vehicle is its CommandMux (command_mux.hpp): the
/// input "operator" while it is the driven one, and the lock "handover"
/// while the operator turns to it or away from it (zero at once when the
/// lock takes it). A handover runs from the switch request until the newly
/// driven vehicle's first state that echoes a command sent after its lock
/// was released — the lock is released once a state newer than the request
/// came in, so the operator sees where it is before commanding it. A turn
/// to a vehicle that has not answered yet is not timed (its start-up is no
/// handover); it is counted apart.
///
/// The automatic operator drives each vehicle until its lap is done or the
/// fleet's time slice ends, then turns to the next whose course is not
/// done. A person turns it at any time (Tab or the controller's Back: the
/// next; 1..9: that one), in the view's window: the switch is felt (a cue
/// on both hands) and shown (the driven tile framed, a line on the HUD),
/// and the slice starts again from it.
///
/// With a person as the operator (`--operator person`) the person drives
/// the vehicle turned to, with the interface that fits its kind (the fleet
/// file's, else what a person at that device drives it with: the keys at
/// the simulated device), and turns only when they choose (no slice). One
/// interface is live at a time: at a turn the forces fade out and in over
/// the run's switch ramp and the interface left is paused at zero
/// (interface_handover.hpp); the person's input reaches only the live one.
///
/// With a view, every vehicle's video is a tile (its name, state and lap)
/// and the driven one's is on the big screen with its world, as a single
/// run shows it. Each vehicle's selected source is published on
/// haptel/<vehicle>/selected. A vehicle lost mid-run is reported by name and the others go on;
/// another operator holding any of them, or a second vehicle answering
/// under one of the names, ends the whole run (nothing of it is ours).
#include <atomic>
#include <string>
#include <vector>

#include "haptel/config/fleet.hpp"
#include "haptel/mediator/session.hpp"

namespace haptel::mediator {

struct FleetSetup {
  FleetConfig fleet;
  /// One per vehicle of the fleet, in its order: each as `haptel run` sets
  /// up that vehicle alone. The haptic device, the operator, the view and
  /// the time limit are the first one's (the same in all).
  std::vector<SessionSetup> vehicles;
};

/// The operator's watch name for the mux's input and lock.
inline constexpr const char* kOperatorInput = "operator";
inline constexpr const char* kHandoverLock = "handover";

/// The haptic cue of a switch: a short push up on both hands, felt over
/// whatever the interface renders (Hal::SetCue; the safety limits still
/// apply). Up, because no interface pushes that way: it cannot be taken for
/// a command's feedback.
inline constexpr double kSwitchCueForce_N = 2.0;
inline constexpr double kSwitchCueDuration_s = 0.08;
/// The selected source is published on every change and this often
/// besides (haptel/<vehicle>/selected).
inline constexpr double kSelectedPeriod_s = 1.0;

/// The vehicle a person's request (InputState::vehicle_request) asks for,
/// while vehicle `driven` is (-1: none): interfaces::kNextVehicle the next
/// after it whose course is not over, else that index. -1 when there is
/// none to switch to: the index is past the fleet, that vehicle's course is
/// over (`over[i]`: completed, lost, crashed or capped), or it is the
/// driven one already.
int RequestedVehicle(int request, int driven, const std::vector<bool>& over);

struct FleetVehicleResult {
  /// Its own outcome and record (one row in the runs database).
  SessionResult result;
  /// Olsen & Goodrich: the time the operator drove it (interaction), and
  /// the time it waited for the operator while its course was not done
  /// (neglect), s.
  double driven_s = 0.0;
  double neglected_s = 0.0;
  /// The mux's selection on the last tick it was in the run: "operator",
  /// "lock:handover" or "none".
  std::string selected = "none";
  int handovers = 0;  ///< times the operator turned to it (the first not counted)
};

struct FleetResult {
  Outcome outcome = Outcome::kInterrupted;
  std::string message;  ///< one line: each vehicle's end
  std::vector<FleetVehicleResult> vehicles;
  /// Each handover's time, switch request to the new vehicle obeying, ms:
  /// of the turns to a vehicle that had answered before the request.
  std::vector<double> handover_ms;
  /// Turns to a vehicle that had not answered yet (still starting): not
  /// timed, since their time would be the vehicle's start-up.
  int handovers_untimed = 0;
  double handover_ms_p50 = -1.0;  ///< nearest rank; negative: no handover
  double handover_ms_p95 = -1.0;
  std::vector<std::string>
      lost;  ///< the vehicles lost mid-run, by name (those that never answered too)
  /// Of `lost`, those never heard from (outcome vehicle did not start): an
  /// attached vehicle that is not running, or a spawned one that never came up.
  std::vector<std::string> never_answered;
  /// Switches a person asked for (a key, a controller button) and made;
  /// the automatic operator's own turns are not counted.
  int person_switches = 0;
  /// The operator process's CPU time (all its threads, getrusage) per wall
  /// second over the run's loop: what the fleet costs the station.
  double operator_cpu_share = 0.0;
  /// The servo loop over the run: its start-to-start period p99, µs; and
  /// the same over the ticks that rendered a switch's cue alone (negative:
  /// no cue was felt), with their count.
  double servo_period_p99_us = 0.0;
  double servo_cue_period_p99_us = -1.0;
  uint64_t servo_cue_ticks = 0;
  std::string fleet_run;  ///< "fleet <name> <started, UTC>": shared by its rows
};

/// Runs the fleet, in the session loop a single vehicle's run goes through
/// (RunSession in session.hpp), until every vehicle's course is done
/// (completed, lost, crashed or capped: a vehicle's lap cap counts the time
/// it was driven), the time limit, the device lost, a refusal or conflict,
/// or `interrupted`. Throws ConfigError / std::runtime_error for parts that
/// cannot be set up (before anything moves).
FleetResult RunSession(const FleetSetup& setup, const std::atomic<bool>& interrupted);

/// The nearest-rank percentile `p` in (0, 1] of `values`; -1 when empty.
double NearestRank(std::vector<double> values, double p);

}  // namespace haptel::mediator
