#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "haptel/vehicles/drive.hpp"

using namespace haptel::vehicles;

TEST_CASE("commands quantise to the nearest of 8 levels each way") {
  CHECK(QuantiseCommand(0.0, 8) == 0);
  CHECK(QuantiseCommand(1.0, 8) == 8);
  CHECK(QuantiseCommand(-1.0, 8) == -8);
  CHECK(QuantiseCommand(0.5, 8) == 4);
  CHECK(QuantiseCommand(0.06, 8) == 0);   // below half a level
  CHECK(QuantiseCommand(0.07, 8) == 1);   // above half a level (0.0625)
  CHECK(QuantiseCommand(-0.3, 8) == -2);  // -2.4 -> -2
  CHECK(QuantiseCommand(0.81, 8) == 6);   // 6.48 -> 6
}

TEST_CASE("quantisation clamps out-of-range commands and stops on NaN") {
  CHECK(QuantiseCommand(3.0, 8) == 8);
  CHECK(QuantiseCommand(-7.0, 8) == -8);
  CHECK(QuantiseCommand(std::numeric_limits<double>::quiet_NaN(), 8) == 0);
  CHECK(QuantiseCommand(std::numeric_limits<double>::infinity(), 8) == 0);
}

TEST_CASE("every command maps to a level within range, monotonically") {
  int previous = -9;
  for (int i = -100; i <= 100; ++i) {
    const int level = QuantiseCommand(i / 100.0, 8);
    CHECK(level >= -8);
    CHECK(level <= 8);
    CHECK(level >= previous);
    previous = level;
  }
}

TEST_CASE("the watchdog is expired until the first command") {
  CommandWatchdog w(0.25);
  CHECK(w.Expired(0));
  CHECK(w.Expired(1'000'000'000));
}

TEST_CASE("the watchdog expires exactly after the timeout without commands") {
  constexpr int64_t kMs = 1'000'000;
  CommandWatchdog w(0.25);
  w.Feed(1000 * kMs);
  CHECK_FALSE(w.Check(1000 * kMs));
  CHECK_FALSE(w.Check(1250 * kMs));  // exactly at the timeout: still fresh
  CHECK(w.Check(1251 * kMs));
  CHECK(w.trips() == 1);
  CHECK(w.Check(1400 * kMs));
  CHECK(w.trips() == 1);  // one trip per silence, not per check
  w.Feed(1500 * kMs);
  CHECK_FALSE(w.Check(1500 * kMs));
  CHECK(w.Check(1800 * kMs));
  CHECK(w.trips() == 2);
}

TEST_CASE("the watchdog rejects a non-positive timeout") {
  CHECK_THROWS_AS(CommandWatchdog(0.0), std::invalid_argument);
  CHECK_THROWS_AS(CommandWatchdog(-1.0), std::invalid_argument);
}
