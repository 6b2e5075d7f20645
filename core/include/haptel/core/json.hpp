#pragma once
/// @file The two pieces every one-line JSON report needs (`--json` on the
/// benchmarks and on `haptel run`): a number and a quoted string; and the
/// one thing read back from such a line (a benchmark reading `haptel run`'s).
#include <string>

namespace haptel {

/// `v` with 6 significant digits; `null` when it is NaN or infinite (JSON has
/// no such numbers).
std::string JsonNumber(double v);
/// `s` in double quotes, with quotes, backslashes and control characters
/// escaped, and every byte that is not well-formed UTF-8 written as \ufffd
/// (JSON text is UTF-8: a name with a stray byte must not make the line invalid).
std::string JsonString(const std::string& s);
/// The value of top-level `key` in a flat one-line JSON object, as text
/// (a string without its quotes; escapes are not undone); "" when absent.
std::string JsonFieldOf(const std::string& json, const std::string& key);

}  // namespace haptel
