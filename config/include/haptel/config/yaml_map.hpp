#pragma once
/// @file Strict reading of one YAML mapping: every key read is remembered,
/// and Finish() rejects the keys nobody asked for. Errors name
/// file:line:column, the full key path and what was expected. The config
/// loaders read through it (mostly by the archives, archives.hpp); a config
/// that lives beside its code elsewhere (an interface's, a questionnaire)
/// reads the same way.
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

/// Throws ConfigError naming `file` when it is a folder or not a regular
/// file (a FIFO, a device, a socket: opening one may block for ever), before
/// anything opens it; `expected` says what it should be ("a YAML file").
/// Nothing for a missing file: opening it says so.
void CheckRegularFile(const std::filesystem::path& file, const std::string& expected);

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

  /// A finite number, a whole number, a list of 3 finite numbers: only the
  /// type is checked; the ranges are the config struct's (ValidateOrThrow).
  double Number(const std::string& key, double fallback);
  double RequireNumber(const std::string& key);
  int Integer(const std::string& key, int fallback);
  std::array<double, 3> Vec3(const std::string& key, const std::array<double, 3>& fallback);
  /// The same, also checking a range (for values no config struct holds).
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
  /// A required list of exactly `count` finite numbers (only the type is
  /// checked); `noun` names them in errors: "a list of 22 non-zero numbers".
  std::vector<double> Numbers(const std::string& key, size_t count,
                              const std::string& noun = "numbers");
  /// A list of finite numbers of any length (the fallback when absent);
  /// errors name the offending element.
  std::vector<double> NumberList(const std::string& key, const std::vector<double>& fallback);
  Vec2 Point(const std::string& key);
  std::vector<Vec2> Points(const std::string& key, size_t min_count);
  /// A list of [x, y, z] points, each coordinate within ±max_abs.
  std::vector<std::array<double, 3>> Points3(const std::string& key, size_t min_count,
                                             size_t max_count, double max_abs);
  std::vector<std::string> Strings(const std::string& key,
                                   const std::vector<std::string>& fallback);
  /// A nested mapping; an absent key yields an empty mapping (all defaults).
  YamlMap Map(const std::string& key);
  /// The keys this mapping holds, in file order (for mappings whose keys are
  /// names the user chooses, e.g. profiles: {careful: ..., quick: ...}).
  std::vector<std::string> Keys() const;
  /// A list of mappings; an absent key yields an empty list.
  std::vector<YamlMap> MapList(const std::string& key);

  /// A key this mapping may hold, though it was not read (it is absent):
  /// Finish's error for an unknown key lists it among the expected ones.
  void Allow(const std::string& key) { read_.insert(key); }
  /// Throws for every key present in the file that was never read.
  void Finish() const;

  [[noreturn]] void Fail(const std::string& key, const std::string& expected) const;
  /// A config struct's ValidateOrThrow error (keys relative to this mapping)
  /// as a ConfigError: at the line of `error.key` when the file has it; else
  /// at the first of `error.related` the file has; else at the nearest
  /// enclosing mapping or list the file has, saying `if_absent` (the value
  /// refused is then a default, or was filled in from another key).
  [[noreturn]] void Fail(const ConfigFieldError& error,
                         const std::string& if_absent = "but it is missing") const;
  /// The node at a key path below this mapping ("hand.material.friction",
  /// "gates[1].width"); an undefined node when the file does not have it.
  /// `deepest`, when given, receives the deepest node along the path the
  /// file has (this mapping at least).
  YAML::Node Find(const std::string& path, YAML::Node* deepest = nullptr) const;
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
  /// Got, but a short list of plain values as written ("[0.0, 5.0, 0.0]").
  std::string FlowText(const YAML::Node& node) const;
  double ToNumber(const YAML::Node& node, const std::string& key,
                  const std::string& expected) const;
  double ReadNumber(const std::string& key, double fallback, const std::string& expected,
                    double min, double max);
  int ReadInteger(const std::string& key, int fallback, const std::string& expected, int min,
                  int max);
  std::array<double, 3> ReadVec3(const std::string& key, const std::array<double, 3>& fallback,
                                 const std::string& expected, double min, double max);

  YAML::Node node_;
  std::string file_;
  std::string prefix_;
  std::set<std::string> read_;
};

/// Runs `config.ValidateOrThrow()`; a ConfigFieldError becomes the
/// ConfigError at its key in `map`'s file (YamlMap::Fail).
template <typename Config>
void ValidateIn(const YamlMap& map, const Config& config) {
  try {
    config.ValidateOrThrow();
  } catch (const ConfigFieldError& e) {
    map.Fail(e);
  }
}

}  // namespace haptel::config_detail
