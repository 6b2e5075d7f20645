// The study file: the shipped synthetic study loads and plans; every file
// that cannot work is refused before anything runs, naming the file, the key
// and what was expected.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <string>

#include "haptel/config/error.hpp"
#include "haptel/config/study.hpp"
#include "haptel/link/families.hpp"
#include "haptel/link/participant.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/study/camera_setup.hpp"
#include "haptel/study/definition.hpp"
#include "haptel/study/design.hpp"
#include "haptel/study/plan.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::study;

namespace {

/// A valid synthetic study with `tail` appended (or replacing a section).
std::string Study(const std::string& conditions, const std::string& participants,
                  const std::string& extra = "") {
  const auto source = std::filesystem::current_path();
  return "name: s\nrun: " + (source / "config/haptel.yaml").string() +
         "\noperators: synthetic\nconditions:\n" + conditions +
         "profiles:\n  p: {steering_noise: 0.02}\nparticipants:\n" + participants + extra;
}

const std::string kFour =
    "  - {name: a, interface: gesture}\n  - {name: b, interface: cockpit}\n"
    "  - {name: c, interface: cockpit-hud}\n  - {name: d, interface: cockpit-assisted}\n";
std::string People(int n) {
  std::string out;
  for (int i = 0; i < n; ++i) out += "  - {id: P" + std::to_string(i) + ", profile: p}\n";
  return out;
}

std::string ErrorOf(const std::string& text) {
  const auto dir = test::ScratchDir("study-file");
  const auto file = dir / "bad.yaml";
  test::WriteFile(file, text);
  return test::WhatOf<ConfigError>([&] { PlanTrials(LoadStudy(file)); });
}

}  // namespace

TEST_CASE("The shipped synthetic study loads and plans a balanced Latin square") {
  const StudyConfig s = LoadStudy("config/studies/grand-prix-synthetic.yaml");
  CHECK(s.name == "grand-prix-synthetic");
  REQUIRE(s.conditions.size() == 4);
  CHECK(s.conditions[2].interface == "cockpit-assisted");
  REQUIRE(s.participants.size() == 4);
  CHECK(s.profiles.at(s.participants[3].profile).learning_gain > 0.0);
  CHECK(s.track.filename() == "test-short.yaml");
  const std::vector<PlannedTrial> plan = PlanTrials(s);
  REQUIRE(plan.size() == 16);
  // Each condition once per position (a Latin square), checked independently of the design code.
  for (int position = 1; position <= 4; ++position) {
    std::set<std::string> at;
    for (const PlannedTrial& t : plan) {
      if (t.position == position) at.insert(t.condition);
    }
    CHECK(at.size() == 4);
  }
}

TEST_CASE(
    "The shipped people's study loads and plans the thesis's study: four people, four interfaces, "
    "questionnaires") {
  const StudyConfig s = LoadStudy("config/studies/grand-prix.yaml");
  CHECK(s.name == "grand-prix");
  CHECK(s.operators == "person");
  REQUIRE(s.conditions.size() == 4);
  CHECK(s.conditions[3].interface == "gesture");
  CHECK(s.participants.size() == 4);
  CHECK(s.trial_cap_s == Approx(600.0));
  CHECK(s.repetitions == 1);
  CHECK(s.track.filename() == "grand-prix.yaml");
  CHECK(s.questionnaires.size() == 2);
  CHECK(s.demographics == "demographics");  // the participants' background, asked once
  CHECK(PlanTrials(s).size() == 16);
  // With a mouse alone: every hand condition on the mouse device.
  for (const StudyCondition& c : s.conditions) CHECK(c.device_name == "mouse");
  CHECK(s.practice);  // with the keys, as before
  // The variant with force feedback: the cockpits on a wheel, the gesture on a joystick.
  const StudyConfig ff = LoadStudy("config/studies/grand-prix-ff.yaml");
  REQUIRE(ff.conditions.size() == 4);
  for (const StudyCondition& c : ff.conditions) {
    INFO(c.name);
    CHECK(c.device_name == (c.interface == "gesture" ? "sdl-ff" : "sdl-ff-wheel"));
  }
  for (const PlannedTrial& t : PlanTrials(ff)) CHECK(t.device.rfind("sdl-ff", 0) == 0);
}

