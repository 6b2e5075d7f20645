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

namespace {
/// The length of the well-formed UTF-8 sequence at `s[i]` (RFC 3629: no
/// overlong forms, no surrogates, nothing past U+10FFFF), or 0.
size_t Utf8Length(const std::string& s, size_t i) {
  const auto byte = [&](size_t k) { return k < s.size() ? static_cast<unsigned char>(s[k]) : 0U; };
  const unsigned c = byte(i);
  const auto cont = [&](size_t k) { return (byte(k) & 0xC0U) == 0x80U; };
  if (c < 0x80U) return 1;
  if (c >= 0xC2U && c <= 0xDFU) return cont(i + 1) ? 2 : 0;
  if (c >= 0xE0U && c <= 0xEFU) {
    const unsigned c1 = byte(i + 1);
    if ((c == 0xE0U && c1 < 0xA0U) || (c == 0xEDU && c1 >= 0xA0U)) return 0;
    return cont(i + 1) && cont(i + 2) ? 3 : 0;
  }
  if (c >= 0xF0U && c <= 0xF4U) {
    const unsigned c1 = byte(i + 1);
    if ((c == 0xF0U && c1 < 0x90U) || (c == 0xF4U && c1 >= 0x90U)) return 0;
    return cont(i + 1) && cont(i + 2) && cont(i + 3) ? 4 : 0;
  }
  return 0;
}
}  // namespace

std::string JsonString(const std::string& s) {
  std::string out = "\"";
  for (size_t i = 0; i < s.size();) {
    const char c = s[i];
    const size_t length = Utf8Length(s, i);
    if (length == 0) {
      out += "\\ufffd";  // a byte that is not UTF-8: JSON text must be
      ++i;
      continue;
    }
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out.append(s, i, length);
    }
    i += length;
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
