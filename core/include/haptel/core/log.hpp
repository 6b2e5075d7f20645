#pragma once
/// @file Minimal leveled logging to stderr, for set-up and slow threads only.
///
/// Never call from a servo loop: loops count events and a slower thread reports.
#include <string_view>

namespace haptel::log {

enum class Level { kDebug = 0, kInfo = 1, kWarn = 2, kError = 3 };

void SetLevel(Level level);
/// Prefix every line with this program name (e.g. "haptel-vehicle").
void SetProgram(std::string_view name);
void Write(Level level, std::string_view message);

inline void Info(std::string_view m) { Write(Level::kInfo, m); }
inline void Warn(std::string_view m) { Write(Level::kWarn, m); }
inline void Error(std::string_view m) { Write(Level::kError, m); }
inline void Debug(std::string_view m) { Write(Level::kDebug, m); }

}  // namespace haptel::log
