// A study with people, end to end (issue 36): `haptel study run` of a study
// like the shipped grand-prix.yaml (its four conditions on the mouse device)
// on the short track, its console in headless Chromium (the experimenter,
// study_experimenter.py: adds participant A, checks each trial's device,
// presses Start, answers the questionnaire), each trial's window on the
// test's own Xvfb driven by the pointer pilot (testing/pointer_pilot.hpp) as
// a person at the mouse would. Every trial's lap is stored, none at the cap.
#include <sqlite3.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "child.hpp"
#include "haptel/config/run.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/testing/pointer_pilot.hpp"
#include "study_file.hpp"
#include "test_env.hpp"
#include "xserver.hpp"

using namespace haptel;
using haptel::test::Child;

namespace {

std::string Bin(const std::string& name) { return (test::BinDir() / name).string(); }

constexpr double kCap_s = 60.0;  // the short track's lap cap: a lap the pilot finishes well within

/// The study's conditions (name, interface): grand-prix.yaml's four.
const std::map<std::string, std::string> kConditions = {{"cockpit", "cockpit"},
                                                        {"cockpit-hud", "cockpit-hud"},
                                                        {"assisted", "cockpit-assisted"},
                                                        {"gesture", "gesture"}};

/// The lines of `text` that start with `prefix`, without it.
std::vector<std::string> LinesAfter(const std::string& text, const std::string& prefix) {
  std::vector<std::string> found;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(prefix, 0) == 0) found.push_back(line.substr(prefix.size()));
  }
  return found;
}

/// Trials the study has finished so far (its one line each: "[study]   completed: lap ...").
size_t TrialsEnded(const std::string& err) {
  size_t n = 0;
  for (size_t at = err.find(" obstacles, "); at != std::string::npos;
       at = err.find(" obstacles, ", at + 1))
    ++n;
  return n;
}

struct TrialRowSeen {
  std::string condition, device;
  bool completed = false;
  double lap_time_s = 0.0;
};

std::vector<TrialRowSeen> TrialRows(const std::filesystem::path& db) {
  sqlite3* raw = nullptr;
  REQUIRE(sqlite3_open_v2(db.c_str(), &raw, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK);
  sqlite3_stmt* select = nullptr;
  REQUIRE(sqlite3_prepare_v2(raw,
                             "SELECT condition, device, completed, lap_time_s FROM study_trials "
                             "WHERE participant = 'A' ORDER BY position",
                             -1, &select, nullptr) == SQLITE_OK);
  std::vector<TrialRowSeen> rows;
  while (sqlite3_step(select) == SQLITE_ROW) {
    rows.push_back({reinterpret_cast<const char*>(sqlite3_column_text(select, 0)),
                    reinterpret_cast<const char*>(sqlite3_column_text(select, 1)),
                    sqlite3_column_int(select, 2) != 0, sqlite3_column_double(select, 3)});
  }
  sqlite3_finalize(select);
  sqlite3_close(raw);
  return rows;
}

}  // namespace

TEST_CASE(
    "a people study through its console in headless Chromium: participant A's four conditions "
    "with the mouse, each lap stored, none at the cap",
    "[people]") {
  const test::XServer x;
  const auto source = std::filesystem::current_path();
  const auto dir = test::ScratchDir("e2e-people-study");
  const auto mouse = source / "config/devices/mouse.yaml";
  std::string conditions;
  for (const auto& [name, interface] : kConditions) {
    conditions +=
        "  - {name: " + name + ", interface: " + interface + ", device: " + mouse.string() + "}\n";
  }
  // grand-prix.yaml on the short track with a short cap; its participants
  // are added in the console (A is the first row of the balanced square).
  const auto file = test::WriteFile(
      dir / "people.yaml", test::StudyFileHead("people-e2e") + "operators: person\nconditions:\n" +
                               conditions +
                               "design: {order: balanced-latin-square}\n"
                               "practice: false\n"
                               "trial_cap_s: " +
                               std::to_string(kCap_s) + "\nquestionnaires: [thesis]\n");
  const auto db = dir / "people.db";
  const int domain = test::UniqueDomain(371);
  const int port = test::FreeLoopbackPort();
  Child study({Bin("haptel"), "study", "run", file.string(), "--database", db.string(), "--domain",
               std::to_string(domain), "--port", std::to_string(port), "--json"});
  REQUIRE(test::WaitForErr(study, "[study] console:", 60.0));
  Child experimenter({"/usr/bin/python3", (source / "tests/e2e/study_experimenter.py").string(),
                      "http://127.0.0.1:" + std::to_string(port) + "/", "A",
                      std::to_string(kConditions.size()), "thesis"});

  // The pilot sits at the mouse for each trial the experimenter starts, and
  // lets go when the study says the trial ended.
  const std::string vehicle = LoadVehicle(LoadRun("config/haptel.yaml").vehicle).name;
  std::unique_ptr<testing::PointerPilot> pilot;
  std::vector<std::string> pilot_errors;
  size_t started = 0;
  auto let_go = [&] {
    if (!pilot) return;
    pilot->Stop();
    if (!pilot->counts().error.empty()) pilot_errors.push_back(pilot->counts().error);
    pilot.reset();
  };
  // Bounds a hang (four laps and their forms on a loaded machine); asserts no timing.
  const bool done = test::WaitFor(
      [&] {
        study.Pump();
        experimenter.Pump();
        const std::vector<std::string> starts = LinesAfter(experimenter.out(), "started ");
        if (pilot && TrialsEnded(study.err()) >= started) let_go();
        if (starts.size() > started) {
          let_go();
          const std::string condition = starts[started].substr(0, starts[started].find(' '));
          ++started;
          testing::PilotSetup setup;
          setup.domain = domain;
          setup.vehicle_name = vehicle;
          setup.track = "config/tracks/test-short.yaml";
          setup.device = mouse;
          setup.interface = kConditions.at(condition);
          pilot = std::make_unique<testing::PointerPilot>(setup);
          pilot->Start();
        }
        return !experimenter.Alive() || !study.Alive();
      },
      600.0);
  let_go();
  experimenter.Pump();
  INFO("experimenter:\n"
       << experimenter.out() << experimenter.err() << "\nstudy:\n"
       << study.err());
  REQUIRE(done);
  CHECK(pilot_errors.empty());
  REQUIRE(experimenter.Wait(30.0) == 0);
  // Every device was named and there: the experimenter saw "mouse" for each.
  for (const std::string& line : LinesAfter(experimenter.out(), "started "))
    CHECK(line.substr(line.find(' ') + 1) == "mouse");
  REQUIRE(study.Wait(60.0) == 0);
  CHECK(test::JsonField(study.LastLine(), "finished") == "true");
  CHECK(test::JsonField(study.LastLine(), "trials_done") == "4");

  // The laps as stored: each condition once, with the mouse, finished under the cap.
  const std::vector<TrialRowSeen> rows = TrialRows(db);
  REQUIRE(rows.size() == kConditions.size());
  for (const TrialRowSeen& row : rows) {
    INFO(row.condition);
    CHECK(kConditions.count(row.condition) == 1);
    CHECK(row.device == "mouse");
    CHECK(row.completed);
    CHECK(row.lap_time_s < kCap_s);
  }
}
