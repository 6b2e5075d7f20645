#pragma once
// An X server of the test's own (Xvfb) for the end-to-end tests with a
// window, and xdotool to type and move the mouse in it.
#include <catch2/catch.hpp>
#include <chrono>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "child.hpp"
#include "haptel/testing/xvfb.hpp"
#include "test_env.hpp"

namespace haptel::test {

/// An X server of the test's own (testing/xvfb.hpp); DISPLAY points at it
/// while it lives.
class XServer {
 public:
  XServer() { REQUIRE_NOTHROW(server_ = std::make_unique<testing::Xvfb>()); }
  const std::string& display() const { return server_->display(); }

 private:
  std::unique_ptr<testing::Xvfb> server_;
};

/// Runs xdotool with `args` on the current DISPLAY; returns its exit code.
inline int XDoTool(std::vector<std::string> args) {
  args.insert(args.begin(), "/usr/bin/xdotool");
  Child c(args);
  return c.Wait(30.0);
}

/// Presses Escape in Haptel's window and waits for `run` to end as a person
/// ending it does: outcome "aborted", exit 1. Returns its JSON line.
inline std::string EndWithEscape(Child& run) {
  // xdotool's windowfocus fails now and then on a loaded host (exit 1, the
  // window's focus changing under it): tried again while the run still runs.
  int pressed = -1;
  for (int attempt = 0; attempt < 3 && pressed != 0 && run.Alive(); ++attempt) {
    if (attempt > 0) std::this_thread::sleep_for(std::chrono::seconds(1));
    pressed =
        XDoTool({"search", "--sync", "--name", "Haptel", "windowfocus", "--sync", "key", "Escape"});
  }
  const int code = run.Wait(60.0);
  // What says the key reached the window is the run's end, aborted by it:
  // xdotool itself may not come back while the window it typed into closes
  // (a suite at load: the run aborted, "the view was closed", and xdotool
  // still waiting at 30 s).
  INFO("xdotool: " << pressed << "\n" << run.out() << run.err());
  CHECK(code == 1);
  const std::string json = run.LastLine();
  CHECK(JsonFieldOf(json, "outcome") == "aborted");
  return json;
}

}  // namespace haptel::test
