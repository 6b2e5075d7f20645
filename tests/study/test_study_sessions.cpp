// The sessions a study runs: a person's practice lap shows a simulated robot
// in the third person as well as through its camera; a trial never does. A
// trial is driven with its condition's device.
#include <catch2/catch.hpp>
#include <cstdlib>

#include "haptel/config/device.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/study.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/study/plan.hpp"
#include "haptel/study/study_sessions.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::study;

TEST_CASE("A practice lap shows the simulated robot in the third person; a trial does not") {
  const StudyConfig config = LoadStudy("config/studies/grand-prix-synthetic.yaml");
  const std::vector<PlannedTrial> plan = PlanTrials(config);
  REQUIRE_FALSE(plan.empty());
  const auto dir = test::ScratchDir("study-sessions");
  const mediator::SessionSetup trial =
      TrialSetup(config, plan.front(), dir / "study.db", "", false, 0, false);
  REQUIRE(trial.vehicle.kind == "sim-robot");
  CHECK_FALSE(trial.third_person);
  CHECK_FALSE(trial.direct_view);
  CHECK_FALSE(trial.single_interface);

  // The same session made a practice lap: the keyboard's direct view, the
  // participant in the title, and the chase camera beside the picture.
  mediator::SessionSetup practice = trial;
  MakePracticeLap(practice, "P3");
  CHECK(practice.third_person);
  CHECK(practice.direct_view);
  CHECK(practice.single_interface);
  CHECK(practice.title == "Haptel - practice lap - P3");

  // A real robot is in the room to be seen: no chase camera of a track
  // that is only a guess for it.
  mediator::SessionSetup real = trial;
  real.vehicle = LoadVehicle("config/vehicles/can-robot.yaml");
  MakePracticeLap(real, "P3");
  CHECK_FALSE(real.third_person);
  CHECK(real.direct_view);
}

TEST_CASE(
    "A trial is driven with its condition's device; a person cannot drive hands on the simulated "
    "one") {
  const auto source = std::filesystem::current_path();
  const auto dir = test::ScratchDir("study-sessions-device");
  const StudyConfig config = LoadStudy(
      test::WriteFile(dir / "people.yaml",
                      "name: people\nrun: " + (source / "config/haptel.yaml").string() +
                          "\noperators: person\nconditions:\n"
                          "  - {name: hands, interface: gesture}\n"
                          "  - {name: pad, interface: gamepad}\n"
                          "design: {order: fixed}\npractice: false\nparticipants: [{id: A}]\n"));
  const std::vector<PlannedTrial> plan = PlanTrials(config);
  REQUIRE(plan.size() == 2);
  for (const PlannedTrial& t : plan) {
    const mediator::SessionSetup trial =
        TrialSetup(config, t, dir / "study.db", "", false, 0, false);
    // The condition's device (here the run file's, named by --device).
    CHECK(std::filesystem::equivalent(trial.run.device, source / "config/devices/sim.yaml"));
    CHECK(trial.device.name == t.device);
    // A controller needs no arms; the gesture's hands on the simulated
    // device cannot be moved by anyone: the study says so before it starts.
    CHECK(PersonCanDrive(trial) == (t.condition == "pad"));
    if (t.condition == "hands") {
      mediator::SessionSetup held = trial;
      held.device = LoadDevice(source / "config/devices/udp.yaml");  // arms a person moves
      CHECK(PersonCanDrive(held));
    }
  }
  // The console is shown each condition's device, and asks it whether it is there.
  const TrialDevice shown = DeviceOf(config.conditions[0]);
  CHECK(shown.name == "sim");
  CHECK(shown.file == config.conditions[0].device);
  REQUIRE(shown.unavailable);
  CHECK(shown.unavailable().empty());  // the simulated device is always there
  CHECK(DeviceOf(StudyCondition{"x", "gesture"}).name.empty());

  // The shipped people's study's mouse, without a display: what is missing, said.
  const TrialDevice mouse = DeviceOf(LoadStudy("config/studies/grand-prix.yaml").conditions[0]);
  CHECK(mouse.name == "mouse");
  const char* display = std::getenv("DISPLAY");
  const std::string saved = display != nullptr ? display : "";
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  const std::string saved_wayland = wayland != nullptr ? wayland : "";
  unsetenv("DISPLAY");
  unsetenv("WAYLAND_DISPLAY");
  const std::string missing = mouse.unavailable();
  if (!saved.empty()) setenv("DISPLAY", saved.c_str(), 1);
  if (!saved_wayland.empty()) setenv("WAYLAND_DISPLAY", saved_wayland.c_str(), 1);
  CHECK_THAT(missing, Catch::Contains("needs a display"));
}

