#include "haptel/mcap/info.hpp"

namespace haptel::mcap {
// Stub: the contract, committed first; the body follows.
std::string DescribeFile(const Reader&) { return {}; }
std::string DescribeFileJson(const Reader&) { return "{}\n"; }
}  // namespace haptel::mcap
