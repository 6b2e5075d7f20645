#include "haptel/config/check.hpp"

#include <cmath>
#include <sstream>

namespace haptel {

namespace {
std::string Join(const std::string& prefix, const std::string& key) {
  if (prefix.empty()) return key;
  if (key.empty()) return prefix;
  return key.front() == '[' ? prefix + key : prefix + "." + key;
}
}  // namespace

ConfigFieldError::ConfigFieldError(std::string key_in, std::string expected_in,
                                   std::vector<std::string> related_in, std::string got_in)
    : std::invalid_argument(key_in + ": expected " + expected_in +
                            (got_in.empty() ? "" : ", got " + got_in)),
      key(std::move(key_in)),
      expected(std::move(expected_in)),
      related(std::move(related_in)),
      got(std::move(got_in)) {}

ConfigFieldError ConfigFieldError::Within(const std::string& prefix) const {
  std::vector<std::string> prefixed;
  prefixed.reserve(related.size());
  for (const std::string& r : related) prefixed.push_back(Join(prefix, r));
  return ConfigFieldError(Join(prefix, key), expected, std::move(prefixed), got);
}

namespace config_check {

std::string Range(double min, double max) {
  std::ostringstream out;
  out << "[" << min << ", " << max << "]";
  return out.str();
}

void Fail(const std::string& key, const std::string& expected, std::vector<std::string> related) {
  throw ConfigFieldError(key, expected, std::move(related));
}

void Number(const std::string& key, double value, double min, double max) {
  if (!(value >= min && value <= max)) Fail(key, "a number in " + Range(min, max));
}

void Whole(const std::string& key, long value, long min, long max) {
  if (value < min || value > max) {
    Fail(key, "a whole number in [" + std::to_string(min) + ", " + std::to_string(max) + "]");
  }
}

void Vec3(const std::string& key, const std::array<double, 3>& value, double min, double max) {
  for (double v : value) {
    if (!(v >= min && v <= max)) Fail(key, "a list of 3 numbers in " + Range(min, max));
  }
}

void Positive(const std::string& key, double value) {
  if (!(value > 0.0) || !std::isfinite(value)) Fail(key, "a finite number > 0");
}

void NonNegative(const std::string& key, double value) {
  if (!(value >= 0.0) || !std::isfinite(value)) Fail(key, "a finite number >= 0");
}

void NonEmpty(const std::string& key, const std::string& value) {
  if (value.empty()) Fail(key, "a non-empty string");
}

}  // namespace config_check
}  // namespace haptel
