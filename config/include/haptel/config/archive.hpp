#pragma once
/// @file How a config struct names each field once, for loading, validation
/// and saving alike (Drake's `Serialize(Archive*)` is the model):
///
///     struct SafetyConfig {
///       double wrist_force_limit = 7.0;  ///< N
///       ...
///       template <typename Archive>
///       void Serialize(Archive* a) {
///         a->Visit(HAPTEL_NVP(wrist_force_limit), config::Range{0.0, 200.0});
///         ...
///       }
///     };
///
/// The archives walking Serialize live in config/src: the strict YAML reader
/// (unknown and duplicate keys refused, errors naming file:line:column, the
/// key path and what was expected), the field checker every ValidateOrThrow
/// starts with (the rules below, keys relative to the struct), and the YAML
/// writer (configs written back, e.g. a calibration). A rule between fields
/// ("setpoint_timeout_s + fade_s <= 0.05") stays in ValidateOrThrow, after
/// the field checks.
#include <initializer_list>
#include <string>
#include <utility>

namespace haptel::config {

/// One field: its key in the file and where it lives.
template <typename T>
struct NameValue {
  const char* name;
  T* value;
};

template <typename T>
NameValue<T> MakeNameValue(const char* name, T* value) {
  return {name, value};
}

/// The field `member`, its key its name: `a->Visit(HAPTEL_NVP(rate_hz))`.
#define HAPTEL_NVP(member) ::haptel::config::MakeNameValue(#member, &(member))

// Rules a Visit may carry, after the field, in any order. The reader only
// checks types (and the rules that say so); ranges are checked by
// ValidateOrThrow, so a struct built in code is held to them too.

/// A number in [min, max] ("a number in [0, 200]"); for a whole number "a
/// whole number in [min, max]" (an unsigned one is checked as it is read);
/// for a list of 3, every element ("a list of 3 numbers in [-5, 5]").
struct Range {
  double min;
  double max;
};
/// A list's errors name the element ("glove_gain[3]: expected a number in ...").
struct EachElement {};
/// Numbers that must not be 0 (a scale, a slope).
struct NonZero {};
/// A string that must not be empty.
struct NonEmpty {};
/// The file must have the key; `expected` says what, when the value's type
/// does not ("the elevator channel (a mapping: ...)").
struct Required {
  std::string expected = {};
};
/// A struct the file writes as one line of text ("delay=100ms,loss=5%"):
/// `parse` throws std::invalid_argument saying what it expected.
template <typename T>
struct AsText {
  T (*parse)(const std::string& text, const T& base);
  std::string (*print)(const T& value);
};
/// A path written relative to the file's folder.
struct RelativeToFile {};
/// A section the file may leave out (then not read at all); the struct
/// holding it validates it, when it applies (a vehicle's `can:` for the
/// kinds that drive a CAN bus).
struct IfPresent {};
/// Written beside the value when the config is saved ("m per device unit").
struct Comment {
  const char* text;
};
/// A value the file spells as one of some words (an enum, or a bool as
/// on/off); `expected` defaults to "one of: a, b, c".
template <typename T>
struct Choice {
  std::initializer_list<std::pair<T, const char*>> names;
  const char* expected = nullptr;
};

}  // namespace haptel::config
