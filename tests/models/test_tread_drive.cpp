// The tread drive's model: quantisation to the brick's speed levels.
#include <catch2/catch.hpp>
#include <limits>

#include "haptel/models/tread_drive.hpp"

using namespace haptel::models;

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
