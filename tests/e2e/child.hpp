#pragma once
// The program under an end-to-end test: the product's own ChildProcess with
// its stdout and stderr captured (one way to start processes in Haptel).
#include <catch2/catch.hpp>
#include <memory>
#include <regex>
#include <string>
#include <vector>

#include "haptel/core/child_process.hpp"
#include "haptel/core/json.hpp"
#include "haptel/testing/loopback.hpp"
#include "test_env.hpp"

namespace haptel::test {

class Child : public ChildProcess {
 public:
  /// argv[0] is the program.
  explicit Child(std::vector<std::string> argv)
      : ChildProcess(argv.at(0), std::vector<std::string>(argv.begin() + 1, argv.end()),
                     Options{true}) {}
  static constexpr int kRunning = kStillRunning;
};

/// Pumps `child` until its stderr contains `text` (at most `timeout_s`;
/// bounds a wait, asserts no timing). False if it never did.
inline bool WaitForErr(Child& child, const std::string& text, double timeout_s) {
  return WaitFor(
      [&] {
        child.Pump();
        return child.err().find(text) != std::string::npos;
      },
      timeout_s);
}

/// True once a progress line of `err` shows a command round trip: the vehicle
/// has answered. The first progress line alone does not say so: on a loaded
/// machine it can come (rtt p50 0.00 ms) before the vehicle is discovered.
inline bool VehicleAnswered(const std::string& err) {
  static const std::regex answered(R"(rtt p50 (?!0\.00 )[0-9]+\.[0-9]+ ms)");
  return std::regex_search(err, answered);
}

/// Pumps `child` until VehicleAnswered (at most `timeout_s`).
inline bool WaitForVehicle(Child& child, double timeout_s) {
  return WaitFor(
      [&] {
        child.Pump();
        return VehicleAnswered(child.err());
      },
      timeout_s);
}

/// Starts every program at once, each argv[0] its program. Each start costs
/// about half a second of CPU loading shared libraries, so cases that only
/// check a one-line error start side by side instead of one after another.
inline std::vector<std::unique_ptr<Child>> StartAll(
    const std::vector<std::vector<std::string>>& argvs) {
  std::vector<std::unique_ptr<Child>> children;
  children.reserve(argvs.size());
  for (const auto& argv : argvs) children.push_back(std::make_unique<Child>(argv));
  return children;
}

/// What `child` printed, for an INFO: every failing check after it shows it.
inline std::string Output(const Child& child) {
  return "stdout:\n" + child.out() + "\nstderr:\n" + child.err();
}

/// Waits for `child` (at most `timeout_s`), requires that it exited 0 with a
/// JSON line last (a run's --json), and returns that line.
inline std::string FinishedJson(Child& child, double timeout_s) {
  const int code = child.Wait(timeout_s);
  INFO(Output(child));
  REQUIRE(code == 0);
  std::string json = child.LastLine();
  REQUIRE(json.rfind('{', 0) == 0);
  return json;
}

/// Value of a top-level key in a flat JSON object line (numbers, bools, strings).
inline std::string JsonField(const std::string& json, const std::string& key) {
  return JsonFieldOf(json, key);
}

using haptel::testing::FreeLoopbackPort;

}  // namespace haptel::test
