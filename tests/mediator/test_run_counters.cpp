// What reaches the user of the parts' counts: the counts the operator side
// reads from the vehicle's states, a loop's rate against its target interval
// by interval and over the run, and the progress line's list of non-zero
// counters.
#include <catch2/catch.hpp>

#include "../../mediator/src/session_loop.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/process_identity.hpp"
#include "haptel/mediator/run_counters.hpp"
#include "haptel/mediator/vehicle_link.hpp"

using namespace haptel;
using haptel::mediator::LinkCounts;
using haptel::mediator::RateCheck;
using haptel::mediator::StateInbox;

namespace {

msg::VehicleState State(uint64_t seq, bool tripped, uint64_t echoed, uint64_t accepted) {
  msg::VehicleState s;
  s.seq(seq);
  s.watchdog_tripped(tripped);
  s.last_command_seq(echoed);
  s.commands_received(accepted);
  return s;
}

}  // namespace

TEST_CASE("the states tell missed states, watchdog trips and commands the vehicle did not accept") {
  StateInbox inbox;
  // Before any command: the watchdog is tripped; commands sent before the
  // vehicle listened (seq 1..177) are not the vehicle's to drop.
  inbox.Push(State(1, true, 0, 0));
  inbox.Push(State(2, true, 0, 0));
  inbox.Push(State(3, false, 178, 1));
  CHECK(inbox.Counts().watchdog_trips == 0);
  CHECK(inbox.Counts().commands_dropped == 0);
  CHECK(inbox.Counts().states_missed == 0);

  inbox.Push(State(4, false, 200, 23));  // every command taken
  CHECK(inbox.Counts().commands_dropped == 0);
  inbox.Push(State(7, false, 210, 30));  // 3 of 10 not taken; states 5 and 6 never came
  CHECK(inbox.Counts().commands_dropped == 3);
  CHECK(inbox.Counts().states_missed == 2);

  inbox.Push(State(8, true, 210, 30));  // commands stopped: the watchdog trips
  inbox.Push(State(9, true, 210, 30));  // still tripped: one trip
  inbox.Push(State(10, false, 220, 40));
  inbox.Push(State(11, true, 220, 40));
  const LinkCounts counts = inbox.Counts();
  CHECK(counts.watchdog_trips == 2);
  CHECK(counts.commands_dropped == 3);
  CHECK(counts.states_missed == 2);

  // A vehicle that started again counts afresh, keeping what was counted.
  inbox.Push(State(1, false, 230, 1));
  inbox.Push(State(2, false, 240, 6));
  CHECK(inbox.Counts().commands_dropped == 3 + 5);
  CHECK(inbox.Counts().states_missed == 2);
  CHECK(inbox.Drain().size() == 11);
}

TEST_CASE(
    "the states tell the video feedback the vehicle refused, from the first state this run "
    "received") {
  StateInbox inbox;
  const auto state = [](uint64_t seq, uint64_t refused) {
    msg::VehicleState s = State(seq, false, 0, 0);
    s.video_feedback_refused(refused);
    return s;
  };
  // An attached vehicle had refused 4 before this run: not this run's.
  inbox.Push(state(1, 4));
  CHECK(inbox.Counts().video_feedback_refused == 0);
  inbox.Push(state(2, 10));  // a stranger's feedback, refused
  CHECK(inbox.Counts().video_feedback_refused == 6);
  // The vehicle started again: it counts from 0, what was counted is kept.
  inbox.Push(state(1, 3));
  CHECK(inbox.Counts().video_feedback_refused == 9);
}

TEST_CASE(
    "a command goes out the tick it changes; an unchanged one once a period, counted from the "
    "last one sent") {
  using haptel::mediator::CommandDue;
  constexpr int64_t kMs = 1'000'000, kPeriod = 20 * kMs;  // the interfaces' 50 Hz
  int64_t next = 0;
  const auto due = [&](int64_t t_ms, bool changed) {
    return CommandDue(next, t_ms * kMs, kPeriod, changed);
  };
  CHECK(due(0, false));
  CHECK_FALSE(due(10, false));
  CHECK(due(20, false));
  CHECK(due(25, true));  // not 40: the person's input does not wait
  CHECK_FALSE(due(35, false));
  CHECK_FALSE(due(40, false));
  CHECK(due(45, false));  // a period after the change
  // Changing every 10-ms session tick: one each tick, no more (the link's bound).
  int sent = 0;
  for (int64_t t = 100; t < 200; t += 10) sent += due(t, true) ? 1 : 0;
  CHECK(sent == 10);
}

