#include "haptel/haptics/gravity.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "haptel/config/error.hpp"
#include "haptel/haptics/sim_device.hpp"

namespace haptel::haptics {

// ---------------------------------------------------------------- online ---

GravityGrid::GravityGrid(const GravityGridData& data, double fade_distance_m)
    : data_(Validated(data)), fade_distance_(fade_distance_m) {
  if (!std::isfinite(fade_distance_m) || fade_distance_m <= 0.0) {
    throw std::invalid_argument("gravity grid: fade_distance must be a finite distance > 0 m");
  }
  for (int a = 0; a < 3; ++a) {
    cells_per_metre_[a] = static_cast<double>(data_.counts[a] - 1) / (data_.max[a] - data_.min[a]);
  }
}

GravityGrid GravityGrid::Load(const std::filesystem::path& file, double fade_distance_m) {
  return GravityGrid(LoadGravityGrid(file), fade_distance_m);
}

Vec3d GravityGrid::Vertex(int i, int j, int k) const {
  const std::array<int, 3> n{i, j, k};
  Vec3d v{};
  for (int a = 0; a < 3; ++a) v[a] = data_.min[a] + static_cast<double>(n[a]) / cells_per_metre_[a];
  return v;
}

double GravityGrid::Evaluate(const Vec3d& position_m) const noexcept {
  double outside2 = 0.0;  // squared distance to the box
  std::array<std::size_t, 3> cell{};
  std::array<double, 3> frac{};
  for (int a = 0; a < 3; ++a) {
    double q = position_m[a];
    if (!std::isfinite(q)) return 0.0;
    if (q < data_.min[a]) {
      outside2 += (data_.min[a] - q) * (data_.min[a] - q);
      q = data_.min[a];
    } else if (q > data_.max[a]) {
      outside2 += (q - data_.max[a]) * (q - data_.max[a]);
      q = data_.max[a];
    }
    const double t = (q - data_.min[a]) * cells_per_metre_[a];  // in [0, counts − 1]
    const int last_cell = data_.counts[a] - 2;
    const int c = std::min(static_cast<int>(t), last_cell);
    cell[a] = static_cast<std::size_t>(c);
    frac[a] = std::clamp(t - c, 0.0, 1.0);
  }
  if (outside2 >= fade_distance_ * fade_distance_) return 0.0;

  const std::size_t nx = static_cast<std::size_t>(data_.counts[0]);
  const std::size_t nxy = nx * static_cast<std::size_t>(data_.counts[1]);
  const double* f = data_.force_z.data() + cell[0] + nx * cell[1] + nxy * cell[2];
  const double fx = frac[0], fy = frac[1], fz = frac[2];
  // Along x on the four edges, then y, then z.
  const double c00 = f[0] + fx * (f[1] - f[0]);
  const double c10 = f[nx] + fx * (f[nx + 1] - f[nx]);
  const double c01 = f[nxy] + fx * (f[nxy + 1] - f[nxy]);
  const double c11 = f[nxy + nx] + fx * (f[nxy + nx + 1] - f[nxy + nx]);
  const double c0 = c00 + fy * (c10 - c00);
  const double c1 = c01 + fy * (c11 - c01);
  const double value = c0 + fz * (c1 - c0);
  if (outside2 == 0.0) return value;
  const double s = std::sqrt(outside2) / fade_distance_;  // in (0, 1)
  return value * (1.0 - s * s * (3.0 - 2.0 * s));         // 1 − smoothstep: C¹, monotone
}

}  // namespace haptel::haptics
