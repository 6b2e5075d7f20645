#include "haptel/config/yaml_map.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>

#include "haptel/config/check.hpp"
#include "haptel/config/paths.hpp"

namespace haptel::config_detail {
namespace {
using config_check::Range;
constexpr double kInf = std::numeric_limits<double>::infinity();

/// "4 MB", "0.5 MB", "64.1 MB" (MB = 2^20 bytes).
std::string Megabytes(std::uintmax_t bytes) {
  std::ostringstream out;
  out << std::setprecision(3) << static_cast<double>(bytes) / static_cast<double>(1 << 20) << " MB";
  return out.str();
}
}  // namespace

void CheckRegularFile(const std::filesystem::path& file, const std::string& expected) {
  if (const std::string what = NotRegularFile(file); !what.empty()) {
    throw ConfigError(file.string() + ": is " + what + "; expected " + expected);
  }
}

namespace {

/// yaml-cpp keeps a key given twice and a lookup finds the first: the second,
/// the one edited last, would be ignored without a word. Refused anywhere in
/// the file, at the second, naming the first's line.
void CheckNoDuplicateKeys(const YAML::Node& node, const std::string& file,
                          const std::string& path) {
  if (node.IsSequence()) {
    for (size_t i = 0; i < node.size(); ++i) {
      CheckNoDuplicateKeys(node[i], file, path + "[" + std::to_string(i) + "]");
    }
    return;
  }
  if (!node.IsMap()) return;
  std::map<std::string, YAML::Mark> seen;
  for (const auto& entry : node) {
    if (!entry.first.IsScalar()) continue;  // Finish names a key that is not plain
    const std::string& key = entry.first.Scalar();
    const std::string at = path.empty() ? key : path + "." + key;
    if (const auto first = seen.find(key); first != seen.end()) {
      const YAML::Mark m = entry.first.Mark();
      throw ConfigError(file + ":" + std::to_string(m.line + 1) + ":" +
                        std::to_string(m.column + 1) + ": key '" + at +
                        "': given twice (first at line " + std::to_string(first->second.line + 1) +
                        "); expected each key once");
    }
    seen.emplace(key, entry.first.Mark());
    CheckNoDuplicateKeys(entry.second, file, at);
  }
}

}  // namespace

YamlMap YamlMap::Load(const std::filesystem::path& file, std::uintmax_t max_bytes) {
  CheckRegularFile(file, "a YAML file");
  std::error_code ec;
  // Before parsing: yaml-cpp takes seconds and many times the file's size in
  // memory for a file of tens of megabytes, long before any check could speak.
  if (const std::uintmax_t size = std::filesystem::file_size(file, ec); !ec && size > max_bytes) {
    throw ConfigError(file.string() + ": the file is " + std::to_string(size) + " bytes (" +
                      Megabytes(size) + ")" + "; expected a YAML file of at most " +
                      Megabytes(max_bytes) + " (is it the right file?)");
  }
  YAML::Node root;
  try {
    root = YAML::LoadFile(file.string());
  } catch (const YAML::BadFile&) {
    throw ConfigError(file.string() + ": cannot open the file");
  } catch (const std::ios_base::failure& e) {
    throw ConfigError(file.string() + ": cannot read the file: " + e.what());
  } catch (const YAML::Exception& e) {
    if (e.mark.is_null()) throw ConfigError(file.string() + ": cannot read the file: " + e.msg);
    throw ConfigError(file.string() + ":" + std::to_string(e.mark.line + 1) + ":" +
                      std::to_string(e.mark.column + 1) + ": not valid YAML: " + e.msg);
  }
  if (!root.IsMap()) {
    throw ConfigError(file.string() + ": expected a mapping of keys at the top level");
  }
  CheckNoDuplicateKeys(root, file.string(), "");
  return YamlMap(root, file.string(), "");
}

YamlMap::YamlMap(YAML::Node node, std::string file, std::string prefix)
    : node_(std::move(node)), file_(std::move(file)), prefix_(std::move(prefix)) {}

std::string YamlMap::Path(const std::string& key) const {
  return prefix_.empty() ? key : prefix_ + "." + key;
}

std::string YamlMap::Where(const YAML::Node& node) const {
  const YAML::Mark mark = node.Mark();
  if (mark.is_null()) return file_;
  return file_ + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
}

std::string YamlMap::FlowText(const YAML::Node& node) const {
  // A short list of plain values as written: "[0.0, 5.0, 0.0]".
  if (!node.IsSequence() || node.size() > 8) return Got(node);
  std::string text = "[";
  for (size_t i = 0; i < node.size(); ++i) {
    if (!node[i].IsScalar()) return Got(node);
    text += (i == 0 ? "" : ", ") + node[i].Scalar();
  }
  return text + "]";
}

std::string YamlMap::Got(const YAML::Node& node) const {
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return "a list";
  if (node.IsMap()) return "a mapping";
  return "nothing";
}

void YamlMap::Fail(const std::string& key, const std::string& expected) const {
  YAML::Node child = node_.IsMap() ? node_[key] : YAML::Node();
  const bool present = child.IsDefined();
  throw ConfigError(Where(present ? child : node_) + ": key '" + Path(key) + "': expected " +
                    expected + (present ? ", got " + Got(child) : ", but it is missing"));
}

YAML::Node YamlMap::Find(const std::string& path, YAML::Node* deepest) const {
  // Each step is a key, or an index into the list reached so far:
  // "gates[1].width" is gates, [1], width. Nodes are copied and rebound
  // (reset), never assigned: operator= would write into the document.
  const auto step = [&path](const YAML::Node& node, size_t& pos) -> YAML::Node {
    if (path[pos] == '[') {
      const size_t close = path.find(']', pos);
      const std::string digits =
          close == std::string::npos ? "" : path.substr(pos + 1, close - pos - 1);
      pos = close == std::string::npos ? path.size() : close + 1;
      if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos) {
        return YAML::Node();
      }
      const size_t index = std::stoul(digits);
      if (!node.IsSequence() || index >= node.size()) return YAML::Node();
      return node[index];
    }
    if (path[pos] == '.') ++pos;
    const size_t end = std::min(path.find_first_of(".[", pos), path.size());
    const std::string key = path.substr(pos, end - pos);
    pos = end;
    if (!node.IsMap()) return YAML::Node();
    const YAML::Node child = node[key];
    return child.IsDefined() ? child : YAML::Node();
  };
  YAML::Node node;
  node.reset(node_);
  if (deepest != nullptr) deepest->reset(node_);
  size_t pos = 0;
  while (pos < path.size()) {
    const YAML::Node next = step(node, pos);
    if (!next.IsDefined() || next.IsNull()) return YAML::Node(YAML::NodeType::Undefined);
    node.reset(next);
    if (deepest != nullptr) deepest->reset(node);
  }
  return node;
}

