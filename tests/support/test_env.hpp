#pragma once
/// @file Where tests find binaries and scratch space, and a DDS domain of
/// their own so tests running in parallel never hear each other.
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>

namespace haptel::test {

/// build/bin, from HAPTEL_BIN_DIR (set by ctest).
inline std::filesystem::path BinDir() {
  const char* dir = std::getenv("HAPTEL_BIN_DIR");
  return dir != nullptr ? std::filesystem::path(dir) : std::filesystem::path("build/bin");
}

/// A fresh folder for this process's scratch files.
inline std::filesystem::path ScratchDir(const std::string& name) {
  const char* base = std::getenv("HAPTEL_TEST_TMP");
  const std::filesystem::path root = base != nullptr ? base : std::filesystem::temp_directory_path();
  const auto dir = root / (name + "-" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

/// A DDS domain id unlikely to be shared with another test process (1..232).
inline int UniqueDomain(int salt = 0) { return 1 + static_cast<int>((getpid() * 7 + salt) % 230); }

/// Polls `condition` every 10 ms until it holds or `timeout_s` passes.
/// Generous timeouts only: this bounds a wait, it asserts no timing.
template <typename Condition>
bool WaitFor(Condition condition, double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < deadline) {
    if (condition()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return condition();
}

}  // namespace haptel::test
