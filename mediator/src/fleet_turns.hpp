#pragma once
// A fleet's turns (fleet.hpp): which vehicle the operator drives, the
// handover to it, every other vehicle held safe, and what the fleet adds to
// the view (the tiles) and the progress lines. The session loop
// (session.cpp) has one when it runs a fleet; a single vehicle's run is
// driven all along and has none. Internal to the mediator library.
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "family_session.hpp"
#include "haptel/mediator/command_mux.hpp"
#include "haptel/mediator/fleet.hpp"
#include "haptel/mediator/interface_handover.hpp"
#include "session_loop.hpp"

namespace haptel::mediator {

class SessionView;

class FleetTurns {
 public:
  /// Pauses every vehicle's interface: none is live before the first turn.
  /// `vehicles` (their families built) and `result` must outlive the turns.
  FleetTurns(const FleetConfig& fleet, std::vector<VehicleRun*> vehicles, HapticSide& haptic,
             FleetResult& result);
  /// The loop begins: `view` (null: none) shows each turn's vehicle on the
  /// big screen; a person's requests count from `vehicle_requests` on.
  void Begin(SessionView* view, uint32_t vehicle_requests) {
    view_ = view;
    vehicle_requests_seen_ = vehicle_requests;
  }

  /// A vehicle's end (its health's, or its course's): the whole fleet's
  /// when nothing of it is ours (a conflict, a refusal, control lost), else
  /// that vehicle's alone: said at once, held safe from now on.
  std::optional<LoopEnd> OnVehicleEnd(VehicleRun& vehicle, LoopEnd end);
  /// Each tick, after the states: a person's turn first (a key, a controller
  /// button), then the automatic operator's (the driven vehicle's course is
  /// over, or its slice). False when every course is over.
  bool Turn(const interfaces::InputState& person, int64_t now_ns, double t_s);
  /// Each tick, before the commands: the person's input and the forces go to
  /// one interface only, the driven vehicle's once the one left faded out.
  void TickInterfaces(double t_s, const interfaces::InputState& person);
  /// Whether vehicle `i` is the operator's this tick (its family commands
  /// it); if not, it was held safe. Its mux's selection is published, and
  /// its driven and neglected time counted.
  bool Operated(size_t i, int64_t now_ns, double t_s, double dt_s);
  /// After the commands: the handover's force ramp.
  void Settle(double t_s);
  /// The driven vehicle (-1: none yet, or none left): on the big screen.
  int driven() const { return target_; }
  /// A vehicle's lap cap, on the time it was driven.
  std::optional<LoopEnd> CapEnd(const VehicleRun& vehicle) const;
  /// The tiles and the HUD's line, from the overlays made this tick.
  /// Allocation-free: overlays and tiles are flat.
  void PublishTiles(SessionView& view, double t_s) const;
  /// The progress line of every vehicle (after the driven one's own lines).
  void LogProgress(double t_s) const;
  /// Once the haptic side has stopped: the fleet's outcome (`end`, or each
  /// vehicle's), its servo figures and its handovers' percentiles.
  void Finish(const std::optional<LoopEnd>& end, const HapticSide& haptic);

 private:
  /// What the turns keep for one vehicle: who commands it (its mux) and a
  /// handover to it under way.
  struct Hold {
    Hold();
    CommandMux mux;
    int operator_input;
    int handover_lock;
    int64_t next_hold_ns = 0;
    // A handover to this vehicle under way: requested at request_ns; the lock
    // released (and the echo watched) at released_ns.
    bool handover_pending = false;
    bool measure_handover = false;  ///< false for the run's first vehicle
    int64_t request_ns = 0;
    int64_t released_ns = 0;
    double lock_until_t = -1.0;  ///< turned away from: the lock holds until then
    // The selected source as last published, and when it is due again.
    CommandMux::Selection published_selection;
    int64_t next_selected_ns = 0;
  };

  /// Turns the operator to vehicle `to` (-1: none left).
  void SwitchTo(int to, int64_t now_ns, double t_s, const char* why);
  /// The automatic operator's choice: the next vehicle after `from` whose course is not done.
  int NextAfter(int from) const;
  /// A person's request for a vehicle, when a new one came.
  void OnPersonRequest(const interfaces::InputState& person, int64_t now_ns, double t_s);
  /// The handover lock released (once its interface is the live one), and
  /// the echo timed, as the driven vehicle answers.
  void AdvanceHandover(VehicleRun& vehicle, Hold& hold, bool interface_live, int64_t now_ns,
                       double t_s);

  const FleetConfig& fleet_;
  std::vector<VehicleRun*> vehicles_;
  std::vector<std::unique_ptr<Hold>> holds_;  // one per vehicle (a mux does not move)
  HapticSide& haptic_;
  FleetResult& result_;
  SessionView* view_ = nullptr;
  const bool person_drives_;
  const bool progress_;
  InterfaceHandover interfaces_;
  int live_ = -1;  ///< the live interface's vehicle this tick
  int target_ = -1;
  double driven_since_t_ = 0.0;
  uint32_t vehicle_requests_seen_ = 0;
  char switch_note_[64] = "";  ///< the HUD's note of the last switch
  double switch_note_until_t_ = -1.0;
};

}  // namespace haptel::mediator
