// The command mux: priorities, time-outs, locks (explicit and heartbeat),
// zero at once when a lock takes the vehicle, and the selection's name.
#include <catch2/catch.hpp>
#include <stdexcept>
#include <vector>

#include "haptel/interfaces/input.hpp"
#include "haptel/mediator/command_mux.hpp"
#include "haptel/mediator/fleet.hpp"

using haptel::mediator::CommandMux;
using haptel::mediator::MuxInputSpec;
using haptel::mediator::MuxLockSpec;

namespace {

/// The operator's station (100), a second station (50), an autonomy stack
/// (10); a handover lock over the stations (120) and a dead man's switch
/// over the autonomy (20) with a 0.3 s heartbeat.
CommandMux Fleet() {
  return CommandMux({{"operator", 100, 0.5}, {"second", 50, 0.5}, {"autonomy", 10, 1.0}},
                    {{"handover", 120, 0.0}, {"deadman", 20, 0.3}});
}

}  // namespace

TEST_CASE("the live input of the highest priority drives; a silent one times out to the next") {
  CommandMux mux = Fleet();
  mux.OnLock(1, false, 0.0);  // the dead man's switch is held (released lock)
  mux.OnInput(2, 0.0);
  CHECK(mux.Select(0.1).input == 2);
  mux.OnInput(1, 0.2);
  CHECK(mux.Select(0.2).input == 1);
  mux.OnInput(0, 0.25);
  const CommandMux::Selection s = mux.Select(0.3);
  CHECK(s.input == 0);
  CHECK_FALSE(s.zero);
  CHECK(mux.SelectedName(s) == "operator");
  // The operator falls silent: after its 0.5 s the second station has it
  // again, while that one still speaks.
  mux.OnLock(1, false, 0.5);
  mux.OnInput(1, 0.6);
  CHECK(mux.Select(0.75).input == 0);  // 0.5 s after its last: still live
  CHECK(mux.Select(0.76).input == 1);
  // Nobody live: zero, named "none".
  mux.OnLock(1, false, 2.0);
  const CommandMux::Selection nobody = mux.Select(2.2);
  CHECK(nobody.input == -1);
  CHECK(nobody.zero);
  CHECK(mux.SelectedName(nobody) == "none");
}

TEST_CASE("equal priorities: the first declared wins, whoever spoke last") {
  CommandMux mux({{"a", 50, 1.0}, {"b", 50, 1.0}}, {});
  mux.OnInput(1, 0.0);
  mux.OnInput(0, 0.1);
  CHECK(mux.Select(0.2).input == 0);
  mux.OnInput(1, 0.3);
  CHECK(mux.Select(0.3).input == 0);
}

TEST_CASE("a lock holds the inputs of its priority and below, and zero goes out at once") {
  CommandMux mux = Fleet();
  mux.OnLock(1, false, 0.0);
  mux.OnInput(0, 0.0);
  bool changed = false;
  REQUIRE(mux.Select(0.0, &changed).input == 0);
  CHECK(changed);  // the first selection is news
  mux.Select(0.05, &changed);
  CHECK_FALSE(changed);
  // The handover lock engages: the operator (100 <= 120) is held, and so is
  // everyone else: zero, at once, naming the lock.
  mux.OnLock(0, true, 0.1);
  mux.OnInput(0, 0.1);
  const CommandMux::Selection held = mux.Select(0.1, &changed);
  CHECK(changed);
  CHECK(held.zero);
  CHECK(held.input == -1);
  CHECK(held.lock == 0);
  CHECK(mux.SelectedName(held) == "lock:handover");
  // Released: the operator drives again on its next command.
  mux.OnLock(0, false, 0.2);
  mux.OnInput(0, 0.2);
  const CommandMux::Selection back = mux.Select(0.2, &changed);
  CHECK(changed);
  CHECK(back.input == 0);
  CHECK(back.lock == -1);
}

