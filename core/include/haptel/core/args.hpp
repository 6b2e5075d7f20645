#pragma once
/// @file A small strict command-line parser: `--key value`, `--key=value` and
/// `--flag`. Unknown options and missing values are errors (UsageError).
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "haptel/core/cli.hpp"

namespace haptel {

/// A command line that cannot work (exit 2, with a pointer to --help).
class UsageError : public cli::InputError {
 public:
  using cli::InputError::InputError;
};

/// "a,b,,c" -> {"a", "b", "", "c"}: an option's comma-separated list, empty
/// parts kept (so a parser can name them); "" -> {""}.
std::vector<std::string> SplitList(const std::string& text, char separator = ',');
/// {"a", "b"} -> "a,b" (with `separator` between): SplitList's inverse.
std::string JoinList(const std::vector<std::string>& parts, const std::string& separator = ",");

/// The length of the plain decimal number `text` starts with: an optional
/// sign, digits with at most one point, an optional exponent ("-1.5e3");
/// 0 when it starts with none. Unlike strtod, hexadecimal ("0x10"), "inf",
/// "nan" and leading spaces are not numbers a person types.
size_t DecimalPrefix(const std::string& text);

class Args {
 public:
  /// @param value_options options that take a value (without "--").
  /// @param flags options that take none.
  Args(int argc, const char* const* argv, std::set<std::string> value_options,
       std::set<std::string> flags);

  std::optional<std::string> Value(const std::string& name) const;
  /// An integer option in [min, max]; UsageError names the option otherwise.
  std::optional<int> Int(const std::string& name, int min, int max) const;
  /// A number option in [min, max], the whole word a plain decimal ("5x",
  /// "0x10" are not: DecimalPrefix);
  /// UsageError names the option, the range and what was given otherwise.
  std::optional<double> Number(const std::string& name, double min, double max) const;
  bool Flag(const std::string& name) const { return flags_set_.count(name) != 0; }
  /// Words that are not options (e.g. a sub-command), in order.
  const std::vector<std::string>& positional() const { return positional_; }

 private:
  std::map<std::string, std::string> values_;
  std::set<std::string> flags_set_;
  std::vector<std::string> positional_;
};

}  // namespace haptel
