#pragma once
/// @file The archives that walk a config struct's Serialize
/// (haptel/config/archive.hpp): YamlReadArchive reads a file strictly,
/// FieldChecker checks the fields' rules (what ValidateOrThrow starts with),
/// YamlWriteArchive writes a file. `LoadFile<Config>(file)` is the whole of
/// a loader for a struct with a Serialize, in config/ or beside its code
/// (an interface's own config: docs/architecture.md, "Adding an interface").
#include <yaml-cpp/yaml.h>

#include <array>
#include <concepts>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "haptel/config/archive.hpp"
#include "haptel/config/check.hpp"
#include "haptel/config/yaml_map.hpp"

namespace haptel::config_detail {

/// The first of `rules` that is a `Rule`, or nullptr.
template <typename Rule, typename... Rules>
const Rule* FindRule(const Rules&... rules) {
  const Rule* found = nullptr;
  const auto take = [&found](const auto& rule) {
    if constexpr (std::is_same_v<std::decay_t<decltype(rule)>, Rule>) {
      if (found == nullptr) found = &rule;
    }
  };
  (take(rules), ...);
  (void)take;  // unused when there are no rules
  return found;
}

template <typename Rule, typename... Rules>
constexpr bool kHasRule = (std::is_same_v<Rule, Rules> || ...);

template <typename T>
struct IsStdArray : std::false_type {};
template <typename T, size_t N>
struct IsStdArray<std::array<T, N>> : std::true_type {};

/// Values a Visit reads as one YAML value (all else is a struct: a mapping).
template <typename T>
constexpr bool kPlainType =
    std::is_arithmetic_v<T> || std::is_enum_v<T> || std::is_same_v<T, std::string> ||
    std::is_same_v<T, std::filesystem::path> || std::is_same_v<T, std::vector<std::string>> ||
    std::is_same_v<T, std::vector<double>> || IsStdArray<T>::value;

/// "one of: a, b, c", or the choice's own words.
template <typename T>
std::string ChoiceExpected(const config::Choice<T>& choice) {
  if (choice.expected != nullptr) return choice.expected;
  std::string out = "one of: ";
  bool first = true;
  for (const auto& [value, name] : choice.names) {
    out += (first ? "" : ", ") + std::string(name);
    first = false;
  }
  return out;
}

/// The word for `value`, or nullptr when the choice has none.
template <typename T>
const char* ChoiceName(const config::Choice<T>& choice, const T& value) {
  for (const auto& [v, name] : choice.names) {
    if (v == value) return name;
  }
  return nullptr;
}

/// Reads a struct's fields from one mapping of a file (and its nested
/// structs from the mappings under their keys, each finished: a key nobody
/// reads is refused). Only types are checked here; ValidateIn checks the
/// values once the whole file is read.
class YamlReadArchive {
 public:
  static constexpr bool kReads = true;

  /// `dir` is the file's folder (paths marked RelativeToFile resolve there).
  YamlReadArchive(YamlMap& map, std::filesystem::path dir) : map_(map), dir_(std::move(dir)) {}

