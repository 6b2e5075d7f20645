#include "haptel/core/json.hpp"

#include <cmath>
#include <cstdio>

namespace haptel {

std::string JsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string JsonString(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string JsonFieldOf(const std::string& json, const std::string& key) {
  const std::string needle = "\"" + key + "\":";
  const auto at = json.find(needle);
  if (at == std::string::npos) return "";
  const auto start = at + needle.size();
  if (start < json.size() && json[start] == '"') {
    const auto end = json.find('"', start + 1);
    return json.substr(start + 1, end == std::string::npos ? std::string::npos : end - start - 1);
  }
  const auto end = json.find_first_of(",}", start);
  return json.substr(start, end == std::string::npos ? std::string::npos : end - start);
}

}  // namespace haptel
