// One operator, several vehicles: the fleet's session loop (fleet.hpp).
// Written over FamilySession and VehicleLink as RunSession is, one of each
// per vehicle, and a CommandMux per vehicle for who commands it.
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
#include "haptel/core/log.hpp"
#include "haptel/mediator/command_mux.hpp"
#include "haptel/mediator/fleet.hpp"
#include "haptel/mediator/run_counters.hpp"
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
  bool done = false;             ///< its course is over (completed, lost, crashed, capped)
  bool lost = false;
  int64_t next_hold_ns = 0;
  // A handover to this vehicle under way: requested at request_ns; the lock
  // released (and the echo watched) at released_ns.
  bool handover_pending = false;
  bool measure_handover = false;  ///< false for the run's first vehicle
  int64_t request_ns = 0;
  int64_t released_ns = 0;
  double lock_until_t = -1.0;     ///< turned away from: the lock holds until then
};

std::string FleetRunName(const std::string& fleet, int64_t wall_ns) {
  const std::time_t seconds = static_cast<std::time_t>(wall_ns / 1000000000);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return "fleet " + fleet + " " + text;
}

}  // namespace

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

  // --- The vehicles: each spawned (or attached) and linked on the one domain. ---
  for (auto& m : members) {
    VehicleLinkOptions options;
    options.vehicle = m->setup.vehicle;
    options.link = m->setup.run.link;
    options.track_file = m->family->world_file();
    options.program = m->setup.vehicle_program;
    options.decode_video = false;  // no view shows them yet (issue 30's tiles)
    m->link = std::make_unique<VehicleLink>(options);
    m->out.result.record.vehicle_pid = m->link->pid();
    if (first.progress) {
      log::Info("fleet '" + setup.fleet.name + "': vehicle '" + m->setup.vehicle.name + "' (" +
                m->setup.vehicle.kind + ") " +
                (m->link->pid() != 0 ? "started, pid " + std::to_string(m->link->pid())
                                     : std::string("attached on domain ") + std::to_string(run.link.domain_id)));
    }
  }

  const int64_t t0 = MonotonicNs();
  for (auto& m : members) {
    m->health = std::make_unique<VehicleHealth>(m->setup.vehicle.name, run.link.domain_id, m->link->session(),
                                                run.vehicle_timeout_s);
    m->trace = std::make_unique<RunTrace>(m->out.result.record);
    m->out.result.record.path.reserve(16384);
    m->watch = std::make_unique<LoopWatch>(haptic, m->family->physics(), *m->link, nullptr, t0);
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
    const bool lost = end.outcome == Outcome::kVehicleLost || end.outcome == Outcome::kVehicleDidNotStart;
    end.message = "vehicle '" + m.setup.vehicle.name + "': " + end.message;
    Finish(m.out.result, std::move(end), m.family->MadeSafe());
    m.done = true;
    m.lost = lost;
    if (lost) {
      fleet.lost.push_back(m.setup.vehicle.name);
    } else {
      m.link->SendSafe();
    }
    if (first.progress && !lost) log::Info(m.out.result.message);
  };

  // Turns the operator to vehicle `to` (-1: none left): the handover lock
  // on both, the one left sent zero at once.
  const auto switch_to = [&](int to, int64_t now, double t) {
    if (target >= 0) {
      Member& from = *members[static_cast<size_t>(target)];
      from.mux.OnLock(from.handover_lock, true, t);
      from.lock_until_t = t + kOperatorTimeout_s;
      from.handover_pending = false;
    }
    const bool measured = target >= 0;
    target = to;
    driven_since_t = t;
    if (to < 0) return;
    Member& m = *members[static_cast<size_t>(to)];
    m.mux.OnLock(m.handover_lock, true, t);
    m.lock_until_t = -1.0;
    m.handover_pending = true;
    m.measure_handover = measured;
    m.request_ns = now;
    m.released_ns = 0;
    m.link->WatchEcho(0);
    if (measured) ++m.out.handovers;
    if (first.progress) log::Info("fleet: driving '" + m.setup.vehicle.name + "'");
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
      if (end->outcome == Outcome::kConflict || end->outcome == Outcome::kRefused) {
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

    // The automatic operator's turn: the driven vehicle's lap is done, or
    // its slice is over and another is waiting.
    if (target < 0 || members[static_cast<size_t>(target)]->done) {
      const int next = next_after(target);
      if (next < 0) break;  // every course is done
      switch_to(next, now, t);
    } else if (setup.fleet.slice_s > 0.0 && t - driven_since_t >= setup.fleet.slice_s) {
      const int next = next_after(target);
      if (next >= 0 && next != target) switch_to(next, now, t);
    }

    for (size_t i = 0; i < members.size(); ++i) {
      Member& m = *members[i];
      if (m.lost) continue;
      const bool driven = static_cast<int>(i) == target;
      if (m.lock_until_t >= 0.0 && t >= m.lock_until_t) {
        m.mux.OnLock(m.handover_lock, false, t);  // turned away from long enough: nothing of ours is live
        m.lock_until_t = -1.0;
      }
      if (driven && m.handover_pending) {
        if (m.released_ns == 0 && m.health->up() && m.link->last_received_ns() > m.request_ns) {
          // It has been seen since the request: the operator may command it.
          m.mux.OnLock(m.handover_lock, false, t);
          m.released_ns = now;
          m.link->WatchEcho(now);
        }
        if (m.released_ns != 0) {
          if (const int64_t echoed = m.link->EchoReceivedNs(); echoed != 0) {
            if (m.measure_handover) fleet.handover_ms.push_back(static_cast<double>(echoed - m.request_ns) * 1e-6);
            m.handover_pending = false;
          }
        }
      }
      if (driven && m.released_ns != 0) m.mux.OnInput(m.operator_input, t);
      bool changed = false;
      const CommandMux::Selection selection = m.mux.Select(t, &changed);
      m.out.selected = m.mux.SelectedName(selection);
      if (driven && selection.input == m.operator_input) {
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
        end_member(m, LoopEnd{Outcome::kLapCap, "lap cap of " + std::to_string(static_cast<int>(m.family->lap_cap_s())) +
                                                    " s of driving reached"});
      }
    }
    if (fleet_end) break;
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
          char part[120];
          std::snprintf(part, sizeof part, " %s %s (driven %.1f s%s)", mp->setup.vehicle.name.c_str(),
                        mp->lost ? "LOST" : mp->done ? "done" : mp->out.selected.c_str(), mp->out.driven_s,
                        mp->lost || mp->health->up() ? "" : ", not answering yet");
          line += part;
        }
        log::Info(line);
      }
    }
  }
  for (auto& m : members) m->watch->EndInterval(MonotonicNs());

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
    const bool all = std::all_of(members.begin(), members.end(),
                                 [](const auto& m) { return m->out.result.outcome == Outcome::kCompleted; });
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
      fleet.message += m->setup.vehicle.name + " " + ToString(m->out.result.outcome);
    }
  }

  // Make safe: forces to zero, every vehicle stopped or at neutral.
  haptic.hal().ZeroForces();
  for (auto& m : members) {
    m->family->RequestStop();
    if (!m->lost) m->link->SendSafe();
  }
  for (auto& m : members) m->family->Finish(m->out.result, first.progress);
  haptic.Stop();
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
