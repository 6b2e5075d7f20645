#pragma once
/// @file Who wrote a sample, as DDS itself knows it: the writer's GUID, which
/// Fast DDS hands the reader with every sample (SampleInfo) and which no
/// other participant's writer has. A vehicle binds its ownership to it, not
/// to anything the samples carry (a session id in a command is read off the
/// wire by anyone on the domain and sent back under it).
///
/// Without DDS Security this guards against mistakes, not attackers: RTPS
/// does not authenticate the GUID prefix a packet claims. With it, only
/// participants the deployment's CA vouches for join the link at all.
/// Plain bytes, no DDS headers: the vehicle's command intake uses it.
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <string>

namespace haptel::link {

struct WriterId {
  /// The GUID: its prefix (12 bytes: the participant) and entity id (4: the writer).
  static constexpr size_t kSize = 16;
  static constexpr size_t kPrefixSize = 12;
  std::array<uint8_t, kSize> guid{};

  /// All zero: no writer (nobody owns a vehicle).
  bool empty() const {
    return std::all_of(guid.begin(), guid.end(), [](uint8_t b) { return b == 0; });
  }
  /// Both are writers of one participant (the same GUID prefix): a run's
  /// command writer and its video feedback writer.
  bool SameParticipant(const WriterId& other) const {
    return std::equal(guid.begin(), guid.begin() + kPrefixSize, other.guid.begin());
  }
  friend bool operator==(const WriterId&, const WriterId&) = default;

  /// "010f2a…|00000103": the prefix and the entity, in hex (for messages).
  std::string ToString() const {
    std::string s;
    char byte[3];
    for (size_t i = 0; i < kSize; ++i) {
      if (i == kPrefixSize) s += '|';
      std::snprintf(byte, sizeof byte, "%02x", guid[i]);
      s += byte;
    }
    return s;
  }
};

/// The writer of a session that steps its vehicle in its own process
/// (`haptel run --simulated-time`: no DDS, one sender): never a Fast DDS
/// GUID (those begin with the vendor id 01.0f).
inline constexpr WriterId kInProcessWriter{
    {0xff, 0xff, 'i', 'n', '-', 'p', 'r', 'o', 'c', 'e', 's', 's', 0, 0, 0, 1}};

}  // namespace haptel::link
