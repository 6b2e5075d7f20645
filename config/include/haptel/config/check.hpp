#pragma once
/// @file The checks config structs' ValidateOrThrow are written with. Each
/// throws ConfigFieldError naming `key` and what was expected; NaN fails every
/// range, and ranges are closed ("a number in [min, max]").
#include <array>
#include <string>
#include <vector>

#include "haptel/config/error.hpp"

namespace haptel::config_check {

/// "[min, max]", as the messages print it.
std::string Range(double min, double max);

[[noreturn]] void Fail(const std::string& key, const std::string& expected,
                       std::vector<std::string> related = {});

/// min <= value <= max: "a number in [min, max]".
void Number(const std::string& key, double value, double min, double max);
/// min <= value <= max: "a whole number in [min, max]".
void Whole(const std::string& key, long value, long min, long max);
/// Each element in [min, max]: "a list of 3 numbers in [min, max]".
void Vec3(const std::string& key, const std::array<double, 3>& value, double min, double max);
/// Finite and > 0: "a finite number > 0".
void Positive(const std::string& key, double value);
/// Finite and >= 0: "a finite number >= 0".
void NonNegative(const std::string& key, double value);
/// Not empty: "a non-empty string".
void NonEmpty(const std::string& key, const std::string& value);

/// Validates a struct held under `prefix`, its errors' keys prefixed.
template <typename Config>
void Nested(const std::string& prefix, const Config& child) {
  try {
    child.ValidateOrThrow();
  } catch (const ConfigFieldError& e) {
    throw e.Within(prefix);
  }
}

}  // namespace haptel::config_check
