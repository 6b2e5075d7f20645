// One operator, several vehicles: the fleet's session loop (fleet.hpp).
// Written over FamilySession and VehicleLink as RunSession is, one of each
// per vehicle, and a CommandMux per vehicle for who commands it.
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <memory>
#include <optional>
#include <thread>

#include "family_session.hpp"
#include "haptel/config/link.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/histogram.hpp"
#include "haptel/core/log.hpp"
#include "haptel/mediator/command_mux.hpp"
#include "haptel/mediator/fleet.hpp"
#include "haptel/mediator/interface_handover.hpp"
#include "haptel/mediator/run_counters.hpp"
#include "haptel/mediator/session_view.hpp"
#include "session_loop.hpp"

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

/// One vehicle of the fleet and everything the session keeps for it.
struct Member {
  Member(const SessionSetup& s)
      : setup(s),
        mux({{kOperatorInput, 100, kOperatorTimeout_s}}, {{kHandoverLock, 255, 0.0}}),
        operator_input(mux.input_index(kOperatorInput)),
        handover_lock(mux.lock_index(kHandoverLock)) {}

  const SessionSetup& setup;
  FleetVehicleResult out;
  std::unique_ptr<FamilySession> family;
  std::unique_ptr<VehicleLink> link;
  std::unique_ptr<VehicleHealth> health;
  std::unique_ptr<RunTrace> trace;
  std::unique_ptr<LoopWatch> watch;
  CommandMux mux;
  int operator_input;
  int handover_lock;
  bool done = false;  ///< its course is over (completed, lost, crashed, capped)
  bool lost = false;
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
  view::Overlay overlay;  ///< its view's overlay, made each tick the view is fed
};

/// The process's CPU time (every thread), s.
double ProcessCpuS() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) * 1e-6;
}

