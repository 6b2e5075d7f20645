#include "haptel/mcap/recover.hpp"

namespace haptel::mcap {
// Stub: the contract, committed first; the body follows.
RecoverResult Recover(const std::filesystem::path&, const std::filesystem::path&) { return {}; }
}  // namespace haptel::mcap
