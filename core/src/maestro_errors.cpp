#include "haptel/core/maestro_errors.hpp"

#include <cstdio>

namespace haptel::maestro_errors {

const char* ErrorBitName(int bit) {
  static constexpr const char* kNames[] = {
      "serial signal error", "serial overrun",          "serial RX buffer full",
      "CRC error",           "protocol error",          "serial timeout",
      "script stack error",  "script call stack error", "script program counter error"};
  static constexpr const char* kHigh[] = {"bit 9",  "bit 10", "bit 11", "bit 12",
                                          "bit 13", "bit 14", "bit 15"};
  if (bit >= 0 && bit <= 8) return kNames[bit];
  if (bit >= 9 && bit <= 15) return kHigh[bit - 9];
  return "?";
}

std::string ErrorNames(uint16_t errors) {
  if (errors == 0) return "none";
  std::string out;
  for (int bit = 15; bit >= 0; --bit) {
    if ((errors & (1U << bit)) == 0) continue;
    if (!out.empty()) out += ", ";
    out += ErrorBitName(bit);
  }
  return out;
}

std::string ErrorsText(uint16_t errors) {
  if (errors == 0) return "none";
  char raw[32];
  std::snprintf(raw, sizeof raw, " (register 0x%04X)", static_cast<unsigned>(errors));
  return ErrorNames(errors) + raw;
}

}  // namespace haptel::maestro_errors