TEST_CASE("between ticks a command goes out only when the robot's motor levels change") {
  using haptel::mediator::LevelsChange;
  constexpr int kLevels = 8;  // per direction: a level is 0.125, the first from 0.0625
  CHECK_FALSE(LevelsChange({0.0, 0.0}, {0.05, 0.05}, kLevels));  // within the stopped level
  CHECK(LevelsChange({0.0, 0.0}, {0.07, 0.07}, kLevels));        // the first level forward
  CHECK(LevelsChange({0.0, 0.0}, {0.0, -0.07}, kLevels));        // either tread
  CHECK_FALSE(LevelsChange({0.5, 0.3}, {0.52, 0.31}, kLevels));  // within the same levels
  CHECK(LevelsChange({0.5, 0.3}, {0.5, 0.15}, kLevels));  // the right tread from level 2 to 1
}

TEST_CASE("a loop below 90 % of its target says so, interval by interval and for the run") {
  const int64_t t0 = SToNs(100.0);
  RateCheck servo("servo", 1000.0, 50, t0);
  CHECK(servo.target_hz() == 1000.0);
  CHECK_FALSE(servo.EndInterval(50 + 1950, t0 + SToNs(2.0)));  // 975 Hz: kept
  CHECK_FALSE(servo.short_of_rate());
  CHECK_FALSE(servo.EndInterval(2500, t0 + SToNs(2.1)));  // too short an interval to judge
  const auto line = servo.EndInterval(2000 + 612, t0 + SToNs(4.0));  // 306 Hz
  REQUIRE(line);
  CHECK(*line == "servo 306 Hz of 1000 Hz: cannot keep its rate");
  CHECK(servo.short_of_rate());
  CHECK_FALSE(servo.EndInterval(2612 + 1990, t0 + SToNs(6.0)));
  CHECK(servo.short_of_rate());  // once short, the run is marked

  RateCheck physics("physics", 10000.0, 0, t0);
  LoopStats run;
  run.ticks = 26;
  run.elapsed_s = 2.0;
  run.rate_hz = 13.0;
  const auto whole = physics.EndRun(run);
  REQUIRE(whole);
  CHECK(*whole == "physics 13 Hz of 10000 Hz: cannot keep its rate");
  CHECK(physics.short_of_rate());

  RateCheck kept("physics", 1000.0, 0, t0);
  run.rate_hz = 950.0;
  CHECK_FALSE(kept.EndRun(run));
  CHECK_FALSE(kept.short_of_rate());
}

TEST_CASE("the progress line lists the counters that are not zero") {
  CHECK(mediator::NonZeroCounters({{"a", 0}, {"b", 0}}).empty());
  CHECK(
      mediator::NonZeroCounters({{"servo_overruns", 3}, {"b", 0}, {"video_frames_dropped", 12}}) ==
      "servo_overruns 3, video_frames_dropped 12");
}

TEST_CASE(
    "a run that started its vehicle takes states from that process only; a stranger's first state "
    "is a conflict") {
  const int64_t spawned = 4242;
  mediator::VehicleHealth health("robot1", 7, /*session=*/99, link::WriterId{},
                                 /*vehicle_timeout_s=*/1.0,
                                 mediator::VehicleHealth::kStartupTimeout_s, spawned);
  msg::VehicleState ours;
  ours.vehicle_pid(spawned);
  ours.vehicle_host(HostName());
  CHECK_FALSE(health.FromAnotherProcess(ours));
  CHECK_FALSE(health.StrangerConflict());

  msg::VehicleState elsewhere = ours;  // the same pid on another host is another process
  elsewhere.vehicle_host("other-host");
  CHECK(health.FromAnotherProcess(elsewhere));
  msg::VehicleState stray = ours;
  stray.vehicle_pid(5151);
  CHECK(health.FromAnotherProcess(stray));
  const auto end = health.StrangerConflict();
  REQUIRE(end);
  CHECK(end->outcome == mediator::Outcome::kConflict);
  // Named by the first stranger seen, against the run's own vehicle.
  CHECK(end->message.find(
            "another vehicle answers as 'robot1' on domain 7 (pid 4242 on host 'other-host', "
            "not the vehicle this run started, pid 4242)") != std::string::npos);
  CHECK_FALSE(health.FromAnotherProcess(ours));  // its own states are still its own

  // Attached (no process of the run's): any process may send the states.
  mediator::VehicleHealth attached("robot1", 7, 99, link::WriterId{}, 1.0);
  CHECK_FALSE(attached.FromAnotherProcess(stray));
  CHECK_FALSE(attached.StrangerConflict());
}