void YamlMap::Fail(const ConfigFieldError& error, const std::string& if_absent) const {
  const auto fail_at = [&](const YAML::Node& node, const std::string& key, const std::string& got) {
    throw ConfigError(Where(node) + ": key '" + Path(key) + "': expected " + error.expected +
                      ", got " + (got.empty() ? Got(node) : got));
  };
  if (const YAML::Node node = Find(error.key); node.IsDefined()) {
    fail_at(node, error.key, error.got.empty() ? FlowText(node) : error.got);
  }
  for (const std::string& related : error.related) {
    if (const YAML::Node node = Find(related); node.IsDefined()) fail_at(node, related, "");
  }
  YAML::Node deepest;
  Find(error.key, &deepest);
  throw ConfigError(Where(deepest) + ": key '" + Path(error.key) + "': expected " + error.expected +
                    ", " + if_absent);
}

namespace {
/// Whether the list under `key` has element `index`.
bool HasItem(const YAML::Node& map, const std::string& key, size_t index) {
  const YAML::Node list = map.IsMap() ? map[key] : YAML::Node();
  return list.IsSequence() && index < list.size();
}
/// Element `index` of the list under `key`; when there is none, the list
/// itself (e.g. an empty one), or `map` when there is no list either. (A
/// default YAML::Node counts as defined and has no mark: never return one.)
YAML::Node ItemOrNearest(const YAML::Node& map, const std::string& key, size_t index) {
  if (!map.IsMap()) return map;
  const YAML::Node list = map[key];
  if (HasItem(map, key, index)) return list[index];
  return list.IsDefined() && !list.IsNull() ? list : map;
}
}  // namespace

