#pragma once
/// @file One hand's wrist positions in a device trace (`haptel run --trace`),
/// as a test or a benchmark reads where the device put it.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <utility>
#include <vector>

#include "haptel/haptics/trace.hpp"

namespace haptel::testing {

/// (t_ns, position) of one side's wrist records, in time order.
using WristTrack = std::vector<std::pair<int64_t, haptics::Vec3d>>;

inline WristTrack WristsOf(const std::vector<haptics::TraceRecord>& trace, haptics::Side side) {
  WristTrack out;
  for (const auto& r : trace) {
    if (r.kind != haptics::TraceRecord::kWrist || r.side != haptics::Index(side)) continue;
    out.push_back({r.t_ns, {r.values[0], r.values[1], r.values[2]}});
  }
  return out;
}

/// The position at `t_ns` (the last record at or before it; the first
/// before any); NaN for an empty track.
inline haptics::Vec3d PositionAt(const WristTrack& track, int64_t t_ns) {
  if (track.empty()) return {std::nan(""), std::nan(""), std::nan("")};
  const auto it = std::upper_bound(track.begin(), track.end(), t_ns,
                                   [](int64_t t, const auto& e) { return t < e.first; });
  return it == track.begin() ? track.front().second : std::prev(it)->second;
}

}  // namespace haptel::testing