TEST_CASE("a lock above some inputs and below others only holds the lower ones") {
  CommandMux mux = Fleet();
  mux.OnLock(1, true, 0.0);  // the dead man's switch let go: the autonomy (10 <= 20) is held
  mux.OnInput(2, 0.0);
  CommandMux::Selection s = mux.Select(0.0);
  CHECK(s.input == -1);
  CHECK(s.zero);
  CHECK(s.lock == 1);
  mux.OnInput(1, 0.1);  // the second station (50 > 20) is not held
  s = mux.Select(0.1);
  CHECK(s.input == 1);
  CHECK(s.lock == 1);  // still engaged, just not over this input
  CHECK_FALSE(s.zero);
}

TEST_CASE("a heartbeat lock engages when its heartbeat stops, and before it ever beats") {
  CommandMux mux({{"autonomy", 10, 1.0}}, {{"deadman", 20, 0.3}});
  mux.OnInput(0, 0.0);
  CHECK(mux.Select(0.0).lock == 0);  // never heard: engaged
  mux.OnLock(0, false, 0.0);
  mux.OnInput(0, 0.1);
  CHECK(mux.Select(0.1).input == 0);
  mux.OnInput(0, 0.3);
  CHECK(mux.Select(0.3).input == 0);                 // 0.3 s of silence: still held open
  const CommandMux::Selection s = mux.Select(0.31);  // past it: the lock engages
  CHECK(s.lock == 0);
  CHECK(s.zero);
  // An explicit-only lock (time-out 0) never engages by silence.
  CommandMux explicit_only({{"a", 10, 1.0}}, {{"stop", 20, 0.0}});
  explicit_only.OnInput(0, 0.0);
  CHECK(explicit_only.Select(0.5).input == 0);
}

TEST_CASE("the mux's entries are checked, naming the bad one") {
  CHECK_THROWS_WITH(CommandMux({{"", 1, 0.5}}, {}), Catch::Contains("inputs[0].name"));
  CHECK_THROWS_WITH(CommandMux({{"a", 1, 0.5}, {"a", 2, 0.5}}, {}),
                    Catch::Contains("inputs[1].name: 'a' is named twice"));
  CHECK_THROWS_WITH(CommandMux({{"a", 256, 0.5}}, {}),
                    Catch::Contains("inputs[0].priority: expected 0..255"));
  CHECK_THROWS_WITH(CommandMux({{"a", 1, 0.0}}, {}), Catch::Contains("inputs[0].timeout_s"));
  CHECK_THROWS_WITH(CommandMux({}, {{"l", 1, -1.0}}), Catch::Contains("locks[0].timeout_s"));
  // An input and a lock may share a name: they are told apart by kind.
  CHECK_NOTHROW(CommandMux({{"stop", 1, 0.5}}, {{"stop", 2, 0.0}}));
  CommandMux mux({{"keys", 1, 0.5}}, {{"stop", 2, 0.0}});
  CHECK(mux.input_index("keys") == 0);
  CHECK(mux.lock_index("stop") == 0);
  CHECK(mux.input_index("stop") == -1);
}

// --- A fleet's person asking for a vehicle (fleet.hpp: RequestedVehicle). ---

TEST_CASE("a person's request picks the next vehicle whose course is not over, or the one named") {
  using haptel::interfaces::kNextVehicle;
  using haptel::mediator::RequestedVehicle;
  const std::vector<bool> none_over{false, false, false};
  // Tab: the next one, round the end.
  CHECK(RequestedVehicle(kNextVehicle, 0, none_over) == 1);
  CHECK(RequestedVehicle(kNextVehicle, 2, none_over) == 0);
  CHECK(RequestedVehicle(kNextVehicle, -1, none_over) == 0);
  // Past the ones whose course is over.
  CHECK(RequestedVehicle(kNextVehicle, 0, {false, true, false}) == 2);
  CHECK(RequestedVehicle(kNextVehicle, 2, {true, false, false}) == 1);
  // Nobody else waits: no switch.
  CHECK(RequestedVehicle(kNextVehicle, 1, {true, false, true}) == -1);
  CHECK(RequestedVehicle(kNextVehicle, 0, {true, true, true}) == -1);
  // 1..9: that one, unless it is driven already, over, or not in the fleet.
  CHECK(RequestedVehicle(2, 0, none_over) == 2);
  CHECK(RequestedVehicle(0, 0, none_over) == -1);
  CHECK(RequestedVehicle(1, 0, {false, true, false}) == -1);
  CHECK(RequestedVehicle(3, 0, none_over) == -1);
}
