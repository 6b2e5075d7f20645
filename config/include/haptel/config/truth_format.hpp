#pragma once
/// @file The truth record's file: what a simulated vehicle writes (its
/// drawn reality, then its true motion at its control rate) and what the
/// scoring reads after the run (record/truth_record.hpp). Plain text:
///
///     # haptel truth record 1
///     # reality lab
///     # seed 7
///     # left_gain 1.0312            (every DrawnReality::ForEach number)
///     # floor_patch x y radius traction   (one line per patch)
///     # wall ax ay bx by   (where each wall truly stands, with map error)
///     # post x y radius    (where each round post truly stands, likewise)
///     operator_ns,x,y,z,heading,speed,yaw_rate
///     123456789012,0.1,0.2,0,1.57,0.25,0.01
///
/// `operator_ns` is the operator host's CLOCK_MONOTONIC (MonotonicNs(): the
/// clock the operator's receive stamps use; a simulated-time run's
/// simulated clock), not the vehicle's own offset and drifting clock.
#include <cstddef>
#include <cstdint>
#include <string>

#include "haptel/config/reality.hpp"

namespace haptel {

/// One row: where the vehicle truly was at `operator_ns`. The robot's z is 0.
struct TruthRow {
  int64_t operator_ns = 0;
  double x = 0.0, y = 0.0, z = 0.0;  ///< m, track / course frame
  double heading = 0.0;              ///< rad (the blimp's yaw)
  double speed = 0.0;                ///< m/s, forward (the blimp's horizontal ground speed)
  double yaw_rate = 0.0;             ///< rad/s
};

/// The header's lines, the column line last, each ending in '\n'.
std::string TruthHeaderText(const DrawnReality& reality);
/// Writes `row` as one line ending in '\n' into `out` (no allocation);
/// returns its length, or 0 when it does not fit.
size_t FormatTruthRow(const TruthRow& row, char* out, size_t size);

/// Reads a header line into `reality` (false: the line is not a header
/// line); throws std::invalid_argument saying what was expected.
bool ParseTruthHeaderLine(const std::string& line, DrawnReality& reality);
/// Whether `line` is the column line.
bool IsTruthColumnLine(const std::string& line);
/// Reads a row; throws std::invalid_argument saying what was expected.
TruthRow ParseTruthRow(const std::string& line);

}  // namespace haptel