TEST_CASE("Conditions may differ only in the predictive display; the link's fault is the study's") {
  const auto dir = test::ScratchDir("study-file-predict");
  const auto file = test::WriteFile(
      dir / "predict.yaml", Study("  - {name: plain, interface: gesture}\n"
                                  "  - {name: predicted, interface: gesture, predict: true}\n",
                                  People(2), "link_fault: delay=200ms,jitter=10ms\n"));
  const StudyConfig config = LoadStudy(file);
  REQUIRE(config.conditions.size() == 2);
  CHECK(config.conditions[0].interface == config.conditions[1].interface);
  CHECK_FALSE(config.conditions[0].predict);
  CHECK(config.conditions[1].predict);
  CHECK(config.link_fault == "delay=200ms,jitter=10ms");

  const std::string bad_fault = ErrorOf(Study(kFour, People(4), "link_fault: delay=fast\n"));
  CHECK_THAT(bad_fault, Catch::Contains("bad.yaml") && Catch::Contains("link_fault"));
  const StudyConfig on_lte = LoadStudy(
      test::WriteFile(dir / "lte.yaml",
                      Study(kFour, People(4), "link_profile: lte-uplink\nlink_fault: loss=2%\n")));
  CHECK(on_lte.link_profile == "lte-uplink");
  const std::string bad_profile = ErrorOf(Study(kFour, People(4), "link_profile: dialup\n"));
  CHECK_THAT(bad_profile,
             Catch::Contains("bad.yaml") && Catch::Contains("link_profile") &&
                 Catch::Contains("expected one of lan, lte-uplink, satellite, wifi-busy"));
  const std::string bad_predict = ErrorOf(Study(
      "  - {name: a, interface: gesture, predict: maybe}\n  - {name: b, interface: gesture}\n",
      People(2)));
  CHECK_THAT(bad_predict, Catch::Contains("conditions[0].predict"));
}

TEST_CASE(
    "A study file that cannot work is refused naming the file, the key and what was expected") {
  SECTION("an unknown interface") {
    const std::string e = ErrorOf(Study(
        "  - {name: a, interface: gesture}\n  - {name: b, interface: wheelchair}\n", People(2)));
    CHECK_THAT(e, Catch::Contains("bad.yaml") && Catch::Contains("conditions[1].interface") &&
                      Catch::Contains("wheelchair"));
  }
  SECTION("a duplicate participant") {
    const std::string e = ErrorOf(Study(kFour, People(4) + "  - {id: P1, profile: p}\n"));
    CHECK_THAT(e, Catch::Contains("participants[4].id") && Catch::Contains("'P1' appears twice"));
  }
  SECTION("a balanced Latin square that does not fit the participants") {
    const std::string e = ErrorOf(Study(kFour, People(3)));
    CHECK_THAT(e, Catch::Contains("bad.yaml") && Catch::Contains("'design'") &&
                      Catch::Contains("multiple of 4") && Catch::Contains("3"));
  }
  SECTION("a person's keyboard for a simulated driver") {
    const std::string e = ErrorOf(Study(
        "  - {name: a, interface: gesture}\n  - {name: k, interface: keyboard}\n", People(2)));
    CHECK_THAT(e,
               Catch::Contains("conditions[1].interface") && Catch::Contains("simulated driver"));
  }
  SECTION("an unknown profile") {
    const std::string e = ErrorOf(Study(kFour, "  - {id: A, profile: ghost}\n"));
    CHECK_THAT(e, Catch::Contains("participants[0].profile") && Catch::Contains("ghost"));
  }
  SECTION("a profile value out of range") {
    std::string text = Study(kFour, People(4));
    text.replace(text.find("steering_noise: 0.02"), 20, "steering_noise: 3.0");
    const std::string e = ErrorOf(text);
    CHECK_THAT(e, Catch::Contains("steering_noise") && Catch::Contains("[0, 1]"));
  }
  SECTION("a name with spaces, a seed without random order, an unknown key") {
    CHECK_THAT(ErrorOf("name: my study\n"), Catch::Contains("'name'"));
    CHECK_THAT(ErrorOf(Study(kFour, People(4), "design: {order: fixed, seed: 3}\n")),
               Catch::Contains("design.seed") && Catch::Contains("order: random"));
    CHECK_THAT(ErrorOf(Study(kFour, People(4), "lap_count: 3\n")),
               Catch::Contains("lap_count") && Catch::Contains("unknown key"));
  }
  SECTION(
      "demographics: people only, a questionnaire's name, not also asked after each condition") {
    CHECK_THAT(ErrorOf(Study(kFour, People(4), "demographics: demographics\n")),
               Catch::Contains("'demographics'") && Catch::Contains("simulated drivers"));
    std::string person = Study(kFour, "  - {id: A}\n", "demographics: demographics\n");
    person.replace(person.find("operators: synthetic"), 20, "operators: person");
    const std::string profiles = "profiles:\n  p: {steering_noise: 0.02}\n";
    person.replace(person.find(profiles), profiles.size(), "");
    const auto dir = test::ScratchDir("study-file-demographics");
    CHECK(LoadStudy(test::WriteFile(dir / "good.yaml", person)).demographics == "demographics");
    std::string twice = person + "questionnaires: [demographics]\n";
    CHECK_THAT(ErrorOf(twice),
               Catch::Contains("'demographics'") && Catch::Contains("in 'questionnaires'"));
    std::string spaced = person;
    spaced.replace(spaced.find("demographics: demographics"), 26, "demographics: about you");
    CHECK_THAT(ErrorOf(spaced), Catch::Contains("'demographics'") && Catch::Contains("1 to 40"));
  }
}

