#include "haptel/config/gravity_grid.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "haptel/config/check.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

namespace {

constexpr double kCoordinateLimit = 1000.0;  // m: anything beyond is a typo
/// A grid is sampled data, not a hand-written file: room for the largest grid
/// a file may hold (kGravityGridMaxVertices forces of ~20 characters each).
constexpr std::uintmax_t kMaxGridFileBytes = std::uintmax_t{256} << 20;

std::string Where(const std::filesystem::path& file, const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  if (mark.is_null()) return file.string();
  return file.string() + ":" + std::to_string(mark.line + 1) + ":" +
         std::to_string(mark.column + 1);
}

std::string CountsText(const std::array<int, 3>& c) {
  return std::to_string(c[0]) + "*" + std::to_string(c[1]) + "*" + std::to_string(c[2]);
}

}  // namespace

void GravityGridData::ValidateOrThrow() const {
  long product = 1;
  for (int a = 0; a < 3; ++a) {
    if (counts[a] < 2 || counts[a] > kGravityGridMaxCount) {
      check::Fail("counts", "a list of 3 whole numbers in [2, " +
                                std::to_string(kGravityGridMaxCount) + "] (vertices per axis)");
    }
    product *= counts[a];
  }
  if (product > kGravityGridMaxVertices) {
    check::Fail("counts",
                "at most " + std::to_string(kGravityGridMaxVertices) + " vertices in all");
  }
  check::Vec3("min", min, -kCoordinateLimit, kCoordinateLimit);
  check::Vec3("max", max, -kCoordinateLimit, kCoordinateLimit);
  for (int a = 0; a < 3; ++a) {
    if (!(min[a] < max[a])) {
      check::Fail("max", "a list of 3 numbers, each greater than 'min' on its axis", {"min"});
    }
  }
  if (force_z.size() != static_cast<std::size_t>(product)) {
    throw ConfigFieldError(
        "force_z",
        std::to_string(product) + " forces in newtons (" + CountsText(counts) + ", x fastest)", {},
        std::to_string(force_z.size()));
  }
  for (std::size_t n = 0; n < force_z.size(); ++n) {
    if (!std::isfinite(force_z[n])) {
      check::Fail("force_z[" + std::to_string(n) + "]", "a finite number (N)");
    }
  }
}

GravityGridData LoadGravityGrid(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file, kMaxGridFileBytes);  // unreadable files, bad YAML
  // The same document again, for the line of each force_z element.
  const YAML::Node raw = YAML::LoadFile(file.string());
  GravityGridData g;
  g.device = root.String("device", "");

  const std::string corner = "a list of 3 numbers in metres";
  if (!root.Has("min")) root.Fail("min", corner);
  if (!root.Has("max")) root.Fail("max", corner);
  g.min = root.Vec3("min", {});
  g.max = root.Vec3("max", {});

  const std::string counts_expected = "a list of 3 whole numbers (vertices per axis)";
  if (!root.Has("counts")) root.Fail("counts", counts_expected);
  const std::array<double, 3> counts = root.Vec3("counts", {});
  double product = 1.0;  // for the wording below; ValidateOrThrow checks the counts
  for (int a = 0; a < 3; ++a) {
    if (counts[a] != std::floor(counts[a]) || std::abs(counts[a]) > 1e9) {
      root.Fail("counts", counts_expected);
    }
    g.counts[a] = static_cast<int>(counts[a]);
    product *= counts[a];
  }

  const YAML::Node list = raw["force_z"];
  if (!list.IsDefined() || !list.IsSequence()) {
    std::ostringstream forces;
    forces << "a list of " << product << " forces in newtons (" << CountsText(g.counts)
           << ", x fastest)";
    root.Fail("force_z", forces.str());
  }
  g.force_z.reserve(list.size());
  for (std::size_t n = 0; n < list.size(); ++n) {
    const YAML::Node item = list[n];
    double value = 0.0;
    if (!item.IsScalar() || !YAML::convert<double>::decode(item, value) || !std::isfinite(value)) {
      throw ConfigError(Where(file, item) + ": key 'force_z[" + std::to_string(n) +
                        "]': expected a finite number (N), got " +
                        (item.IsScalar() ? "'" + item.Scalar() + "'" : std::string("no number")));
    }
    g.force_z.push_back(value);
  }
  (void)root.Strings("force_z", {});  // read above; marks the key as read for Finish()
  root.Finish();
  config_detail::ValidateIn(root, g);
  return g;
}

void SaveGravityGrid(const std::filesystem::path& file, const GravityGridData& grid) {
  try {
    grid.ValidateOrThrow();
  } catch (const ConfigFieldError& e) {
    throw std::invalid_argument("gravity grid for " + file.string() + ": " + e.what());
  }
  YAML::Emitter out;
  out.SetDoublePrecision(std::numeric_limits<double>::max_digits10);
  out << YAML::Comment(
      "Gravity compensation grid: the upward force (N) that holds the arm still at each "
      "vertex. Vertex (i,j,k) = min + (i,j,k)*(max-min)/(counts-1); force_z is x fastest.");
  out << YAML::BeginMap;
  if (!grid.device.empty()) out << YAML::Key << "device" << YAML::Value << grid.device;
  auto vec = [&out](const char* key, const auto& values) {
    out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (const auto v : values) out << v;
    out << YAML::EndSeq;
  };
  vec("min", grid.min);
  vec("max", grid.max);
  vec("counts", grid.counts);
  out << YAML::Key << "force_z" << YAML::Value << YAML::BeginSeq;
  for (const double f : grid.force_z) out << f;
  out << YAML::EndSeq << YAML::EndMap;
  if (!out.good())
    throw std::runtime_error(file.string() + ": cannot encode the grid: " + out.GetLastError());

  if (file.has_parent_path()) std::filesystem::create_directories(file.parent_path());
  std::ofstream stream(file);
  stream << out.c_str() << "\n";
  stream.close();
  if (!stream) throw std::runtime_error(file.string() + ": cannot write the file");
}

}  // namespace haptel
