// The operator's side of the blimp's servo controller: a state carrying the
// Maestro's error bits is named in the progress line's part, and the run's
// errors in the summary and the JSON line (with the raw register).
#include <catch2/catch.hpp>
#include <cstdio>
#include <string>

#include "haptel/app/run_command.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/link/families.hpp"
#include "haptel/mediator/controller_errors.hpp"

using namespace haptel;
using namespace haptel::mediator;

namespace {

/// What app::PrintRunSummary writes, as a string.
std::string Summary(const SessionSetup& setup, const RecordedRun& run) {
  std::FILE* file = std::tmpfile();
  REQUIRE(file != nullptr);
  app::PrintRunSummary(file, setup, run);
  std::rewind(file);
  std::string text;
  char buffer[4096];
  for (size_t n; (n = std::fread(buffer, 1, sizeof buffer, file)) > 0;) text.append(buffer, n);
  std::fclose(file);
  return text;
}

}  // namespace

TEST_CASE(
    "a blimp state carrying the controller's error bits is named in the next progress line, once") {
  ControllerErrorWatch watch;
  msg::BlimpState state;
  CHECK(watch.TakeProgressText().empty());
  state.controller_errors(0x0008);  // CRC error
  watch.ObserveState(state);
  state.controller_errors(0x0000);  // the device cleared it on reading
  watch.ObserveState(state);
  state.controller_errors(0x0020);  // then a serial timeout
  watch.ObserveState(state);
  CHECK(watch.TakeProgressText() ==
        "  controller errors: serial timeout, CRC error (register 0x0028)");
  CHECK(watch.TakeProgressText().empty());  // said; nothing new since
  state.controller_errors(0x0100);
  watch.ObserveState(state);
  CHECK(watch.TakeProgressText() ==
        "  controller errors: script program counter error (register 0x0100)");
  CHECK(watch.seen() == 0x0128);
}

TEST_CASE("the run's summary and JSON line name the Maestro's errors and keep the register") {
  SessionSetup setup;
  setup.vehicle = LoadVehicle("config/vehicles/sim-blimp-maestro.yaml");
  RecordedRun run;
  run.result.outcome = Outcome::kVehicleLost;
  run.result.message =
      "vehicle 'blimp1' stopped itself: servo controller on /dev/pts/3 cannot be trusted: ...";
  run.result.record.outcome = "vehicle lost";

  SECTION("errors") {
    run.result.controller_errors = 0x0028;
    CHECK_THAT(Summary(setup, run),
               Catch::Contains(
                   "\n  servo controller errors: serial timeout, CRC error (register 0x0028)\n"));
    const std::string json = app::RunJson(setup, run);
    CHECK_THAT(
        json,
        Catch::Contains(
            R"("controller_errors":40,"controller_error_names":["serial timeout","CRC error"])"));
  }
  SECTION("none") {
    CHECK_THAT(Summary(setup, run), Catch::Contains("\n  servo controller errors: none\n"));
    CHECK_THAT(app::RunJson(setup, run),
               Catch::Contains(R"("controller_errors":0,"controller_error_names":[])"));
  }
  SECTION("a vehicle without a Maestro has no such line") {
    setup.vehicle = LoadVehicle("config/vehicles/sim-robot.yaml");
    CHECK_THAT(Summary(setup, run), !Catch::Contains("servo controller errors"));
    CHECK_THAT(app::RunJson(setup, run),
               Catch::Contains(R"("controller_errors":0,"controller_error_names":[])"));
  }
}