void YamlMap::FailItem(const std::string& key, size_t index, const std::string& expected) const {
  const bool present = HasItem(node_, key, index);
  const YAML::Node item = ItemOrNearest(node_, key, index);
  throw ConfigError(Where(item) + ": key '" + Path(key) + "[" + std::to_string(index) +
                    "]': expected " + expected +
                    (present ? ", got " + Got(item) : ", but it is missing"));
}

std::string YamlMap::ItemLocation(const std::string& key, size_t index) const {
  return Where(ItemOrNearest(node_, key, index));
}

bool YamlMap::Has(const std::string& key) const { return node_.IsMap() && node_[key].IsDefined(); }

bool YamlMap::IsScalar(const std::string& key) const { return Has(key) && node_[key].IsScalar(); }

bool YamlMap::IsMap(const std::string& key) const { return Has(key) && node_[key].IsMap(); }

YAML::Node YamlMap::Child(const std::string& key) {
  read_.insert(key);
  return node_.IsMap() ? node_[key] : YAML::Node();
}

double YamlMap::ToNumber(const YAML::Node& node, const std::string& key,
                         const std::string& expected) const {
  double value = 0.0;
  if (!node.IsScalar() || !YAML::convert<double>::decode(node, value) || !std::isfinite(value)) {
    Fail(key, expected);
  }
  return value;
}

double YamlMap::ReadNumber(const std::string& key, double fallback, const std::string& expected,
                           double min, double max) {
  const YAML::Node child = Child(key);
  if (!child.IsDefined() || child.IsNull()) return fallback;
  const double value = ToNumber(child, key, expected);
  if (value < min || value > max) Fail(key, expected);
  return value;
}

double YamlMap::Number(const std::string& key, double fallback) {
  return ReadNumber(key, fallback, "a number", -kInf, kInf);
}

double YamlMap::Number(const std::string& key, double fallback, double min, double max) {
  return ReadNumber(key, fallback, "a number in " + Range(min, max), min, max);
}

double YamlMap::RequireNumber(const std::string& key) {
  if (!Has(key)) Fail(key, "a number");
  return Number(key, 0.0);
}

double YamlMap::RequireNumber(const std::string& key, double min, double max) {
  if (!Has(key)) Fail(key, "a number in " + Range(min, max));
  return Number(key, 0.0, min, max);
}

int YamlMap::ReadInteger(const std::string& key, int fallback, const std::string& expected, int min,
                         int max) {
  const YAML::Node child = Child(key);
  if (!child.IsDefined() || child.IsNull()) return fallback;
  int value = 0;
  if (!child.IsScalar() || !YAML::convert<int>::decode(child, value)) Fail(key, expected);
  if (value < min || value > max) Fail(key, expected);
  return value;
}

int YamlMap::Integer(const std::string& key, int fallback) {
  return ReadInteger(key, fallback, "a whole number", std::numeric_limits<int>::min(),
                     std::numeric_limits<int>::max());
}

int YamlMap::Integer(const std::string& key, int fallback, int min, int max) {
  return ReadInteger(key, fallback, "a whole number in " + Range(min, max), min, max);
}

bool YamlMap::Bool(const std::string& key, bool fallback) {
  const YAML::Node child = Child(key);
  if (!child.IsDefined() || child.IsNull()) return fallback;
  bool value = false;
  if (!child.IsScalar() || !YAML::convert<bool>::decode(child, value)) {
    Fail(key, "true or false");
  }
  return value;
}

std::string YamlMap::String(const std::string& key, const std::string& fallback) {
  const YAML::Node child = Child(key);
  if (!child.IsDefined() || child.IsNull()) return fallback;
  if (!child.IsScalar() || child.Scalar().empty()) Fail(key, "a non-empty string");
  return child.Scalar();
}

std::string YamlMap::RequireString(const std::string& key) {
  if (!Has(key)) Fail(key, "a non-empty string");
  return String(key, "");
}

