#pragma once
#include <stdexcept>
#include <string>
#include <vector>

#include "haptel/core/cli.hpp"

namespace haptel {

/// A configuration file (or command-line option) is wrong. The message names
/// the file, the line, the key and what was expected, on one line.
class ConfigError : public cli::InputError {
 public:
  using cli::InputError::InputError;
};

/// A config struct holds a value one of its invariants forbids: what every
/// config struct's ValidateOrThrow throws, whether the struct came from a file
/// or was built in code. what() is "<key>: expected <expected>" (then ", got
/// <got>" when the rule says what it found). Loaders turn it into a
/// ConfigError at the line of the key in the file.
///
/// Keys are spelled as in the struct's config file, relative to the struct
/// validated: "hand.phalanx_radius", "gates[1].width", "wheel.radius".
struct ConfigFieldError : std::invalid_argument {
  ConfigFieldError(std::string key, std::string expected, std::vector<std::string> related = {},
                   std::string got = {});

  /// The same error seen from a struct that holds the one validated under
  /// `prefix` ("hand", "gates[1]", "link"): every key gets the prefix.
  ConfigFieldError Within(const std::string& prefix) const;

  std::string key;       ///< the field that breaks the rule
  std::string expected;  ///< what it must be, e.g. "a number in [0.001, 0.05]"
  /// For a rule between fields, the other fields it involves (a loader points
  /// at one of them when the file sets it but leaves `key` at its default).
  std::vector<std::string> related;
  /// What the rule found, when the value itself does not show it (a list's
  /// length: "7"); empty otherwise (a loader shows the value from the file).
  std::string got;
};

/// `config`, once `config.ValidateOrThrow()` has passed: lets a constructor
/// validate its config struct before its initializer list uses it.
template <typename Config>
const Config& Validated(const Config& config) {
  config.ValidateOrThrow();
  return config;
}

}  // namespace haptel
