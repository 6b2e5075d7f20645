// One operator, several vehicles: the fleet's turns (fleet_turns.hpp), over
// the session loop's vehicles (session.cpp); a CommandMux per vehicle for
// who commands it.
#include "fleet_turns.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "haptel/core/clock.hpp"
#include "haptel/core/histogram.hpp"
#include "haptel/core/log.hpp"
#include "haptel/mediator/session_view.hpp"

namespace haptel::mediator {

namespace {

/// A vehicle left alone is sent its safe command this often: well inside
/// any vehicle's command watchdog (the robot's is 0.2 s), so it is held by
/// the operator, not stopped by its watchdog.
constexpr double kHoldPeriod_s = 0.05;
/// The operator's input is live this long after its last command: the
/// handover lock on the vehicle turned away from is held at least as long,
/// so it can never be selected again by a stale input.
constexpr double kOperatorTimeout_s = 0.25;

std::vector<HandoverSide*> Sides(const std::vector<VehicleRun*>& vehicles) {
  std::vector<HandoverSide*> sides;
  for (VehicleRun* v : vehicles) sides.push_back(v->family.get());
  return sides;
}

/// Not ours to drive: the whole fleet ends, as a single run would.
bool EndsTheFleet(Outcome outcome) {
  return outcome == Outcome::kConflict || outcome == Outcome::kRefused ||
         outcome == Outcome::kLostControl;
}

}  // namespace

int RequestedVehicle(int request, int driven, const std::vector<bool>& over) {
  const int n = static_cast<int>(over.size());
  if (request == interfaces::kNextVehicle) {
    for (int k = 1; k < n; ++k) {
      const int i = ((driven < 0 ? -1 : driven) + k + n) % n;
      if (!over[static_cast<size_t>(i)]) return i;
    }
    // Past the driven one, none is waiting: the first not over, if it is not the driven one.
    for (int i = 0; i < n; ++i) {
      if (!over[static_cast<size_t>(i)]) return i == driven ? -1 : i;
    }
    return -1;
  }
  if (request < 0 || request >= n || request == driven || over[static_cast<size_t>(request)])
    return -1;
  return request;
}

double NearestRank(std::vector<double> values, double p) {
  if (values.empty()) return -1.0;
  std::sort(values.begin(), values.end());
  const size_t rank = static_cast<size_t>(std::ceil(p * static_cast<double>(values.size())));
  return values[std::clamp<size_t>(rank, 1, values.size()) - 1];
}

FleetTurns::Hold::Hold()
    : mux({{kOperatorInput, 100, kOperatorTimeout_s}}, {{kHandoverLock, 255, 0.0}}),
      operator_input(mux.input_index(kOperatorInput)),
      handover_lock(mux.lock_index(kHandoverLock)) {}

FleetTurns::FleetTurns(const FleetConfig& fleet, std::vector<VehicleRun*> vehicles,
                       HapticSide& haptic, FleetResult& result)
    : fleet_(fleet),
      vehicles_(std::move(vehicles)),
      haptic_(haptic),
      result_(result),
      person_drives_(vehicles_.front()->setup.operator_kind == "person"),
      progress_(vehicles_.front()->setup.progress),
      // One interface live at a time (interface_handover.hpp): a person's
      // forces fade over the run's switch ramp at each turn; the automatic
      // operator's interfaces swap at once (nobody holds the arms).
      interfaces_(Sides(vehicles_),
                  person_drives_ ? vehicles_.front()->setup.run.switch_ramp_s : 0.0) {
  for (size_t i = 0; i < vehicles_.size(); ++i) holds_.push_back(std::make_unique<Hold>());
  interfaces_.PauseAll(haptic_.hal());
}

std::optional<LoopEnd> FleetTurns::OnVehicleEnd(VehicleRun& v, LoopEnd end) {
  if (EndsTheFleet(end.outcome)) {
    end.message = "vehicle '" + v.setup.vehicle.name + "': " + end.message;
    return end;
  }
  const bool lost =
      end.outcome == Outcome::kVehicleLost || end.outcome == Outcome::kVehicleDidNotStart;
  if (v.done) {
    if (end.outcome == Outcome::kVehicleLost) v.lost = true;  // after its course: nothing to hold
    return std::nullopt;
  }
  const Outcome end_outcome = end.outcome;
  end.message = "vehicle '" + v.setup.vehicle.name + "': " + end.message;
  mediator::Finish(v.out.result, std::move(end), v.family->MadeSafe());
  v.done = true;
  v.lost = lost;
  if (lost) {
    result_.lost.push_back(v.setup.vehicle.name);
    if (end_outcome == Outcome::kVehicleDidNotStart)
      result_.never_answered.push_back(v.setup.vehicle.name);
  } else {
    v.link->SendSafe();
  }
  if (progress_ && !lost) log::Info(v.out.result.message);
  return std::nullopt;
}

void FleetTurns::OnPersonRequest(const interfaces::InputState& person, int64_t now, double t) {
  if (person.vehicle_requests == vehicle_requests_seen_) return;
  vehicle_requests_seen_ = person.vehicle_requests;
  std::vector<bool> over;
  for (const VehicleRun* v : vehicles_) over.push_back(v->done);
  const int asked = RequestedVehicle(person.vehicle_request, target_, over);
  if (asked >= 0) {
    SwitchTo(asked, now, t, "asked by the person");
    ++result_.person_switches;
  } else if (person.vehicle_request >= 0 &&
             person.vehicle_request < static_cast<int>(vehicles_.size()) &&
             person.vehicle_request != target_) {
    std::snprintf(
        switch_note_, sizeof switch_note_, "%s: its course is over",
        vehicles_[static_cast<size_t>(person.vehicle_request)]->setup.vehicle.name.c_str());
    switch_note_until_t_ = t + 3.0;
  }
}

bool FleetTurns::Turn(const interfaces::InputState& person, int64_t now, double t) {
  OnPersonRequest(person, now, t);
  if (target_ < 0 || vehicles_[static_cast<size_t>(target_)]->done) {
    const int next = NextAfter(target_);
    if (next < 0) return false;  // every course is done
    SwitchTo(next, now, t, target_ < 0 ? "the first" : "the last one's course is over");
  } else if (!person_drives_ && fleet_.slice_s > 0.0 && t - driven_since_t_ >= fleet_.slice_s) {
    // The automatic operator's time slice; a person turns when they choose.
    const int next = NextAfter(target_);
    if (next >= 0 && next != target_) SwitchTo(next, now, t, "its time slice");
  }
  return true;
}

int FleetTurns::NextAfter(int from) const {
  const int n = static_cast<int>(vehicles_.size());
  for (int k = 1; k <= n; ++k) {
    const int i = ((from < 0 ? -1 : from) + k + n) % n;
    if (!vehicles_[static_cast<size_t>(i)]->done) return i;
  }
  return -1;
}

// The handover lock on both, the one left sent zero at once; felt on both
// hands (a cue) and shown (the tile, the HUD's line) when there is a
// vehicle to turn to.
void FleetTurns::SwitchTo(int to, int64_t now, double t, const char* why) {
  if (target_ >= 0) {
    Hold& from = *holds_[static_cast<size_t>(target_)];
    from.mux.OnLock(from.handover_lock, true, t);
    from.lock_until_t = t + kOperatorTimeout_s;
    from.handover_pending = false;
  }
  const bool measured = target_ >= 0;
  target_ = to;
  driven_since_t_ = t;
  interfaces_.TurnTo(to, t, haptic_.hal());
  if (to < 0) return;
  VehicleRun& v = *vehicles_[static_cast<size_t>(to)];
  Hold& h = *holds_[static_cast<size_t>(to)];
  h.mux.OnLock(h.handover_lock, true, t);
  h.lock_until_t = -1.0;
  h.handover_pending = true;
  // Timed only when it had answered before: turning to a vehicle still
  // starting would time its start-up (its process, discovery), not the handover.
  h.measure_handover = measured && v.health->up();
  if (measured && !v.health->up()) ++result_.handovers_untimed;
  h.request_ns = now;
  h.released_ns = 0;
  v.link->WatchEcho(0);
  if (measured) {
    ++v.out.handovers;
    const haptics::Hal::Cue cue{{0.0, 0.0, kSwitchCueForce_N}, now + SToNs(kSwitchCueDuration_s)};
    for (int side = 0; side < haptics::kSides; ++side)
      haptic_.hal().SetCue(static_cast<haptics::Side>(side), cue);
    std::snprintf(switch_note_, sizeof switch_note_, "switched to %s (%s)",
                  v.setup.vehicle.name.c_str(), why);
    switch_note_until_t_ = t + 3.0;
  }
  if (view_) {
    view_->Show(to);
    // Only the driven vehicle's video is shown in full: the others are
    // tiles, and are asked for a preview (fewer pixels and frames).
    for (size_t i = 0; i < vehicles_.size(); ++i)
      vehicles_[i]->link->video().ShowAsTile(static_cast<int>(i) != to);
  }
  if (progress_) log::Info("fleet: driving '" + v.setup.vehicle.name + "' (" + why + ")");
}

void FleetTurns::TickInterfaces(double t, const interfaces::InputState& person) {
  live_ = interfaces_.Tick(t, haptic_.hal(), person);
}

void FleetTurns::AdvanceHandover(VehicleRun& v, Hold& h, bool interface_live, int64_t now,
                                 double t) {
  if (h.released_ns == 0 && interface_live && v.health->up() &&
      v.link->last_received_ns() > h.request_ns) {
    // It has been seen since the request, and its interface is the live
    // one: the operator may command it.
    h.mux.OnLock(h.handover_lock, false, t);
    h.released_ns = now;
    v.link->WatchEcho(now);
  }
  if (h.released_ns != 0) {
    if (const int64_t echoed = v.link->EchoReceivedNs(); echoed != 0) {
      if (h.measure_handover)
        result_.handover_ms.push_back(static_cast<double>(echoed - h.request_ns) * 1e-6);
      h.handover_pending = false;
    }
  }
}

bool FleetTurns::Operated(size_t i, int64_t now, double t, double dt) {
  VehicleRun& v = *vehicles_[i];
  Hold& h = *holds_[i];
  const bool driven = static_cast<int>(i) == target_;
  const bool interface_live = static_cast<int>(i) == live_;
  if (h.lock_until_t >= 0.0 && t >= h.lock_until_t) {
    h.mux.OnLock(h.handover_lock, false,
                 t);  // turned away from long enough: nothing of ours is live
    h.lock_until_t = -1.0;
  }
  if (driven && h.handover_pending) AdvanceHandover(v, h, interface_live, now, t);
  if (driven && h.released_ns != 0) h.mux.OnInput(h.operator_input, t);
  bool changed = false;
  const CommandMux::Selection selection = h.mux.Select(t, &changed);
  v.out.selected = h.mux.SelectedName(selection);
  if (v.health->ours() && (selection != h.published_selection || now >= h.next_selected_ns)) {
    // Who commands it, for anyone on the domain: on a change at once, and
    // now and then for the record.
    v.link->PublishSelected(
        selection.input >= 0 ? h.mux.inputs()[static_cast<size_t>(selection.input)].name : "",
        selection.lock >= 0 ? h.mux.locks()[static_cast<size_t>(selection.lock)].name : "");
    h.published_selection = selection;
    h.next_selected_ns = now + SToNs(kSelectedPeriod_s);
  }
  if (driven && interface_live && selection.input == h.operator_input) {
    v.out.driven_s += dt;
    return true;
  }
  if (!v.done) v.out.neglected_s += dt;
  if (changed || now >= h.next_hold_ns) {
    v.link->SendSafe();
    h.next_hold_ns = now + SToNs(kHoldPeriod_s);
  }
  return false;
}

void FleetTurns::Settle(double t) {
  const bool own_switch_ramping =
      live_ >= 0 && !vehicles_[static_cast<size_t>(live_)]->lost &&
      vehicles_[static_cast<size_t>(live_)]->family->SwitchingInterface();
  interfaces_.Settle(t, haptic_.hal(), own_switch_ramping);
}

std::optional<LoopEnd> FleetTurns::CapEnd(const VehicleRun& v) const {
  const double cap_s = v.family->lap_cap_s();
  if (v.out.driven_s <= cap_s) return std::nullopt;
  return LoopEnd{Outcome::kLapCap,
                 "lap cap of " + std::to_string(static_cast<int>(cap_s)) + " s of driving reached"};
}

void FleetTurns::PublishTiles(SessionView& view, double t) const {
  view::Tiles tiles;
  tiles.count = static_cast<int>(vehicles_.size());
  for (size_t i = 0; i < vehicles_.size(); ++i) {
    const VehicleRun& v = *vehicles_[i];
    view::Tiles::Tile& tile = tiles.tile[i];
    std::snprintf(tile.name, sizeof tile.name, "%s", v.setup.vehicle.name.c_str());
    tile.state = v.lost                           ? view::TileState::kLost
                 : v.done                         ? view::TileState::kDone
                 : static_cast<int>(i) == target_ ? view::TileState::kDriven
                                                  : view::TileState::kHeld;
    tile.lap_time_s = v.overlay.lap_time_s;
    tile.gates_passed = v.overlay.gates_passed;
    tile.gates_total = v.overlay.gates_total;
  }
  if (target_ >= 0) {
    const VehicleRun& v = *vehicles_[static_cast<size_t>(target_)];
    const int n = static_cast<int>(vehicles_.size());
    if (t < switch_note_until_t_) {
      std::snprintf(tiles.line, sizeof tiles.line, "%s  -  Tab: next, 1-%d: pick", switch_note_, n);
    } else {
      std::snprintf(tiles.line, sizeof tiles.line,
                    "driving %s (%d of %d)  -  Tab: next, 1-%d: pick", v.setup.vehicle.name.c_str(),
                    target_ + 1, n, n);
    }
  }
  view.Publish(tiles);
}

void FleetTurns::LogProgress(double t) const {
  if (target_ < 0) return;
  const VehicleRun& driven = *vehicles_[static_cast<size_t>(target_)];
  driven.family->LogProgress(t, *driven.link, driven.out.result.record.distance_m);
  std::string line = "         fleet:";
  for (const VehicleRun* v : vehicles_) {
    char part[140];
    std::snprintf(part, sizeof part, " %s %s (driven %.1f s, %.2f m%s)",
                  v->setup.vehicle.name.c_str(),
                  v->lost   ? "LOST"
                  : v->done ? "done"
                            : v->out.selected.c_str(),
                  v->out.driven_s, v->out.result.record.distance_m,
                  v->lost || v->health->up() ? "" : ", not answering yet");
    line += part;
  }
  log::Info(line);
}

void FleetTurns::Finish(const std::optional<LoopEnd>& end, const HapticSide& haptic) {
  if (end) {
    result_.outcome = end->outcome;
    result_.message = end->message;
  } else {
    const bool all = std::all_of(vehicles_.begin(), vehicles_.end(), [](const VehicleRun* v) {
      return v->out.result.outcome == Outcome::kCompleted;
    });
    result_.outcome = Outcome::kCompleted;
    if (!all) {
      result_.outcome = !result_.lost.empty() ? Outcome::kVehicleLost : Outcome::kLapCap;
      for (const VehicleRun* v : vehicles_) {
        if (result_.lost.empty() && v->out.result.outcome != Outcome::kCompleted) {
          result_.outcome = v->out.result.outcome;
          break;
        }
      }
    }
    for (const VehicleRun* v : vehicles_) {
      if (!result_.message.empty()) result_.message += "; ";
      // A vehicle never heard from was not lost: it never answered (an
      // attached one that is not running, or a spawned one that never came up).
      result_.message +=
          v->setup.vehicle.name + " " +
          (v->out.result.outcome == Outcome::kVehicleDidNotStart ? std::string("never answered")
                                                                 : ToString(v->out.result.outcome));
    }
  }
  result_.servo_period_p99_us = haptic.Stats().period_p99_us;
  const Histogram& cue_periods = haptic.ServoCuePeriods();
  result_.servo_cue_ticks = cue_periods.Count();
  result_.servo_cue_period_p99_us =
      result_.servo_cue_ticks > 0 ? cue_periods.Percentile(0.99) : -1.0;
  result_.handover_ms_p50 = NearestRank(result_.handover_ms, 0.50);
  result_.handover_ms_p95 = NearestRank(result_.handover_ms, 0.95);
}

}  // namespace haptel::mediator
