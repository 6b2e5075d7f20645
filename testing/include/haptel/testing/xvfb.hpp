#pragma once
/// @file An X server of one's own (Xvfb) for what opens a window without a
/// desktop: the window tests (tests/e2e/xserver.hpp) and `haptel bench
/// hands`. DISPLAY points at it while it lives.
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <thread>

#include "haptel/core/child_process.hpp"

namespace haptel::testing {

class Xvfb {
 public:
  /// Starts /usr/bin/Xvfb with a 1280×800 24-bit screen and waits (at most
  /// `timeout_s`) for it to say its display; std::runtime_error when it
  /// is not installed or does not start.
  explicit Xvfb(double timeout_s = 30.0) : server_(Start()) {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (server_.out().find('\n') == std::string::npos) {
      if (std::chrono::steady_clock::now() > deadline || !server_.Alive()) {
        throw std::runtime_error("Xvfb did not start: " + server_.err());
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      server_.Pump();
    }
    // Appended, not `":" + substr(...)`: GCC 12 -O2 flags that form with a
    // false -Werror=restrict.
    display_ = ":";
    display_.append(server_.out(), 0, server_.out().find('\n'));
    setenv("DISPLAY", display_.c_str(), 1);
  }
  ~Xvfb() { unsetenv("DISPLAY"); }
  Xvfb(const Xvfb&) = delete;
  Xvfb& operator=(const Xvfb&) = delete;
  const std::string& display() const { return display_; }

 private:
  static ChildProcess Start() {
    const std::string program = "/usr/bin/Xvfb";
    if (!std::filesystem::exists(program)) {
      throw std::runtime_error(program + " is not installed (Debian: apt-get install xvfb)");
    }
    return ChildProcess(program,
                        {"-displayfd", "1", "-screen", "0", "1280x800x24", "-nolisten", "tcp"},
                        ChildProcess::Options{true});
  }
  ChildProcess server_;
  std::string display_;
};

}  // namespace haptel::testing