std::array<double, 3> YamlMap::ReadVec3(const std::string& key,
                                        const std::array<double, 3>& fallback,
                                        const std::string& expected, double min, double max) {
  const YAML::Node child = Child(key);
  if (!child.IsDefined() || child.IsNull()) return fallback;
  if (!child.IsSequence() || child.size() != 3) Fail(key, expected);
  std::array<double, 3> out{};
  for (size_t i = 0; i < 3; ++i) {
    out[i] = ToNumber(child[i], key, expected);
    if (out[i] < min || out[i] > max) Fail(key, expected);
  }
  return out;
}

std::array<double, 3> YamlMap::Vec3(const std::string& key, const std::array<double, 3>& fallback) {
  return ReadVec3(key, fallback, "a list of 3 numbers", -kInf, kInf);
}

std::array<double, 3> YamlMap::Vec3(const std::string& key, const std::array<double, 3>& fallback,
                                    double min, double max) {
  return ReadVec3(key, fallback, "a list of 3 numbers in " + Range(min, max), min, max);
}

std::vector<double> YamlMap::Numbers(const std::string& key, size_t count, double min, double max,
                                     bool nonzero) {
  const std::string expected = "a list of " + std::to_string(count) + (nonzero ? " non-zero" : "") +
                               " numbers in " + Range(min, max);
  if (!Has(key)) Fail(key, expected);
  const YAML::Node child = Child(key);
  if (!child.IsSequence() || child.size() != count) Fail(key, expected);
  std::vector<double> out;
  for (size_t i = 0; i < count; ++i) {
    const YAML::Node item = child[i];
    double value = 0.0;
    const bool ok = item.IsScalar() && YAML::convert<double>::decode(item, value) &&
                    std::isfinite(value) && value >= min && value <= max &&
                    !(nonzero && value == 0.0);
    if (!ok) {
      throw ConfigError(Where(item) + ": key '" + Path(key) + "[" + std::to_string(i) +
                        "]': expected a" + (nonzero ? " non-zero" : "") + " number in " +
                        Range(min, max) + ", got " + Got(item));
    }
    out.push_back(value);
  }
  return out;
}

std::vector<double> YamlMap::Numbers(const std::string& key, size_t count,
                                     const std::string& noun) {
  const std::string expected = "a list of " + std::to_string(count) + " " + noun;
  if (!Has(key)) Fail(key, expected);
  const YAML::Node child = Child(key);
  if (!child.IsSequence() || child.size() != count) Fail(key, expected);
  std::vector<double> out;
  for (size_t i = 0; i < count; ++i) {
    const YAML::Node item = child[i];
    double value = 0.0;
    if (!item.IsScalar() || !YAML::convert<double>::decode(item, value) || !std::isfinite(value)) {
      throw ConfigError(Where(item) + ": key '" + Path(key) + "[" + std::to_string(i) +
                        "]': expected a finite number, got " + Got(item));
    }
    out.push_back(value);
  }
  return out;
}

std::vector<double> YamlMap::NumberList(const std::string& key,
                                        const std::vector<double>& fallback) {
  const YAML::Node child = Child(key);
  if (!child.IsDefined() || child.IsNull()) return fallback;
  if (!child.IsSequence()) Fail(key, "a list of numbers");
  return Numbers(key, child.size());
}

Vec2 YamlMap::Point(const std::string& key) {
  const YAML::Node child = Child(key);
  const std::string expected = "a point [x, y] in metres";
  if (!child.IsSequence() || child.size() != 2) Fail(key, expected);
  return Vec2(ToNumber(child[0], key, expected), ToNumber(child[1], key, expected));
}

std::vector<Vec2> YamlMap::Points(const std::string& key, size_t min_count) {
  const YAML::Node child = Child(key);
  const std::string expected = min_count == 0 ? std::string("a list of points [x, y] in metres")
                                              : "a list of at least " + std::to_string(min_count) +
                                                    " points [x, y] in metres";
  if (!child.IsSequence() || child.size() < min_count) Fail(key, expected);
  std::vector<Vec2> out;
  for (size_t i = 0; i < child.size(); ++i) {
    const YAML::Node p = child[i];
    if (!p.IsSequence() || p.size() != 2) {
      throw ConfigError(Where(p) + ": key '" + Path(key) + "[" + std::to_string(i) +
                        "]': expected a point [x, y] in metres, got " + Got(p));
    }
    out.emplace_back(ToNumber(p[0], key, expected), ToNumber(p[1], key, expected));
  }
  return out;
}

