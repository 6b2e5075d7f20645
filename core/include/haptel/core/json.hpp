#pragma once
/// @file The two pieces every one-line JSON report needs (`--json` on the
/// benchmarks and on `haptel run`): a number and a quoted string.
#include <string>

namespace haptel {

/// `v` with 6 significant digits; `null` when it is NaN or infinite (JSON has
/// no such numbers).
std::string JsonNumber(double v);
/// `s` in double quotes, with quotes, backslashes and control characters escaped.
std::string JsonString(const std::string& s);

}  // namespace haptel
