#include "haptel/core/log.hpp"

#include <atomic>
#include <cstdio>
#include <mutex>
#include <string>

namespace haptel::log {
namespace {
std::atomic<int> g_level{static_cast<int>(Level::kInfo)};
std::mutex g_mutex;
std::string g_program = "haptel";
}  // namespace

void SetLevel(Level level) { g_level.store(static_cast<int>(level)); }

void SetProgram(std::string_view name) {
  std::lock_guard lock(g_mutex);
  g_program = std::string(name);
}

void Write(Level level, std::string_view message) {
  if (static_cast<int>(level) < g_level.load()) return;
  static constexpr const char* kNames[] = {"debug", "info", "warning", "error"};
  std::lock_guard lock(g_mutex);
  std::fprintf(stderr, "%s: %s: %.*s\n", g_program.c_str(), kNames[static_cast<int>(level)],
               static_cast<int>(message.size()), message.data());
}

}  // namespace haptel::log