std::string FleetRunName(const std::string& fleet, int64_t wall_ns) {
  const std::time_t seconds = static_cast<std::time_t>(wall_ns / 1000000000);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return "fleet " + fleet + " " + text;
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

FleetResult RunFleet(const FleetSetup& setup, const std::atomic<bool>& interrupted) {
  const SessionSetup& first = setup.vehicles.at(0);
  const RunConfig& run = first.run;
  FleetResult fleet;
  const int64_t started_wall_ns = WallNs();
  fleet.fleet_run = FleetRunName(setup.fleet.name, started_wall_ns);

  std::vector<std::unique_ptr<Member>> members;
  for (const SessionSetup& s : setup.vehicles) {
    auto m = std::make_unique<Member>(s);
    RunRecord& rec = m->out.result.record;
    rec.started_wall_ns = started_wall_ns;
    rec.config_name = fleet.fleet_run;  // the rows of one fleet run share it
    rec.vehicle = s.vehicle.name;
    rec.vehicle_kind = s.vehicle.kind;
    rec.link_fault = s.run.link.fault.enabled ? LinkFaultText(s.run.link.fault) : "";
    rec.operator_kind = s.operator_kind;
    rec.device = s.device.name;
    members.push_back(std::move(m));
  }

  // --- One haptic side for all, then each vehicle's family part. ---
  HapticSide haptic(first.device, first.calibration, first.gravity, run.op, first.trace);
  interfaces::InputBox input;
  for (auto& m : members) {
    RunRecord& rec = m->out.result.record;
    switch (m->setup.vehicle.family()) {
      case VehicleFamily::kRobot:
        m->family = MakeRobotSession(m->setup, haptic, input, interrupted, rec);
        break;
      case VehicleFamily::kBlimp:
        m->family = MakeBlimpSession(m->setup, haptic, input, rec);
        break;
    }
    if (interrupted.load()) break;
  }
  if (interrupted.load()) {
    fleet.outcome = Outcome::kInterrupted;
    fleet.message = "interrupted by the operator during the set-up";
    for (auto& m : members) {
      SessionResult& r = m->out.result;
      r.outcome = fleet.outcome;
      r.message = fleet.message;
      r.record.outcome = ToString(r.outcome);
      if (m->family) m->family->AbandonSetup(r);
      fleet.vehicles.push_back(std::move(m->out));
    }
    return fleet;
  }
  haptic.Start(first.progress);
  for (auto& m : members) m->family->Start(haptic);
  // One interface live at a time (interface_handover.hpp): a person's
  // forces fade over the run's switch ramp at each turn; the automatic
  // operator's interfaces swap at once (nobody holds the arms).
  const bool person_drives = first.operator_kind == "person";
  std::vector<HandoverSide*> sides;
  for (auto& m : members) sides.push_back(m->family.get());
  InterfaceHandover interfaces(std::move(sides), person_drives ? run.switch_ramp_s : 0.0);
  interfaces.PauseAll(haptic.hal());

  // --- The vehicles: each spawned (or attached) and linked on the one domain. ---
  for (auto& m : members) {
    VehicleLinkOptions options;
    options.vehicle = m->setup.vehicle;
    options.link = m->setup.run.link;
    options.track_file = m->family->world_file();
    options.program = m->setup.vehicle_program;
    options.decode_video = run.video_decode && DecodesVideo(first.view);  // the tiles show them
    options.publish_selected = true;
    m->link = std::make_unique<VehicleLink>(options);
    m->out.result.record.vehicle_pid = m->link->pid();
    if (first.progress) {
      log::Info("fleet '" + setup.fleet.name + "': vehicle '" + m->setup.vehicle.name + "' (" +
                m->setup.vehicle.kind + ") " +
                (m->link->pid() != 0
                     ? "started, pid " + std::to_string(m->link->pid())
                     : std::string("attaching on domain ") + std::to_string(run.link.domain_id) +
                           " (a vehicle already running there)"));
    }
  }

  // --- The view: every vehicle's tile, the driven one's world on the big screen. ---
  std::unique_ptr<SessionView> view_part;
  if (first.view != ViewKind::kNone) {
    view::ViewOptions options = ViewOptionsFor(first);
    options.title = "Haptel - fleet " + setup.fleet.name;
    std::vector<SessionView::Parts> parts;
    for (size_t i = 0; i < members.size(); ++i) {
      SessionView::Parts p;
      p.hal = &haptic.hal();
      p.physics_config = &members[i]->setup.physics;
      p.video = &members[i]->link->video();
      view::ViewOptions own = options;  // the window is the first vehicle's: its screen placement
      members[i]->family->ConfigureView(p, i == 0 ? options : own);
      parts.push_back(p);
    }
    view_part = std::make_unique<SessionView>(options, std::move(parts), input);
  }
  // A person's controller without a view: a thread of its own polls it.
  std::unique_ptr<view::InputPump> pump;
  if (!view_part && std::any_of(members.begin(), members.end(),
                                [](const auto& m) { return m->family->UsesGamepad(); })) {
    pump = std::make_unique<view::InputPump>(input);
  }
  uint32_t vehicle_requests_seen = input.Load().vehicle_requests;
  char switch_note[64] = "";  // the HUD's note of the last switch
  double switch_note_until_t = -1.0;

  const int64_t t0 = MonotonicNs();
  const double cpu0_s = ProcessCpuS();
  for (auto& m : members) {
    m->health = std::make_unique<VehicleHealth>(
        m->setup.vehicle.name, run.link.domain_id, m->link->session(), m->link->command_writer(),
        run.vehicle_timeout_s, VehicleHealth::kStartupTimeout_s, m->link->pid());
    m->trace = std::make_unique<RunTrace>(m->out.result.record);
    m->out.result.record.path.reserve(16384);
    m->watch = std::make_unique<LoopWatch>(
        haptic, m->family->physics(), *m->link,
        m.get() == members.front().get() ? view_part.get() : nullptr, t0);
  }
  const auto period_ns = static_cast<int64_t>(1e9 / run.session_rate_hz);
  const auto hold_period_ns = static_cast<int64_t>(kHoldPeriod_s * 1e9);
  int64_t next_tick = t0;
  int64_t next_progress_ns = t0 + SToNs(2.0);
  double last_t = 0.0;
  double driven_since_t = 0.0;
  int target = -1;
  std::optional<LoopEnd> fleet_end;

  // Ends one vehicle's course: said at once, held safe from now on.
  const auto end_member = [&](Member& m, LoopEnd end) {
    const bool lost =
        end.outcome == Outcome::kVehicleLost || end.outcome == Outcome::kVehicleDidNotStart;
    const Outcome end_outcome = end.outcome;
    end.message = "vehicle '" + m.setup.vehicle.name + "': " + end.message;
    Finish(m.out.result, std::move(end), m.family->MadeSafe());
    m.done = true;
    m.lost = lost;
    if (lost) {
      fleet.lost.push_back(m.setup.vehicle.name);
      if (end_outcome == Outcome::kVehicleDidNotStart)
        fleet.never_answered.push_back(m.setup.vehicle.name);
    } else {
      m.link->SendSafe();
    }
    if (first.progress && !lost) log::Info(m.out.result.message);
  };

  // Turns the operator to vehicle `to` (-1: none left): the handover lock
  // on both, the one left sent zero at once; felt on both hands (a cue)
  // and shown (the tile, the HUD's line) when there is a vehicle to turn to.
  const auto switch_to = [&](int to, int64_t now, double t, const char* why) {
    if (target >= 0) {
      Member& from = *members[static_cast<size_t>(target)];
      from.mux.OnLock(from.handover_lock, true, t);
      from.lock_until_t = t + kOperatorTimeout_s;
      from.handover_pending = false;
    }
    const bool measured = target >= 0;
    target = to;
    driven_since_t = t;
    interfaces.TurnTo(to, t, haptic.hal());
    if (to < 0) return;
    Member& m = *members[static_cast<size_t>(to)];
    m.mux.OnLock(m.handover_lock, true, t);
    m.lock_until_t = -1.0;
    m.handover_pending = true;
    // Timed only when it had answered before: turning to a vehicle still
    // starting would time its start-up (its process, discovery), not the handover.
    m.measure_handover = measured && m.health->up();
    if (measured && !m.health->up()) ++fleet.handovers_untimed;
    m.request_ns = now;
    m.released_ns = 0;
    m.link->WatchEcho(0);
    if (measured) ++m.out.handovers;
    if (measured) {
      const haptics::Hal::Cue cue{{0.0, 0.0, kSwitchCueForce_N}, now + SToNs(kSwitchCueDuration_s)};
      for (int side = 0; side < haptics::kSides; ++side)
        haptic.hal().SetCue(static_cast<haptics::Side>(side), cue);
      std::snprintf(switch_note, sizeof switch_note, "switched to %s (%s)",
                    m.setup.vehicle.name.c_str(), why);
      switch_note_until_t = t + 3.0;
    }
    if (view_part) view_part->Show(to);
    if (first.progress) log::Info("fleet: driving '" + m.setup.vehicle.name + "' (" + why + ")");
  };

  // The view's next frames: the driven vehicle's overlay, gaze and ghost on
  // the big screen (a fixed gaze and no ghost when it has none), and every
  // vehicle's tile. Allocation-free: overlays and tiles are flat.
  const auto publish_view = [&](double t) {
    view::Tiles tiles;
    tiles.count = static_cast<int>(members.size());
    for (size_t i = 0; i < members.size(); ++i) {
      Member& m = *members[i];
      view_part->SetPhysics(static_cast<int>(i), m.family->physics());  // a world built mid-run
      m.overlay = m.family->Overlay(t, !m.lost && m.health->up(), m.trace->touching());
      view::Tiles::Tile& tile = tiles.tile[i];
      std::snprintf(tile.name, sizeof tile.name, "%s", m.setup.vehicle.name.c_str());
      tile.state = m.lost                          ? view::TileState::kLost
                   : m.done                        ? view::TileState::kDone
                   : static_cast<int>(i) == target ? view::TileState::kDriven
                                                   : view::TileState::kHeld;
      tile.lap_time_s = m.overlay.lap_time_s;
      tile.gates_passed = m.overlay.gates_passed;
      tile.gates_total = m.overlay.gates_total;
    }
    if (target >= 0) {
      Member& m = *members[static_cast<size_t>(target)];
      view_part->Publish(m.overlay);
      view_part->Publish(m.family->Gaze().value_or(view::Gaze{}));
      view_part->Publish(m.family->Prediction(t).value_or(view::Prediction{}));
      const int n = static_cast<int>(members.size());
      if (t < switch_note_until_t) {
        std::snprintf(tiles.line, sizeof tiles.line, "%s  -  Tab: next, 1-%d: pick", switch_note,
                      n);
      } else {
        std::snprintf(tiles.line, sizeof tiles.line,
                      "driving %s (%d of %d)  -  Tab: next, 1-%d: pick",
                      m.setup.vehicle.name.c_str(), target + 1, n, n);
      }
    }
    view_part->Publish(tiles);
  };

  // The automatic operator's choice: the next vehicle after `from` whose course is not done.
  const auto next_after = [&](int from) {
    const int n = static_cast<int>(members.size());
    for (int k = 1; k <= n; ++k) {
      const int i = ((from < 0 ? -1 : from) + k + n) % n;
      if (!members[static_cast<size_t>(i)]->done) return i;
    }
    return -1;
  };

  for (;;) {
    SleepUntilNs(next_tick);
    next_tick += period_ns;
    const int64_t now = MonotonicNs();
    const double t = NsToS(now - t0);
    const double dt = t - last_t;
    last_t = t;

    if (auto end = CheckOperatorSide(interrupted, haptic, first.device.name)) {
      fleet_end = std::move(end);
      break;
    }
    const interfaces::InputState person = input.Load();
    if (person.quit) {
      fleet_end = LoopEnd{Outcome::kAborted, "the view was closed"};
      break;
    }

    // Every vehicle's health and states, driven or not: the operator keeps
    // an eye on all of them, and each one's lap and trace go on.
    for (auto& mp : members) {
      Member& m = *mp;
      if (m.lost) continue;
      std::optional<LoopEnd> end = m.health->CheckProcess(*m.link, now);
      if (!end) {
        m.family->Drain(*m.link, *m.health, haptic, *m.trace, t0);
        end = m.health->CheckStates(*m.link, now, t);
      }
      if (!end) continue;
      if (end->outcome == Outcome::kConflict || end->outcome == Outcome::kRefused ||
          end->outcome == Outcome::kLostControl) {
        // Not ours to drive: the whole fleet ends, as a single run would.
        end->message = "vehicle '" + m.setup.vehicle.name + "': " + end->message;
        fleet_end = std::move(end);
        break;
      }
      if (!m.done) {
        end_member(m, std::move(*end));
      } else if (end->outcome == Outcome::kVehicleLost) {
        m.lost = true;  // after its course: nothing more to hold
      }
    }
    if (fleet_end) break;

    // A person's turn first (a key, a controller button); then the
    // automatic operator's: the driven vehicle's lap is done, or its slice
    // is over and another is waiting.
    if (person.vehicle_requests != vehicle_requests_seen) {
      vehicle_requests_seen = person.vehicle_requests;
      std::vector<bool> over;
      for (const auto& mp : members) over.push_back(mp->done);
      const int asked = RequestedVehicle(person.vehicle_request, target, over);
      if (asked >= 0) {
        switch_to(asked, now, t, "asked by the person");
        ++fleet.person_switches;
      } else if (person.vehicle_request >= 0 &&
                 person.vehicle_request < static_cast<int>(members.size()) &&
                 person.vehicle_request != target) {
        std::snprintf(
            switch_note, sizeof switch_note, "%s: its course is over",
            members[static_cast<size_t>(person.vehicle_request)]->setup.vehicle.name.c_str());
        switch_note_until_t = t + 3.0;
      }
    }
    if (target < 0 || members[static_cast<size_t>(target)]->done) {
      const int next = next_after(target);
      if (next < 0) break;  // every course is done
      switch_to(next, now, t, target < 0 ? "the first" : "the last one's course is over");
    } else if (!person_drives && setup.fleet.slice_s > 0.0 &&
               t - driven_since_t >= setup.fleet.slice_s) {
      // The automatic operator's time slice; a person turns when they choose.
      const int next = next_after(target);
      if (next >= 0 && next != target) switch_to(next, now, t, "its time slice");
    }

    // The person's input and the forces go to one interface only: the
    // driven vehicle's, once the one left has faded out.
    const int live = interfaces.Tick(t, haptic.hal(), person);
    for (size_t i = 0; i < members.size(); ++i) {
      Member& m = *members[i];
      if (m.lost) continue;
      const bool driven = static_cast<int>(i) == target;
      const bool interface_live = static_cast<int>(i) == live;
      if (m.lock_until_t >= 0.0 && t >= m.lock_until_t) {
        m.mux.OnLock(m.handover_lock, false,
                     t);  // turned away from long enough: nothing of ours is live
        m.lock_until_t = -1.0;
      }
      if (driven && m.handover_pending) {
        if (m.released_ns == 0 && interface_live && m.health->up() &&
            m.link->last_received_ns() > m.request_ns) {
          // It has been seen since the request, and its interface is the
          // live one: the operator may command it.
          m.mux.OnLock(m.handover_lock, false, t);
          m.released_ns = now;
          m.link->WatchEcho(now);
        }
        if (m.released_ns != 0) {
          if (const int64_t echoed = m.link->EchoReceivedNs(); echoed != 0) {
            if (m.measure_handover)
              fleet.handover_ms.push_back(static_cast<double>(echoed - m.request_ns) * 1e-6);
            m.handover_pending = false;
          }
        }
      }
      if (driven && m.released_ns != 0) m.mux.OnInput(m.operator_input, t);
      bool changed = false;
      const CommandMux::Selection selection = m.mux.Select(t, &changed);
      m.out.selected = m.mux.SelectedName(selection);
      if (m.health->ours() && (selection != m.published_selection || now >= m.next_selected_ns)) {
        // Who commands it, for anyone on the domain: on a change at once, and now and then for the
        // record.
        m.link->PublishSelected(
            selection.input >= 0 ? m.mux.inputs()[static_cast<size_t>(selection.input)].name : "",
            selection.lock >= 0 ? m.mux.locks()[static_cast<size_t>(selection.lock)].name : "");
        m.published_selection = selection;
        m.next_selected_ns = now + SToNs(kSelectedPeriod_s);
      }
      if (driven && interface_live && selection.input == m.operator_input) {
        m.out.driven_s += dt;
        if (auto end = m.family->Drive(t, now, person, m.health->up(), haptic, *m.link)) {
          fleet_end = std::move(end);
          break;
        }
      } else {
        if (!m.done) m.out.neglected_s += dt;
        if (changed || now >= m.next_hold_ns) {
          m.link->SendSafe();
          m.next_hold_ns = now + hold_period_ns;
        }
      }
      if (m.done) continue;
      if (auto end = m.family->LapEnd()) {
        end_member(m, std::move(*end));
      } else if (m.out.driven_s > m.family->lap_cap_s()) {
        end_member(m,
                   LoopEnd{Outcome::kLapCap,
                           "lap cap of " + std::to_string(static_cast<int>(m.family->lap_cap_s())) +
                               " s of driving reached"});
      }
    }
    if (fleet_end) break;
    interfaces.Settle(t, haptic.hal(),
                      live >= 0 && !members[static_cast<size_t>(live)]->lost &&
                          members[static_cast<size_t>(live)]->family->SwitchingInterface());
    if (view_part) publish_view(t);
    // The session clock's time limit only: each vehicle's lap cap counts its driven time (above).
    if (auto end = CheckLimits(t, std::nullopt, first.time_limit_s, 0.0, 1e300)) {
      fleet_end = std::move(end);
      break;
    }
    if (now >= next_progress_ns) {
      next_progress_ns += SToNs(2.0);
      for (size_t i = 0; i < members.size(); ++i) {
        const std::vector<std::string> short_loops = members[i]->watch->EndInterval(now);
        if (i == 0 && first.progress) {
          for (const std::string& loop : short_loops) log::Warn(loop);
        }
      }
      if (first.progress && target >= 0) {
        Member& m = *members[static_cast<size_t>(target)];
        m.family->LogProgress(t, *m.link, m.out.result.record.distance_m);
        std::string line = "         fleet:";
        for (const auto& mp : members) {
          char part[140];
          std::snprintf(part, sizeof part, " %s %s (driven %.1f s, %.2f m%s)",
                        mp->setup.vehicle.name.c_str(),
                        mp->lost   ? "LOST"
                        : mp->done ? "done"
                                   : mp->out.selected.c_str(),
                        mp->out.driven_s, mp->out.result.record.distance_m,
                        mp->lost || mp->health->up() ? "" : ", not answering yet");
          line += part;
        }
        log::Info(line);
      }
    }
  }
  const int64_t loop_end_ns = MonotonicNs();
  fleet.operator_cpu_share = (ProcessCpuS() - cpu0_s) / std::max(NsToS(loop_end_ns - t0), 1e-3);
  for (auto& m : members) m->watch->EndInterval(loop_end_ns);
  if (pump) pump->Stop();

  // --- The end: who was not done ends as the fleet did. ---
  if (fleet_end) {
    for (auto& m : members) {
      if (m->done) continue;
      LoopEnd end = *fleet_end;
      Finish(m->out.result, std::move(end), m->family->MadeSafe());
      m->done = true;
    }
    fleet.outcome = fleet_end->outcome;
    fleet.message = fleet_end->message;
  } else {
    const bool all = std::all_of(members.begin(), members.end(), [](const auto& m) {
      return m->out.result.outcome == Outcome::kCompleted;
    });
    fleet.outcome = Outcome::kCompleted;
    if (!all) {
      fleet.outcome = !fleet.lost.empty() ? Outcome::kVehicleLost : Outcome::kLapCap;
      for (const auto& m : members) {
        if (fleet.lost.empty() && m->out.result.outcome != Outcome::kCompleted) {
          fleet.outcome = m->out.result.outcome;
          break;
        }
      }
    }
    for (const auto& m : members) {
      if (!fleet.message.empty()) fleet.message += "; ";
      // A vehicle never heard from was not lost: it never answered (an
      // attached one that is not running, or a spawned one that never came up).
      fleet.message +=
          m->setup.vehicle.name + " " +
          (m->out.result.outcome == Outcome::kVehicleDidNotStart ? std::string("never answered")
                                                                 : ToString(m->out.result.outcome));
    }
  }

  // Make safe: forces to zero, every vehicle stopped or at neutral.
  haptic.hal().ZeroForces();
  for (auto& m : members) {
    m->family->RequestStop();
    if (!m->lost) m->link->SendSafe();
  }
  for (auto& m : members) m->family->Finish(m->out.result, first.progress);
  // The view's figures are the first vehicle's record's (one window for all).
  if (view_part) StopAndRecord(*view_part, members.front()->out.result);
  haptic.Stop();
  fleet.servo_period_p99_us = haptic.Stats().period_p99_us;
  const Histogram& cue_periods = haptic.ServoCuePeriods();
  fleet.servo_cue_ticks = cue_periods.Count();
  fleet.servo_cue_period_p99_us = fleet.servo_cue_ticks > 0 ? cue_periods.Percentile(0.99) : -1.0;
  // Every vehicle released and ended at once: one after the other, each
  // would wait for the others' processes to end, past its watchdog.
  {
    std::vector<std::thread> stopping;
    for (auto& m : members) {
      if (!m->lost) m->link->SendSafe();
      stopping.emplace_back([link = m->link.get()] { link->Stop(); });
    }
    for (std::thread& thread : stopping) thread.join();
  }
  for (auto& m : members) {
    RecordLinkFigures(haptic, *m->link, m->out.result);
    m->watch->Finish(m->out.result.record);
    m->out.result.record.outcome = ToString(m->out.result.outcome);
    fleet.vehicles.push_back(std::move(m->out));
  }
  fleet.handover_ms_p50 = NearestRank(fleet.handover_ms, 0.50);
  fleet.handover_ms_p95 = NearestRank(fleet.handover_ms, 0.95);
  return fleet;
}

}  // namespace haptel::mediator
