#pragma once
/// @file Gravity compensation ("anti-gravity"), online: a 3-D grid of
/// vertical forces that hold the arm still, evaluated in the servo loop.
/// (The grid is sampled offline by gravity/gravity_sampler.hpp.)
///
/// - GravityGrid: trilinear interpolation of the 8 vertices around the wrist;
///   outside the box the value at the nearest box point fades smoothly to
///   zero over `fade_distance` (no jump at the boundary). Evaluate() is O(1),
///   allocation-free, lock-free: servo-loop safe.
///
/// Forces are newtons along +z (up) in the device frame; positions metres in
/// the calibrated device frame. Because of Coulomb friction any force within
/// ±friction of the true weight holds the arm still, so a sampled force is
/// right to within the friction, and so is the compensation.
#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "haptel/config/calibration.hpp"
#include "haptel/config/gravity_grid.hpp"
#include "haptel/haptics/device.hpp"
#include "haptel/haptics/types.hpp"

namespace haptel::haptics {

// ---------------------------------------------------------------- online ---

class GravityGrid {
 public:
  static constexpr double kDefaultFadeDistance = 0.03;  ///< m

  /// Validates `data` (GravityGridData::ValidateOrThrow: ConfigFieldError, a
  /// std::invalid_argument) and copies it: the only allocation.
  /// fade_distance_m must be finite and > 0 (std::invalid_argument).
  explicit GravityGrid(const GravityGridData& data, double fade_distance_m = kDefaultFadeDistance);
  /// LoadGravityGrid + constructor (ConfigError for a bad file).
  static GravityGrid Load(const std::filesystem::path& file,
                          double fade_distance_m = kDefaultFadeDistance);

  /// Upward force, N, that holds the arm at `position_m`. Inside the box:
  /// trilinear interpolation (exact at vertices and for any trilinear field).
  /// Outside: the value at the nearest box point times
  /// 1 − smoothstep(distance / fade_distance); 0 beyond fade_distance and for
  /// a non-finite position.
  double Evaluate(const Vec3d& position_m) const noexcept;

  const GravityGridData& data() const { return data_; }
  double fade_distance() const { return fade_distance_; }
  /// Position of vertex (i, j, k), m.
  Vec3d Vertex(int i, int j, int k) const;

 private:
  GravityGridData data_;
  double fade_distance_;
  std::array<double, 3> cells_per_metre_{};  ///< (counts − 1) / (max − min)
};

}  // namespace haptel::haptics