  template <typename T, typename... Rules>
  void Visit(const config::NameValue<T>& field, const Rules&... rules) {
    const std::string key = field.name;
    T& value = *field.value;
    const config::Required* required = FindRule<config::Required>(rules...);
    if (required != nullptr && !required->expected.empty()) {
      // A mapping must be one: its words say more than "a mapping of keys".
      const bool missing = std::is_class_v<T> && !kPlainType<T> ? !map_.IsMap(key) : !map_.Has(key);
      if (missing) map_.Fail(key, required->expected);
    }
    if constexpr (kHasRule<config::Choice<T>, Rules...>) {
      const auto& choice = *FindRule<config::Choice<T>>(rules...);
      const char* current = ChoiceName(choice, value);
      const std::string name = map_.String(key, current != nullptr ? current : "");
      for (const auto& [v, word] : choice.names) {
        if (name == word) {
          value = v;
          return;
        }
      }
      map_.Fail(key, ChoiceExpected(choice));
    } else if constexpr (std::is_same_v<T, bool>) {
      value = map_.Bool(key, value);
    } else if constexpr (std::is_same_v<T, int>) {
      value = map_.Integer(key, value);
    } else if constexpr (std::is_integral_v<T>) {
      // Wider or unsigned whole numbers (seeds): their range as they are read.
      static_assert(kHasRule<config::Range, Rules...>, "an unsigned field needs a config::Range");
      const config::Range& range = *FindRule<config::Range>(rules...);
      value = static_cast<T>(map_.Integer(key, static_cast<int>(value), static_cast<int>(range.min),
                                          static_cast<int>(range.max)));
    } else if constexpr (std::is_same_v<T, double>) {
      value = required != nullptr ? map_.RequireNumber(key) : map_.Number(key, value);
    } else if constexpr (std::is_same_v<T, std::string>) {
      value = required != nullptr ? map_.RequireString(key) : map_.String(key, value);
    } else if constexpr (kHasRule<config::AsText<T>, Rules...>) {
      const auto& as_text = *FindRule<config::AsText<T>>(rules...);
      const std::string text = map_.String(key, "");
      if (text.empty()) return;
      try {
        value = as_text.parse(text, T{});
      } catch (const std::invalid_argument& e) {
        map_.Fail(key, e.what());
      }
    } else if constexpr (std::is_same_v<T, std::filesystem::path>) {
      const std::string text = required != nullptr ? map_.RequireString(key) : map_.String(key, "");
      if (text.empty()) return;
      value =
          kHasRule<config::RelativeToFile, Rules...> ? dir_ / text : std::filesystem::path(text);
    } else if constexpr (std::is_same_v<T, std::vector<std::string>>) {
      value = map_.Strings(key, value);
    } else if constexpr (std::is_same_v<T, std::vector<double>>) {
      value = map_.NumberList(key, value);
    } else if constexpr (IsStdArray<T>::value) {
      ReadArray<kHasRule<config::Required, Rules...>>(key, value,
                                                      kHasRule<config::NonZero, Rules...>);
    } else {
      if constexpr (kHasRule<config::IfPresent, Rules...>) {
        if (!map_.Has(key)) {
          map_.Allow(key);
          return;
        }
      }
      YamlMap child = map_.Map(key);
      YamlReadArchive archive(child, dir_);
      value.Serialize(&archive);
      child.Finish();
    }
  }

  /// A mapping in the file that is no struct of its own (`arms: {left: ...,
  /// right: ...}`): `visit(archive)` visits its keys.
  template <typename Visit, typename... Rules>
  void Group(const char* name, Visit&& visit, const Rules&... rules) {
    if (const config::Required* required = FindRule<config::Required>(rules...);
        required != nullptr && !map_.IsMap(name)) {
      map_.Fail(name, required->expected);
    }
    YamlMap child = map_.Map(name);
    YamlReadArchive archive(child, dir_);
    visit(&archive);
    child.Finish();
  }

 private:
  template <bool kRequired, typename Element, size_t N>
  void ReadArray(const std::string& key, std::array<Element, N>& value, bool nonzero) {
    static_assert(std::is_same_v<Element, double>, "lists of numbers only");
    if constexpr (kRequired) {
      const std::vector<double> read =
          map_.Numbers(key, N, nonzero ? "non-zero numbers" : "numbers");
      for (size_t i = 0; i < N; ++i) value[i] = read[i];
    } else {
      static_assert(N == 3, "an optional list is a list of 3 numbers");
      value = map_.Vec3(key, value);
    }
  }

  YamlMap& map_;
  std::filesystem::path dir_;
};

/// Checks each field against its rules, in the order Serialize visits them;
/// throws ConfigFieldError naming the key relative to the struct. A nested
/// struct is checked by its own ValidateOrThrow (its keys prefixed).
class FieldChecker {
 public:
  static constexpr bool kReads = false;

  template <typename T, typename... Rules>
  void Visit(const config::NameValue<T>& field, const Rules&... rules) {
    namespace check = config_check;
    const std::string key = field.name;
    const T& value = *field.value;
    const config::Range* range = FindRule<config::Range>(rules...);
    if constexpr (kHasRule<config::Choice<T>, Rules...>) {
      const auto& choice = *FindRule<config::Choice<T>>(rules...);
      if (ChoiceName(choice, value) == nullptr) check::Fail(key, ChoiceExpected(choice));
    } else if constexpr (std::is_same_v<T, int>) {
      if (range != nullptr) {
        check::Whole(key, value, static_cast<long>(range->min), static_cast<long>(range->max));
      }
    } else if constexpr (std::is_same_v<T, double>) {
      if (range != nullptr) check::Number(key, value, range->min, range->max);
    } else if constexpr (std::is_same_v<T, std::string>) {
      if (kHasRule<config::NonEmpty, Rules...>) check::NonEmpty(key, value);
    } else if constexpr (IsStdArray<T>::value) {
      if (range == nullptr) return;
      if constexpr (kHasRule<config::EachElement, Rules...>) {
        const bool nonzero = kHasRule<config::NonZero, Rules...>;
        for (size_t i = 0; i < value.size(); ++i) {
          if (!(value[i] >= range->min && value[i] <= range->max) || (nonzero && value[i] == 0.0)) {
            check::Fail(key + "[" + std::to_string(i) + "]",
                        std::string("a") + (nonzero ? " non-zero" : "") + " number in " +
                            check::Range(range->min, range->max));
          }
        }
      } else {
        check::Vec3(key, value, range->min, range->max);
      }
    } else if constexpr (!kPlainType<T>) {
      if constexpr (!kHasRule<config::IfPresent, Rules...>) check::Nested(key, value);
    }
  }

