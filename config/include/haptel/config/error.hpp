#pragma once
#include <stdexcept>
#include <string>

#include "haptel/core/cli.hpp"

namespace haptel {

/// A configuration file (or command-line option) is wrong. The message names
/// the file, the line, the key and what was expected, on one line.
class ConfigError : public cli::InputError {
 public:
  using cli::InputError::InputError;
};

}  // namespace haptel
