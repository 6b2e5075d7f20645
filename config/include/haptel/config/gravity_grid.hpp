#pragma once
/// @file The gravity-compensation grid file (`haptel calibrate --gravity`
/// writes it; DeviceConfig::gravity names it): the vertical force that holds
/// one arm still at each vertex of a regular 3-D grid over a box.
///
/// File format (YAML, strict):
///
///     device: sim                  # optional: the device it was sampled on
///     min: [-0.15, -0.25, -0.15]   # box corner, m, device frame
///     max: [0.25, 0.25, 0.20]      # opposite corner, m; min < max per axis
///     counts: [5, 5, 5]            # vertices per axis, each >= 2
///     force_z:                     # N, upward, nx*ny*nz values, x fastest:
///       - 1.93                     #   index = i + nx*(j + ny*k)
///       - ...
///
/// The vertex (i, j, k) sits at min + (i, j, k) ⊙ (max − min) / (counts − 1).
#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace haptel {

struct GravityGridData {
  std::array<double, 3> min{};  ///< box corner, m
  std::array<double, 3> max{};  ///< opposite corner, m
  std::array<int, 3> counts{};  ///< vertices per axis (≥ 2 each)
  std::vector<double> force_z;  ///< N upward, x fastest: i + nx*(j + ny*k)
  std::string device;           ///< device it was sampled on ("" = unknown)

  /// Throws ConfigFieldError unless counts are in [2, 1000] (10 000 000
  /// vertices at most), min < max within ±1000 m on every axis, and force_z
  /// holds one finite force per vertex. A default-constructed grid is empty,
  /// not valid.
  void ValidateOrThrow() const;
};

/// Largest number of vertices per axis a grid file may have.
constexpr int kGravityGridMaxCount = 1000;
/// Largest number of vertices in all a grid file may have.
constexpr long kGravityGridMaxVertices = 10'000'000;

/// Index into force_z of vertex (i, j, k).
inline std::size_t GravityVertexIndex(const std::array<int, 3>& counts, int i, int j, int k) {
  return static_cast<std::size_t>(i) +
         static_cast<std::size_t>(counts[0]) *
             (static_cast<std::size_t>(j) +
              static_cast<std::size_t>(counts[1]) * static_cast<std::size_t>(k));
}

/// Loads and validates (GravityGridData::ValidateOrThrow) a grid file. ConfigError names
/// file:line:column, the key and what was expected (unknown keys are errors).
GravityGridData LoadGravityGrid(const std::filesystem::path& file);

/// Writes a grid file (full double precision, so it loads back bit for bit),
/// creating parent folders. std::invalid_argument naming the file and what
/// GravityGridData::ValidateOrThrow refuses for an invalid grid,
/// std::runtime_error when the file cannot be written.
void SaveGravityGrid(const std::filesystem::path& file, const GravityGridData& grid);

}  // namespace haptel
