#pragma once
/// @file What the servo loop tells a session file (record/session_recorder.hpp)
/// about each tick of each arm: a flat value pushed from the loop itself, so
/// the tap must be wait-free and allocate nothing (a ring per side: the
/// loop's threads are one producer each).
#include <array>
#include <cstdint>

#include "haptel/haptics/types.hpp"

namespace haptel::haptics {

/// One tick of one arm, in SI units (record/idl/session.idl's ServoTick).
struct ServoSample {
  int64_t t_ns = 0;  ///< the tick's time (CLOCK_MONOTONIC)
  uint64_t cycle = 0;
  uint8_t side = 0;  ///< Index(Side)
  bool coupling = false;
  double period_s = 0.0;
  Vec3d tracked_position{};                               ///< m
  std::array<double, 4> tracked_orientation{1, 0, 0, 0};  ///< w, x, y, z
  Vec3d proxy_position{};                                 ///< m, the coupling's target
  Vec3d field_force{};                                    ///< N, the interface's field
  Vec3d wrist_force{};                                    ///< N, sent
  std::array<double, kFingers> finger_forces{};           ///< N, sent
  double passivity_energy_j = 0.0;                        ///< the observer's energy now
  double passivity_dissipated_j = 0.0;                    ///< damping dissipated so far
};

class ServoTap {
 public:
  virtual ~ServoTap() = default;
  /// From the arm's servo thread: wait-free, no allocation, never blocks.
  virtual void Push(const ServoSample& sample) noexcept = 0;
};

}  // namespace haptel::haptics