  template <typename Visit, typename... Rules>
  void Group(const char* name, Visit&& visit, const Rules&...) {
    try {
      visit(this);
    } catch (const ConfigFieldError& e) {
      throw e.Within(name);
    }
  }
};

/// Checks the rules of `config`'s fields (FieldChecker): the first line of
/// its ValidateOrThrow.
template <typename Config>
void CheckFields(const Config& config) {
  FieldChecker checker;
  // Serialize takes the struct to write into; the checker only reads.
  const_cast<Config&>(config).Serialize(&checker);
}

/// Reads a section (a struct) from `section`, then finishes it (unknown keys
/// refused); `dir` is the file's folder.
template <typename Config>
Config ReadSection(YamlMap& section, const std::filesystem::path& dir = {}) {
  Config config;
  YamlReadArchive archive(section, dir);
  config.Serialize(&archive);
  section.Finish();
  return config;
}

/// Loads a whole file into a Config: its Serialize read strictly from the
/// top-level mapping, then `also(root, config)` (rules on the file itself,
/// e.g. which names a file of this kind may have), then unknown keys refused
/// and ValidateOrThrow run, its errors at their keys' lines.
template <typename Config, typename Also>
Config LoadFile(const std::filesystem::path& file, Also&& also) {
  YamlMap root = YamlMap::Load(file);
  Config config;
  if constexpr (requires { config.file = file; }) config.file = file;
  YamlReadArchive archive(root, file.parent_path());
  config.Serialize(&archive);
  also(root, config);
  root.Finish();
  ValidateIn(root, config);
  return config;
}

template <typename Config>
Config LoadFile(const std::filesystem::path& file) {
  return LoadFile<Config>(file, [](YamlMap&, Config&) {});
}

/// Writes a struct's fields as a YAML mapping, in Serialize's order, each
/// with its Comment; a struct YamlReadArchive reads back equal.
class YamlWriteArchive {
 public:
  static constexpr bool kReads = false;

  explicit YamlWriteArchive(YAML::Emitter& out) : out_(out) {}

  template <typename T, typename... Rules>
  void Visit(const config::NameValue<T>& field, const Rules&... rules) {
    const T& value = *field.value;
    out_ << YAML::Key << field.name << YAML::Value;
    if constexpr (kHasRule<config::Choice<T>, Rules...>) {
      out_ << ChoiceName(*FindRule<config::Choice<T>>(rules...), value);
    } else if constexpr (kHasRule<config::AsText<T>, Rules...>) {
      out_ << FindRule<config::AsText<T>>(rules...)->print(value);
    } else if constexpr (std::is_same_v<T, std::filesystem::path>) {
      out_ << value.string();
    } else if constexpr (std::is_arithmetic_v<T> || std::is_same_v<T, std::string>) {
      out_ << value;
    } else if constexpr (IsStdArray<T>::value || std::is_same_v<T, std::vector<double>> ||
                         std::is_same_v<T, std::vector<std::string>>) {
      out_ << YAML::Flow << YAML::BeginSeq;
      for (const auto& v : value) out_ << v;
      out_ << YAML::EndSeq;
    } else {
      out_ << YAML::BeginMap;
      const_cast<T&>(value).Serialize(this);
      out_ << YAML::EndMap;
    }
    if (const config::Comment* comment = FindRule<config::Comment>(rules...)) {
      out_ << YAML::Comment(comment->text);
    }
  }

  template <typename Visit, typename... Rules>
  void Group(const char* name, Visit&& visit, const Rules&...) {
    out_ << YAML::Key << name << YAML::Value << YAML::BeginMap;
    visit(this);
    out_ << YAML::EndMap;
  }

 private:
  YAML::Emitter& out_;
};

}  // namespace haptel::config_detail
