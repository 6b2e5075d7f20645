#pragma once
// The short-track lap that test_e2e_lap records whole (ctest's fixture
// e2e_lap), read again by the tests that need a recorded lap
// (test_e2e_replay): one lap for them all, not one each.
#include <filesystem>

#include "test_env.hpp"

namespace haptel::test {

/// The lap's folder: sessions/lap.mcap (the session file), live.mp4 (its
/// offscreen view), runs.db, truth.csv. Not per process, as ScratchDir is:
/// the fixture's readers run in processes of their own.
inline std::filesystem::path RecordedLapDir() {
  const char* base = std::getenv("HAPTEL_TEST_TMP");
  return (base != nullptr ? std::filesystem::path(base) : std::filesystem::temp_directory_path()) /
         "e2e-recorded-lap";
}

}  // namespace haptel::test