std::vector<std::array<double, 3>> YamlMap::Points3(const std::string& key, size_t min_count,
                                                    size_t max_count, double max_abs) {
  const YAML::Node child = Child(key);
  const std::string expected = "a list of " + std::to_string(min_count) + " to " +
                               std::to_string(max_count) + " points [x, y, z] in metres";
  if (!child.IsSequence() || child.size() < min_count || child.size() > max_count)
    Fail(key, expected);
  std::vector<std::array<double, 3>> out;
  for (size_t i = 0; i < child.size(); ++i) {
    const YAML::Node p = child[i];
    std::array<double, 3> v{};
    bool ok = p.IsSequence() && p.size() == 3;
    for (size_t k = 0; ok && k < 3; ++k) {
      ok = p[k].IsScalar() && YAML::convert<double>::decode(p[k], v[k]) && std::isfinite(v[k]) &&
           std::abs(v[k]) <= max_abs;
    }
    if (!ok) {
      std::ostringstream limit;
      limit << max_abs;
      throw ConfigError(Where(p) + ": key '" + Path(key) + "[" + std::to_string(i) +
                        "]': expected a point [x, y, z] in metres (|x| <= " + limit.str() +
                        "), got " + Got(p));
    }
    out.push_back(v);
  }
  return out;
}

std::vector<std::string> YamlMap::Strings(const std::string& key,
                                          const std::vector<std::string>& fallback) {
  const YAML::Node child = Child(key);
  if (!child.IsDefined() || child.IsNull()) return fallback;
  if (!child.IsSequence()) Fail(key, "a list of strings");
  std::vector<std::string> out;
  for (const auto& item : child) {
    if (!item.IsScalar() || item.Scalar().empty()) Fail(key, "a list of non-empty strings");
    out.push_back(item.Scalar());
  }
  return out;
}

YamlMap YamlMap::Map(const std::string& key) {
  const YAML::Node child = Child(key);
  if (!child.IsDefined() || child.IsNull())
    return YamlMap(YAML::Node(YAML::NodeType::Map), file_, Path(key));
  if (!child.IsMap()) Fail(key, "a mapping of keys");
  return YamlMap(child, file_, Path(key));
}

std::vector<YamlMap> YamlMap::MapList(const std::string& key) {
  const YAML::Node child = Child(key);
  std::vector<YamlMap> out;
  if (!child.IsDefined() || child.IsNull()) return out;
  if (!child.IsSequence()) Fail(key, "a list of mappings");
  for (size_t i = 0; i < child.size(); ++i) {
    const YAML::Node item = child[i];
    const std::string path = Path(key) + "[" + std::to_string(i) + "]";
    if (!item.IsMap()) {
      throw ConfigError(Where(item) + ": key '" + path + "': expected a mapping of keys, got " +
                        Got(item));
    }
    out.emplace_back(item, file_, path);
  }
  return out;
}

std::vector<std::string> YamlMap::Keys() const {
  std::vector<std::string> keys;
  if (!node_.IsMap()) return keys;
  for (const auto& entry : node_) {
    if (!entry.first.IsScalar()) Fail("<not a plain key>", "plain keys");
    keys.push_back(entry.first.Scalar());
  }
  return keys;
}

void YamlMap::Finish() const {
  if (!node_.IsMap()) return;
  for (const auto& entry : node_) {
    const std::string key = entry.first.IsScalar() ? entry.first.Scalar() : "<not a plain key>";
    if (read_.count(key) == 0) {
      std::string known;
      for (const auto& k : read_) known += (known.empty() ? "" : ", ") + k;
      throw ConfigError(Where(entry.first) + ": key '" + Path(key) + "': unknown key" +
                        (known.empty() ? "" : " (expected one of: " + known + ")"));
    }
  }
}

}  // namespace haptel::config_detail