TEST_CASE(
    "A study's reality is every trial's simulated vehicle's; a bad one names the file, the key "
    "and what was expected") {
  const auto source = std::filesystem::current_path();
  const auto dir = test::ScratchDir("study-sessions-reality");
  const std::string head = "name: twin\nrun: " + (source / "config/haptel.yaml").string() +
                           "\noperators: synthetic\nconditions:\n"
                           "  - {name: a, interface: gesture}\n  - {name: b, interface: cockpit}\n"
                           "profiles:\n  p: {steering_noise: 0.02}\n"
                           "participants: [{id: A, profile: p}, {id: B, profile: p}]\n";
  // None named: the vehicle file's (sim-robot.yaml has none), else the run's default.
  const StudyConfig plain = LoadStudy(test::WriteFile(dir / "plain.yaml", head));
  CHECK(plain.reality.empty());
  const mediator::SessionSetup lab =
      TrialSetup(plain, PlanTrials(plain).front(), dir / "study.db", "", false, 0, false);
  CHECK(lab.vehicle.reality.filename() == "lab.yaml");

  const StudyConfig twin = LoadStudy(test::WriteFile(dir / "twin.yaml", head + "reality: none\n"));
  CHECK(std::filesystem::equivalent(twin.reality, source / "config/realities/none.yaml"));
  const mediator::SessionSetup trial =
      TrialSetup(twin, PlanTrials(twin).front(), dir / "study.db", "", false, 0, false);
  CHECK(trial.vehicle.reality == twin.reality);

  // A file beside the study.
  std::filesystem::copy_file(source / "config/realities/harsh.yaml", dir / "mine.yaml");
  const StudyConfig mine =
      LoadStudy(test::WriteFile(dir / "mine-study.yaml", head + "reality: mine.yaml\n"));
  CHECK(mine.reality == dir / "mine.yaml");

  const auto error = [&](const std::string& name, const std::string& text) {
    const auto file = test::WriteFile(dir / name, text);
    return test::WhatOf<ConfigError>([&] { LoadStudy(file); });
  };
  using Catch::Contains;
  CHECK_THAT(error("moon.yaml", head + "reality: moon\n"),
             Contains("moon.yaml") && Contains("reality") &&
                 Contains("none, lab, harsh or a reality file (not 'moon')"));
  CHECK_THAT(error("missing.yaml", head + "reality: nowhere.yaml\n"),
             Contains("missing.yaml") && Contains("reality") && Contains("nowhere.yaml"));
  // A real robot's reality is the world's.
  const std::string can_run =
      test::WriteFile(dir / "can-run.yaml",
                      "vehicle: " + (source / "config/vehicles/can-robot.yaml").string() +
                          "\ntrack: " + (source / "config/tracks/test-short.yaml").string() + "\n")
          .string();
  std::string can = head + "reality: none\n";
  can.replace(can.find("run: ") + 5, (source / "config/haptel.yaml").string().size(), can_run);
  CHECK_THAT(error("can.yaml", can), Contains("can.yaml") && Contains("reality") &&
                                         Contains("a simulated vehicle") &&
                                         Contains("can-robot.yaml"));
}