namespace {

/// A DDS writer's identity: participant `p` (its GUID prefix), writer 3.
link::WriterId WriterOf(uint8_t p) {
  link::WriterId id;
  id.guid[0] = 0x01;
  id.guid[1] = 0x0f;
  id.guid[11] = p;
  id.guid[15] = 3;
  return id;
}

msg::VehicleState OwnedBy(const link::WriterId& writer, uint64_t session, const char* name) {
  msg::VehicleState s;
  s.owner_writer(writer.guid);
  s.owner_session(session);
  s.owner(name);
  return s;
}

}  // namespace

TEST_CASE(
    "a run that drove its vehicle says at once when another writer's commands are obeyed: lost "
    "control") {
  const link::WriterId mine = WriterOf(1);
  const int64_t ms = 1'000'000;
  {
    // This run's writer owned it, then another run's does (this run fell
    // silent past the vehicle's free time, and a waiting operator took it).
    mediator::VehicleHealth health("robot1", 7, /*session=*/99, mine, 1.0);
    health.OnState(OwnedBy(mine, 99, "this run"), 10 * ms);
    CHECK_FALSE(health.LostControl());
    CHECK(health.ours());
    health.OnState(OwnedBy(WriterOf(2), 55, "haptel run, bo@lab pid 7"), 20 * ms);
    const auto end = health.LostControl();
    REQUIRE(end);  // at once: no grace for a vehicle that was this run's
    CHECK(end->outcome == mediator::Outcome::kLostControl);
    CHECK(mediator::ToString(end->outcome) == "lost control");
    CHECK(mediator::ExitCode(end->outcome) == 2);
    CHECK(end->message.find(
              "vehicle 'robot1' on domain 7 obeys another writer's commands now, not this run's: "
              "'haptel run, bo@lab pid 7', writer ") != std::string::npos);
    CHECK(end->message.find("this run lost control") != std::string::npos);
  }
  {
    // A stranger naming this run's session (copied off the wire) is obeyed:
    // lost control, said so, even before this run's writer was seen owning it.
    mediator::VehicleHealth health("robot1", 7, 99, mine, 1.0);
    health.OnState(OwnedBy(WriterOf(9), 99, "haptel run, ana@lab pid 4"), 10 * ms);
    const auto end = health.LostControl();
    REQUIRE(end);
    CHECK(end->message.find("a participant that names this run's session (copied off the link") !=
          std::string::npos);
  }
  {
    // Never this run's, another run's: refused after its grace, not lost control.
    mediator::VehicleHealth health("robot1", 7, 99, mine, 1.0);
    health.OnState(OwnedBy(WriterOf(2), 55, "bo"), 10 * ms);
    CHECK_FALSE(health.LostControl());
    CHECK_FALSE(health.ours());
    // Free again (a vehicle restarted, an owner released it) is not a loss either.
    mediator::VehicleHealth freed("robot1", 7, 99, mine, 1.0);
    freed.OnState(OwnedBy(mine, 99, "this run"), 10 * ms);
    freed.OnState(OwnedBy({}, 0, ""), 20 * ms);
    CHECK_FALSE(freed.LostControl());
  }
}

TEST_CASE(
    "commands dropped count this run's echoes only: a stranger's sequence is not this run's") {
  // The figure: a stranger obeyed with sequence numbers from 10^9
  // made the owner's run report 999999724 commands dropped.
  const link::WriterId mine = WriterOf(1);
  StateInbox inbox;
  inbox.SetOwnWriter(mine);
  const auto state = [](uint64_t seq, const link::WriterId& owner, uint64_t echoed,
                        uint64_t accepted) {
    msg::VehicleState s = State(seq, false, echoed, accepted);
    s.owner_writer(owner.guid);
    return s;
  };
  inbox.Push(state(1, mine, 100, 1));
  inbox.Push(state(2, mine, 110, 9));  // 2 of 10 not taken
  CHECK(inbox.Counts().commands_dropped == 2);
  inbox.Push(state(3, WriterOf(9), 1'000'000'050, 60));  // a stranger's command obeyed
  inbox.Push(state(4, WriterOf(9), 1'000'000'090, 100));
  CHECK(inbox.Counts().commands_dropped == 2);
  // This run's again (the stranger fell silent): counted from there, what was counted kept.
  inbox.Push(state(5, mine, 300, 101));
  inbox.Push(state(6, mine, 310, 111));
  CHECK(inbox.Counts().commands_dropped == 2);
  inbox.Push(state(7, mine, 320, 116));  // 5 of 10 not taken
  CHECK(inbox.Counts().commands_dropped == 2 + 5);
}
