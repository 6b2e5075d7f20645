#pragma once
// Strict reading of one YAML mapping: every key read is remembered, and
// Finish() rejects the keys nobody asked for. Errors name file:line:column,
// the full key path and what was expected.
#include <yaml-cpp/yaml.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "haptel/config/error.hpp"
#include "haptel/core/geometry2d.hpp"

namespace haptel::config_detail {

/// The largest YAML file a loader parses (tracks, scenes, configurations):
/// anything bigger is not a hand-written file, and parsing it would take
/// seconds and gigabytes before any check could speak.
constexpr std::uintmax_t kMaxYamlFileBytes = std::uintmax_t{4} << 20;

class YamlMap {
 public:
  /// Parses a file whose top level must be a mapping. A file over `max_bytes`
  /// is refused with its size before it is read.
  static YamlMap Load(const std::filesystem::path& file,
                      std::uintmax_t max_bytes = kMaxYamlFileBytes);

  YamlMap(YAML::Node node, std::string file, std::string prefix);

  bool Has(const std::string& key) const;
  /// Whether the key holds a plain value / a mapping (false when absent).
  bool IsScalar(const std::string& key) const;
  bool IsMap(const std::string& key) const;

  double Number(const std::string& key, double fallback, double min, double max);
  double RequireNumber(const std::string& key, double min, double max);
  int Integer(const std::string& key, int fallback, int min, int max);
  bool Bool(const std::string& key, bool fallback);
  std::string String(const std::string& key, const std::string& fallback);
  std::string RequireString(const std::string& key);
  std::array<double, 3> Vec3(const std::string& key, const std::array<double, 3>& fallback,
                             double min, double max);
  /// A required list of exactly `count` numbers in [min, max] (and != 0 when
  /// `nonzero`); errors name the offending element, e.g. "gains[3]".
  std::vector<double> Numbers(const std::string& key, size_t count, double min, double max,
                              bool nonzero = false);
  Vec2 Point(const std::string& key);
  std::vector<Vec2> Points(const std::string& key, size_t min_count);
  /// A list of [x, y, z] points, each coordinate within ±max_abs.
  std::vector<std::array<double, 3>> Points3(const std::string& key, size_t min_count, size_t max_count,
                                             double max_abs);
  std::vector<std::string> Strings(const std::string& key, const std::vector<std::string>& fallback);
  /// A nested mapping; an absent key yields an empty mapping (all defaults).
  YamlMap Map(const std::string& key);
  /// The keys this mapping holds, in file order (for mappings whose keys are
  /// names the user chooses, e.g. profiles: {careful: ..., quick: ...}).
  std::vector<std::string> Keys() const;
  /// A list of mappings; an absent key yields an empty list.
  std::vector<YamlMap> MapList(const std::string& key);

  /// Throws for every key present in the file that was never read.
  void Finish() const;

  [[noreturn]] void Fail(const std::string& key, const std::string& expected) const;
  /// Like Fail, for element `index` of the list under `key` ("key[index]",
  /// at the element's line).
  [[noreturn]] void FailItem(const std::string& key, size_t index,
                             const std::string& expected) const;
  const std::string& file() const { return file_; }
  /// "file:line:col" of this mapping (just "file" for an absent section).
  std::string Location() const { return Where(node_); }
  /// "file:line:col" of element `index` of the list under `key` (the list's
  /// when it has no such element, this mapping's when there is no list).
  std::string ItemLocation(const std::string& key, size_t index) const;
  /// The full key path of key in this mapping, e.g. "gates[1].width".
  std::string Path(const std::string& key) const;

 private:
  YAML::Node Child(const std::string& key);
  std::string Where(const YAML::Node& node) const;
  std::string Got(const YAML::Node& node) const;
  double ToNumber(const YAML::Node& node, const std::string& key, const std::string& expected) const;

  YAML::Node node_;
  std::string file_;
  std::string prefix_;
  std::set<std::string> read_;
};

}  // namespace haptel::config_detail
