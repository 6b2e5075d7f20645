// End to end: SIGTERM and SIGHUP end `haptel run` promptly and the run is
// recorded as interrupted, even while the physics world is inside a step that
// alone takes far longer than the test waits (the first step of a pile of
// overlapping spheres creates a contact for every pair: over a minute here).
// Behaviour only: the waits are generous bounds so a fault fails the test
// instead of hanging it; the time to exit is measured by hand, not here.
#include <signal.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <utility>

#include "child.hpp"
#include "haptel/record/recorder.hpp"
#include "test_env.hpp"

using namespace haptel;
using haptel::test::Child;

namespace {

std::string Bin(const std::string& name) { return (test::BinDir() / name).string(); }

/// A YAML scene: a floor and `count` dynamic spheres of 5 cm radius, their
/// centres scattered in a 20 cm cube so that most pairs overlap.
std::filesystem::path PileOfSpheres(const std::filesystem::path& dir, int count) {
  const auto file = dir / "pile.yaml";
  std::ofstream out(file);
  out << "objects:\n"
         "  - name: floor\n    type: static\n    shapes:\n"
         "      - {type: plane, normal: [0, 0, 1], offset: 0}\n";
  std::mt19937 random(1);
  std::uniform_real_distribution<double> within(-0.1, 0.1);
  for (int i = 0; i < count; ++i) {
    out << "  - name: ball" << i << "\n    type: dynamic\n    position: [" << within(random) << ", "
        << within(random) << ", " << 0.5 + within(random)
        << "]\n    mass: 0.1\n    shapes:\n      - {type: sphere, radius: 0.05}\n";
  }
  return file;
}

}  // namespace

TEST_CASE("a signal ends a run whose physics is stuck in a long step, and the run is recorded") {
  const auto dir = test::ScratchDir("e2e-shutdown");
  const auto scene = PileOfSpheres(dir, 3000);
  const auto [name, number] = GENERATE(std::pair<const char*, int>{"SIGTERM", SIGTERM},
                                       std::pair<const char*, int>{"SIGHUP", SIGHUP});
  INFO("signal " << name);
  const auto db = dir / (std::string(name) + ".db");
  Child run({Bin("haptel"), "run", "--operator", "auto", "--view", "none", "--track",
             "config/tracks/test-short.yaml", "--scene", scene.string(), "--domain",
             std::to_string(test::UniqueDomain(31)), "--database", db.string(), "--vehicle-timeout",
             "5"});
  // The vehicle is spawned once the world has started stepping; a moment
  // later the session loop runs, and the first step is far from done.
  const bool started = test::WaitFor(
      [&] {
        return run.Wait(0.0) != Child::kRunning ||
               run.err().find("started, pid") != std::string::npos;
      },
      120.0);
  INFO("stderr:\n" << run.err());
  REQUIRE(started);
  REQUIRE_FALSE(run.exited());
  std::this_thread::sleep_for(std::chrono::seconds(2));
  REQUIRE(run.Wait(0.0) == Child::kRunning);
  kill(run.pid(), number);
  const int code = run.Wait(20.0);
  REQUIRE(code != Child::kRunning);
  CHECK(code == 1);  // interrupted: not completed, nothing lost

  record::Recorder recorder(db);
  const auto runs = recorder.LoadAll();
  REQUIRE(runs.size() == 1);
  CHECK(runs[0].outcome == "interrupted");
  CHECK_FALSE(runs[0].completed);
}
