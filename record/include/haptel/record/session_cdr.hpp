#pragma once
/// @file A session file's message (session_channels.hpp: the CDR bytes as
/// they crossed the link) decoded through its fastddsgen type, for the
/// readers of session files (`haptel replay --drive`, `haptel bench hands`).
#include <fastdds/rtps/common/SerializedPayload.h>

#include <algorithm>
#include <cstring>
#include <exception>

#include "haptel/mcap/reader.hpp"

namespace haptel::record {

/// `m`'s CDR into `out` through `PubSub`; false when it does not decode.
template <typename PubSub, typename Msg>
bool DecodeCdr(const mcap::MessageView& m, Msg& out) {
  PubSub type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(
      static_cast<uint32_t>(std::max<size_t>(m.size, 1)));
  std::memcpy(payload.data, m.data, m.size);
  payload.length = static_cast<uint32_t>(m.size);
  try {
    return type.deserialize(&payload, &out);
  } catch (const std::exception&) {
    return false;  // Fast CDR throws on a short buffer
  }
}

}  // namespace haptel::record
