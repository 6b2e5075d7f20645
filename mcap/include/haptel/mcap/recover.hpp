#pragma once
/// @file Rewrites a truncated MCAP file (a recording killed before it was
/// closed) as a complete one: every message, schema, channel, attachment and
/// metadata record that survived, in new chunks, with the summary and every
/// index rebuilt.
#include <cstdint>
#include <filesystem>

#include "haptel/mcap/reader.hpp"

namespace haptel::mcap {

struct RecoverResult {
  uint64_t messages = 0;
  uint32_t attachments = 0;
  uint32_t metadata = 0;
  Loss loss;  // what the input had lost (its torn tail)
};

/// Reads `in` (scanning it when it has no summary) and writes `out`, a
/// complete file with the input's chunk compression. Throws McapError when
/// `in` is not MCAP, std::runtime_error when `out` cannot be written.
/// `in` and `out` must differ.
RecoverResult Recover(const std::filesystem::path& in, const std::filesystem::path& out);
/// The same from a reader already open on the input.
RecoverResult Recover(const Reader& in, const std::filesystem::path& out);

}  // namespace haptel::mcap