namespace {

std::string Text(const std::filesystem::path& file) {
  std::ifstream in(file);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

/// A person study on the shipped run file whose conditions are `conditions`.
std::string PersonStudy(const std::string& conditions) {
  const auto source = std::filesystem::current_path();
  return "name: p\nrun: " + (source / "config/haptel.yaml").string() +
         "\noperators: person\nconditions:\n" + conditions +
         "design: {order: fixed}\nparticipants:\n  - {id: A}\n";
}

}  // namespace

TEST_CASE(
    "Each condition names the device it is driven with, a device file checked as one; the plan "
    "carries it") {
  const auto source = std::filesystem::current_path();
  const auto dir = test::ScratchDir("study-file-devices");
  // A device file beside the study, named relative to it.
  std::string sim = Text(source / "config/devices/sim.yaml");
  sim.replace(sim.find("name: sim"), 9, "name: mine");
  test::WriteFile(dir / "mine.yaml", sim);
  const StudyConfig s = LoadStudy(
      test::WriteFile(dir / "devices.yaml",
                      PersonStudy("  - {name: a, interface: gesture, device: " +
                                  (source / "config/devices/udp.yaml").string() +
                                  "}\n"
                                  "  - {name: b, interface: cockpit}\n"
                                  "  - {name: c, interface: cockpit-hud, device: mine.yaml}\n")));
  REQUIRE(s.conditions.size() == 3);
  CHECK(s.conditions[0].device_name == "udp");
  // None named: the run file's.
  CHECK(std::filesystem::equivalent(s.conditions[1].device, source / "config/devices/sim.yaml"));
  CHECK(s.conditions[1].device_name == "sim");
  CHECK(s.conditions[2].device == dir / "mine.yaml");
  CHECK(s.conditions[2].device_name == "mine");
  const std::vector<PlannedTrial> plan = PlanTrials(s);
  REQUIRE(plan.size() == 3);
  CHECK(plan[0].device == "udp");
  CHECK(plan[1].device == "sim");
  CHECK(plan[2].device == "mine");
  CHECK(PlanParticipant(s, "B", 1)[2].device == "mine");
  // The device defines the study: a resumed one is held to it.
  std::string form;
  for (const DefiningValue& v : StudyDefinition(s)) {
    if (v.key == "conditions.c.device") form = v.value;
  }
  CHECK(form == "mine.yaml");

  SECTION("a device file that is not there, or not a device file, or empty, is refused") {
    CHECK_THAT(ErrorOf(PersonStudy("  - {name: a, interface: gesture}\n"
                                   "  - {name: b, interface: gesture, device: nowhere.yaml}\n")),
               Catch::Contains("bad.yaml") && Catch::Contains("conditions[1].device") &&
                   Catch::Contains("nowhere.yaml") && Catch::Contains("expected a device file"));
    std::string slow = Text(source / "config/devices/sim.yaml");
    slow.replace(slow.find("rate_hz: 1000"), 13, "rate_hz: 5");
    const auto slow_file = test::WriteFile(dir / "slow.yaml", slow);
    CHECK_THAT(
        ErrorOf(PersonStudy("  - {name: a, interface: gesture, device: " + slow_file.string() +
                            "}\n"
                            "  - {name: b, interface: gesture}\n")),
        Catch::Contains("conditions[0].device") && Catch::Contains("slow.yaml") &&
            Catch::Contains("servo.rate_hz"));
    CHECK_THAT(ErrorOf(PersonStudy("  - {name: a, interface: gesture, device: ''}\n"
                                   "  - {name: b, interface: gesture}\n")),
               Catch::Contains("conditions[0].device") && Catch::Contains("non-empty"));
  }
}

namespace {

/// A person study of the blimp with both cameras, its conditions `conditions`.
std::string BlimpStudy(const std::string& conditions) {
  const auto source = std::filesystem::current_path();
  return "name: s\nrun: " + (source / "config/blimp-surveillance.yaml").string() +
         "\ntrack: " + (source / "config/tracks/blimp-hop.yaml").string() +
         "\noperators: person\npractice: false\nconditions:\n" + conditions;
}

}  // namespace

TEST_CASE(
    "A condition names its camera set-up: the shipped study's three, and each bad key refused "
    "naming the file, the key and what was expected",
    "[cameras]") {
  const StudyConfig s = LoadStudy("config/studies/blimp-camera-setups.yaml");
  REQUIRE(s.conditions.size() == 3);
  CHECK(s.conditions[0].cameras == std::vector<std::string>{"pilot"});
  CHECK(s.conditions[0].station.empty());
  CHECK(s.conditions[1].cameras == std::vector<std::string>{"pilot", "surveillance"});
  CHECK(s.conditions[2].station == "surveillance");
  CHECK(CameraSetupText(s.conditions[0]) == "cameras pilot");
  CHECK(CameraSetupText(s.conditions[2]) ==
        "cameras pilot + surveillance, a station holds surveillance");
  // The console's trial card says it before the trial starts.
  CHECK(WithCameraSetup("participant A, with-station (position 1)", s.conditions[2]) ==
        "participant A, with-station (position 1); cameras pilot + surveillance, a station holds "
        "surveillance");
  // The database's record of the study holds each condition's set-up.
  const std::string definition = DefinitionText(StudyDefinition(s));
  CHECK_THAT(definition, Catch::Contains("conditions.one-camera.cameras: pilot\n") &&
                             Catch::Contains("conditions.with-station.station: surveillance\n"));
  StudyCondition plain;
  CHECK(WithCameraSetup("participant A, x (position 1)", plain) == "participant A, x (position 1)");

  const std::string keys = "  - {name: a, interface: blimp-keys}\n";
  SECTION("a camera the vehicle does not have") {
    const std::string e = ErrorOf(
        BlimpStudy(keys + "  - {name: b, interface: blimp-keys, cameras: [pilot, rear]}\n"));
    CHECK_THAT(e, Catch::Contains("bad.yaml") && Catch::Contains("conditions[1].cameras") &&
                      Catch::Contains("no camera 'rear'") &&
                      Catch::Contains("(pilot, surveillance)"));
  }
  SECTION("the driven camera left out") {
    const std::string e = ErrorOf(
        BlimpStudy(keys + "  - {name: b, interface: blimp-keys, cameras: [surveillance]}\n"));
    CHECK_THAT(e, Catch::Contains("conditions[1].cameras") &&
                      Catch::Contains("the driven camera 'pilot' among them"));
  }
  SECTION("a station on the driven camera") {
    const std::string e =
        ErrorOf(BlimpStudy(keys + "  - {name: b, interface: blimp-keys, station: pilot}\n"));
    CHECK_THAT(e, Catch::Contains("conditions[1].station") &&
                      Catch::Contains("a camera other than the driven one"));
  }
  SECTION("a station on a camera the condition does not stream") {
    const std::string e = ErrorOf(BlimpStudy(
        keys + "  - {name: b, interface: blimp-keys, cameras: [pilot], station: surveillance}\n"));
    CHECK_THAT(e, Catch::Contains("conditions[1].station") &&
                      Catch::Contains("'surveillance' is not streamed"));
  }
}

TEST_CASE(
    "A station condition's trial is refused until a station is at the camera, with a line naming "
    "the command that starts one",
    "[cameras]") {
  LinkConfig link;
  link.domain_id = test::UniqueDomain(41);
  StationWatch watch(link, "blimp1", "surveillance", "with-station");
  const std::string refused = watch.Missing();
  CHECK(refused == StationMissingLine("with-station", "surveillance", "blimp1", link.domain_id));
  CHECK_THAT(refused,
             Catch::Contains("condition 'with-station'") &&
                 Catch::Contains("haptel station --vehicle blimp1 --camera surveillance") &&
                 Catch::Contains("--domain " + std::to_string(link.domain_id)));
  // A station starts (its command writer, as `haptel station` makes it while it waits for the
  // vehicle): the trial may start.
  {
    link::Participant station(link, "test-station");
    link::CameraCommandWriter writer(station, link::CameraCommandTopic("blimp1", "surveillance"),
                                     link::CameraMessages::kCommandProfile);
    REQUIRE(test::WaitFor([&] { return watch.Missing().empty(); }, 20.0));
  }
  // It went away: refused again.
  REQUIRE(test::WaitFor([&] { return !watch.Missing().empty(); }, 20.0));
}
