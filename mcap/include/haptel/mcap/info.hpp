#pragma once
/// @file What a session file holds, for `haptel replay --info`: channels with
/// their schemas and encodings, message counts, rates, duration, chunks and
/// their compression, attachments and metadata, and what a truncated file
/// lost.
#include <string>

#include "haptel/mcap/reader.hpp"

namespace haptel::mcap {

/// A table for people.
std::string DescribeFile(const Reader& reader);
/// The same as one JSON object (channels[], duration_s, chunks, compression,
/// attachments[], metadata[], recovered, loss).
std::string DescribeFileJson(const Reader& reader);

}  // namespace haptel::mcap
