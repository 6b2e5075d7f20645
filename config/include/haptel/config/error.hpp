#pragma once
#include <stdexcept>
#include <string>

namespace haptel {

/// A configuration file (or command-line option) is wrong. The message names
/// the file, the line, the key and what was expected, on one line.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace haptel
