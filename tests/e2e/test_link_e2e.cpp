// End to end, whose vehicle it is: `haptel run --attach` driving a
// `haptel-vehicle` started by hand, a second operator refused while the
// first drives, and a second vehicle under the same name reported as a
// conflict, never mixed into a run.
#include <catch2/catch.hpp>
#include <signal.h>

#include <regex>
#include <string>
#include <vector>

#include "child.hpp"
#include "test_env.hpp"

using namespace haptel;
using haptel::test::Child;
using haptel::test::JsonField;

namespace {

std::string Bin(const std::string& name) { return (test::BinDir() / name).string(); }

/// A simulated robot started by hand on `domain`, up (its ready line seen).
class HandStartedVehicle {
 public:
  explicit HandStartedVehicle(int domain)
      : child_({Bin("haptel-vehicle"), "--track", "config/tracks/test-short.yaml", "--domain",
                std::to_string(domain)}) {
    REQUIRE(test::WaitFor([&] {
      child_.Pump();
      return child_.err().find(" up on domain") != std::string::npos;
    }, 30.0));
  }
  Child& child() { return child_; }

 private:
  Child child_;
};

/// `haptel run --attach` on the short track and `domain`, plus `extra`.
std::vector<std::string> AttachArgs(int domain, const std::filesystem::path& db) {
  return {Bin("haptel"), "run", "--attach", "--track", "config/tracks/test-short.yaml", "--json", "--domain",
          std::to_string(domain), "--database", db.string(), "--vehicle-timeout", "5"};
}

}  // namespace

TEST_CASE("haptel run --attach drives a vehicle started by hand, leaves it running, and a second run can attach") {
  const int domain = test::UniqueDomain(41);
  const auto dir = test::ScratchDir("e2e-attach");
  HandStartedVehicle vehicle(domain);
  for (int lap = 0; lap < 2; ++lap) {
    Child run(AttachArgs(domain, dir / "runs.db"));
    const int code = run.Wait(120.0);
    INFO("lap " << lap << "\n" << run.out() << run.err());
    REQUIRE(code == 0);
    const std::string json = run.LastLine();
    CHECK(JsonField(json, "outcome") == "completed");
    CHECK(JsonField(json, "gates_passed") == "2");
    CHECK(JsonField(json, "vehicle_pid") == "0");  // nothing spawned
    CHECK(run.err().find("attached to vehicle 'robot1' on domain " + std::to_string(domain)) != std::string::npos);
    // The vehicle is not the run's to end.
    CHECK(kill(vehicle.child().pid(), 0) == 0);
  }
  kill(vehicle.child().pid(), SIGTERM);
  CHECK(vehicle.child().Wait(30.0) == 0);
  INFO(vehicle.child().err());
  CHECK(vehicle.child().err().find("refused") == std::string::npos);  // nobody else's commands came
}

TEST_CASE("a second operator is refused, naming the one driving; the first completes its lap") {
  const int domain = test::UniqueDomain(42);
  const auto dir = test::ScratchDir("e2e-owner");
  HandStartedVehicle vehicle(domain);
  Child first(AttachArgs(domain, dir / "first.db"));
  REQUIRE(test::WaitFor([&] {
    first.Pump();
    return first.err().find("distance") != std::string::npos;  // a progress line: driving
  }, 60.0));
  Child second(AttachArgs(domain, dir / "second.db"));
  const int second_code = second.Wait(60.0);
  INFO(second.out() << second.err());
  CHECK(second_code == 2);
  const std::string refused = second.LastLine();
  CHECK(JsonField(refused, "outcome") == "refused");
  CHECK(JsonField(refused, "message").find("driven by another operator") != std::string::npos);
  CHECK(JsonField(refused, "message").find("pid " + std::to_string(first.pid())) != std::string::npos);

  const int first_code = first.Wait(120.0);
  INFO(first.out() << first.err());
  CHECK(first_code == 0);
  CHECK(JsonField(first.LastLine(), "outcome") == "completed");
  // The vehicle counted the second run's commands as refused.
  kill(vehicle.child().pid(), SIGTERM);
  CHECK(vehicle.child().Wait(30.0) == 0);
  static const std::regex refused_count(R"(([0-9]+) refused)");
  std::smatch m;
  REQUIRE(std::regex_search(vehicle.child().err(), m, refused_count));
  CHECK(std::stoi(m[1]) > 0);
}

TEST_CASE("a second vehicle under the same name is a conflict: exit 2, nothing driven as a lap") {
  const int domain = test::UniqueDomain(43);
  const auto dir = test::ScratchDir("e2e-conflict");
  HandStartedVehicle stray(domain);
  // haptel run spawns its own robot1 on the same domain.
  Child run({Bin("haptel"), "run", "--track", "config/tracks/test-short.yaml", "--json", "--domain",
             std::to_string(domain), "--database", (dir / "runs.db").string(), "--vehicle-timeout", "5"});
  const int code = run.Wait(60.0);
  INFO(run.out() << run.err());
  CHECK(code == 2);
  const std::string json = run.LastLine();
  CHECK(JsonField(json, "outcome") == "conflict");
  CHECK(JsonField(json, "completed") == "false");
  CHECK(JsonField(json, "message").find("2 vehicles answer as 'robot1' on domain " + std::to_string(domain)) !=
        std::string::npos);
  // Reported as soon as both answer: the run never got far into its lap.
  CHECK(std::stod(JsonField(json, "distance_m")) < 0.5);
}
