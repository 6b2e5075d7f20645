// The UDP device protocol's wire format: layout, round trips, every rejection,
// and random input (fuzz-style) that must never decode by accident nor crash.
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string_view>
#include <vector>

#include "haptel/udp/udp_protocol.hpp"

using namespace haptel::haptics;
using namespace haptel::haptics::udp;

namespace {

/// One valid message of every type, with distinctive values, in version 1
/// (its layout; version 2's energy reports: test_udp_passivity.cpp).
std::vector<Message> Samples() {
  WristRequest wrist_request{{1.5, -2.25, 3.0}, {0.0, 0.5, 1.0, 1.5, 2.0}};
  WristReply wrist_reply{123456789012345, {12.5, -7.25, 0.125}, {0.5, 0.5, -0.5, 0.5}};
  GloveReply glove_reply;
  glove_reply.device_ns = -42;
  for (int j = 0; j < kGloveJoints; ++j) glove_reply.sensors[j] = 100.0 + j;
  for (int f = 0; f < kFingers; ++f) glove_reply.grasp[f] = -0.5 * f;
  return {
      Message{1, Side::kLeft, wrist_request, 1},
      Message{0xFFFFFFFFU, Side::kRight, wrist_reply, 1},
      Message{7, Side::kRight, GloveRequest{}, 1},
      Message{8, Side::kLeft, glove_reply, 1},
      Message{9, Side::kLeft, WristForce{{-1e-300, 0.0, 6.5}}, 1},
      Message{10, Side::kRight, FingerForce{{0.0, 1.0, 2.0, 3.0, 4.0}}, 1},
      Message{0x01020304U, Side::kLeft, ErrorReply{ErrorCode::kBusy}, 1},
  };
}

std::vector<uint8_t> Encoded(const Message& m) {
  Buffer buffer{};
  const std::size_t n = Encode(m, buffer);
  REQUIRE(n > 0);
  return {buffer.begin(), buffer.begin() + static_cast<std::ptrdiff_t>(n)};
}

/// Recomputes the checksum after a test edited a datagram on purpose.
void Reseal(std::vector<uint8_t>& d) {
  for (int i = 20; i < 24; ++i) d[i] = 0;
  const uint32_t crc = Crc32(d);
  for (int i = 0; i < 4; ++i) d[20 + i] = static_cast<uint8_t>(crc >> (8 * i));
}

void PutF64(std::vector<uint8_t>& d, std::size_t offset, double v) {
  uint64_t bits = 0;
  std::memcpy(&bits, &v, 8);
  for (int i = 0; i < 8; ++i) d[offset + i] = static_cast<uint8_t>(bits >> (8 * i));
}

DecodeStatus DecodeBytes(const std::vector<uint8_t>& d) {
  Message m;
  return Decode(d, m);
}

/// Field-by-field equality of two payloads (bitwise on doubles).
bool SameBytes(const Message& a, const Message& b) {
  Buffer x{};
  Buffer y{};
  const std::size_t n = Encode(a, x);
  const std::size_t m = Encode(b, y);
  return n == m && n > 0 && std::memcmp(x.data(), y.data(), n) == 0;
}

}  // namespace

TEST_CASE("crc32 is the IEEE/zlib CRC-32", "[udp][protocol]") {
  constexpr std::string_view check = "123456789";
  const auto* bytes = reinterpret_cast<const uint8_t*>(check.data());
  CHECK(Crc32({bytes, check.size()}) == 0xCBF43926U);
  // Continuing from a previous result equals one pass.
  CHECK(Crc32({bytes + 4, 5}, Crc32({bytes, 4})) == 0xCBF43926U);
  CHECK(Crc32({}) == 0U);
}

TEST_CASE("header layout is fixed little-endian", "[udp][protocol]") {
  const Message m{0x01020304U, Side::kRight, WristForce{{1.0, -2.0, 0.0}}, 1};
  const std::vector<uint8_t> d = Encoded(m);
  REQUIRE(d.size() == kHeaderSize + kWristForceSize);
  CHECK(d[0] == 'H');
  CHECK(d[1] == 'P');
  CHECK(d[2] == 'T');
  CHECK(d[3] == 'L');
  CHECK(d[4] == 1);  // version 1
  CHECK(d[5] == 0);
  CHECK(d[6] == 5);  // WRIST_FORCE
  CHECK(d[7] == 0);
  CHECK(d[8] == 0x04);  // sequence
  CHECK(d[9] == 0x03);
  CHECK(d[10] == 0x02);
  CHECK(d[11] == 0x01);
  CHECK(d[12] == 24);  // payload length
  CHECK(d[13] == 0);
  CHECK(d[14] == 0);
  CHECK(d[15] == 0);
  CHECK(d[16] == 1);  // right
  CHECK(d[17] == 0);
  CHECK(d[18] == 0);
  CHECK(d[19] == 0);
  // 1.0 as little-endian IEEE-754 binary64: 00 .. 00 F0 3F; -2.0: 00 .. 00 00 C0.
  const std::array<uint8_t, 8> one{0, 0, 0, 0, 0, 0, 0xF0, 0x3F};
  const std::array<uint8_t, 8> minus_two{0, 0, 0, 0, 0, 0, 0x00, 0xC0};
  CHECK(std::equal(one.begin(), one.end(), d.begin() + 24));
  CHECK(std::equal(minus_two.begin(), minus_two.end(), d.begin() + 32));
  // Checksum: CRC-32 of the datagram with the checksum field zeroed.
  std::vector<uint8_t> zeroed = d;
  for (int i = 20; i < 24; ++i) zeroed[i] = 0;
  const uint32_t crc = Crc32(zeroed);
  CHECK(d[20] == static_cast<uint8_t>(crc));
  CHECK(d[23] == static_cast<uint8_t>(crc >> 24));
}

TEST_CASE("every message type round-trips", "[udp][protocol]") {
  for (const Message& m : Samples()) {
    INFO(ToString(m.type()));
    const std::vector<uint8_t> d = Encoded(m);
    CHECK(d.size() == kHeaderSize + PayloadSize(m.type(), 1));
    Message out;
    out.sequence = 999;
    REQUIRE(Decode(d, out) == DecodeStatus::kOk);
    CHECK(out.sequence == m.sequence);
    CHECK(out.side == m.side);
    CHECK(out.type() == m.type());
    CHECK(SameBytes(out, m));
  }
  // And the values themselves, for the two richest payloads.
  Message out;
  REQUIRE(Decode(Encoded(Samples()[3]), out) == DecodeStatus::kOk);
  const auto& glove = std::get<GloveReply>(out.payload);
  CHECK(glove.device_ns == -42);
  CHECK(glove.sensors[21] == 121.0);
  CHECK(glove.grasp[4] == -2.0);
  REQUIRE(Decode(Encoded(Samples()[0]), out) == DecodeStatus::kOk);
  const auto& request = std::get<WristRequest>(out.payload);
  CHECK(request.wrist_force == Vec3d{1.5, -2.25, 3.0});
  CHECK(request.finger_forces[4] == 2.0);
}

TEST_CASE("encode refuses small buffers and values the peer would reject", "[udp][protocol]") {
  std::array<uint8_t, kHeaderSize + kWristForceSize - 1> small{};
  CHECK(Encode(Message{1, Side::kLeft, WristForce{{1, 2, 3}}, 1}, small) == 0);
  std::array<uint8_t, kHeaderSize + kWristForceSize> exact{};
  CHECK(Encode(Message{1, Side::kLeft, WristForce{{1, 2, 3}}, 1}, exact) == exact.size());
  Buffer b{};
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  CHECK(Encode(Message{1, Side::kLeft, WristForce{{1, nan, 3}}}, b) == 0);
  CHECK(Encode(Message{1, Side::kLeft, FingerForce{{1, 1, inf, 1, 1}}}, b) == 0);
  CHECK(Encode(Message{1, Side::kLeft, FingerForce{{1, 1, -0.1, 1, 1}}}, b) == 0);
  CHECK(Encode(Message{1, Side::kLeft, WristReply{0, {0, 0, 0}, {2, 0, 0, 0}}}, b) == 0);
  CHECK(Encode(Message{1, Side::kLeft, ErrorReply{static_cast<ErrorCode>(77)}}, b) == 0);
  CHECK(Encode(Message{1, static_cast<Side>(2), GloveRequest{}}, b) == 0);
}

TEST_CASE("decode rejects each kind of bad datagram with its status", "[udp][protocol]") {
  const std::vector<uint8_t> good =
      Encoded(Message{42, Side::kLeft, WristRequest{{1, 2, 3}, {1, 1, 1, 1, 1}}});
  REQUIRE(DecodeBytes(good) == DecodeStatus::kOk);

  SECTION("short") {
    CHECK(DecodeBytes({}) == DecodeStatus::kShort);
    CHECK(DecodeBytes(std::vector<uint8_t>(good.begin(), good.begin() + kHeaderSize - 1)) ==
          DecodeStatus::kShort);
    CHECK(DecodeBytes(std::vector<uint8_t>(good.begin(), good.end() - 1)) == DecodeStatus::kShort);
  }
  SECTION("bad magic") {
    std::vector<uint8_t> d = good;
    d[0] = 'X';
    Reseal(d);
    CHECK(DecodeBytes(d) == DecodeStatus::kBadMagic);
  }
  SECTION("bad version") {
    std::vector<uint8_t> d = good;
    d[4] = 3;  // versions 1 and 2 are spoken
    Reseal(d);
    CHECK(DecodeBytes(d) == DecodeStatus::kBadVersion);
  }
  SECTION("bad length") {
    std::vector<uint8_t> trailing = good;
    trailing.push_back(0);
    CHECK(DecodeBytes(trailing) == DecodeStatus::kBadLength);
    std::vector<uint8_t> huge = good;
    huge[13] = 1;  // length 64 + 256: more than any payload
    Reseal(huge);
    CHECK(DecodeBytes(huge) == DecodeStatus::kBadLength);
    // A self-consistent datagram whose length is not its type's size.
    std::vector<uint8_t> wrong = good;
    wrong.resize(good.size() - 8);
    wrong[12] = static_cast<uint8_t>(kWristRequestSize - 8);
    Reseal(wrong);
    CHECK(DecodeBytes(wrong) == DecodeStatus::kBadLength);
  }
  SECTION("bad checksum") {
    std::vector<uint8_t> d = good;
    d[30] ^= 0x01;
    CHECK(DecodeBytes(d) == DecodeStatus::kBadChecksum);
    std::vector<uint8_t> c = good;
    c[21] ^= 0x80;
    CHECK(DecodeBytes(c) == DecodeStatus::kBadChecksum);
  }
  SECTION("unknown type, with sequence and side still readable") {
    std::vector<uint8_t> d = good;
    d[6] = 99;
    Reseal(d);
    Message m;
    CHECK(Decode(d, m) == DecodeStatus::kUnknownType);
    CHECK(m.sequence == 42);
    CHECK(m.side == Side::kLeft);
    d[6] = 0;
    Reseal(d);
    CHECK(DecodeBytes(d) == DecodeStatus::kUnknownType);
  }
  SECTION("bad header: side or reserved bytes") {
    std::vector<uint8_t> side = good;
    side[16] = 2;
    Reseal(side);
    CHECK(DecodeBytes(side) == DecodeStatus::kBadHeader);
    std::vector<uint8_t> reserved = good;
    reserved[18] = 1;
    Reseal(reserved);
    CHECK(DecodeBytes(reserved) == DecodeStatus::kBadHeader);
  }
  SECTION("non-finite values in any payload double") {
    for (const double bad :
         {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
          -std::numeric_limits<double>::infinity(), std::numeric_limits<double>::signaling_NaN()}) {
      for (const Message& m : Samples()) {
        const std::vector<uint8_t> base = Encoded(m);
        // Doubles start after the 8-byte device time in replies, at once otherwise.
        const bool has_time =
            m.type() == MessageType::kWristReply || m.type() == MessageType::kGloveReply;
        const std::size_t first = kHeaderSize + (has_time ? 8 : 0);
        if (m.type() == MessageType::kGloveRequest || m.type() == MessageType::kError) continue;
        for (std::size_t at = first; at + 8 <= base.size(); at += 8) {
          std::vector<uint8_t> d = base;
          PutF64(d, at, bad);
          Reseal(d);
          INFO(ToString(m.type()) << " double at byte " << at);
          CHECK(DecodeBytes(d) == DecodeStatus::kNonFinite);
        }
      }
    }
  }
  SECTION("finite values out of their domain") {
    std::vector<uint8_t> finger = good;
    PutF64(finger, kHeaderSize + 3 * 8 + 2 * 8, -0.5);  // third finger force
    Reseal(finger);
    CHECK(DecodeBytes(finger) == DecodeStatus::kBadValue);
    std::vector<uint8_t> quaternion = Encoded(Samples()[1]);
    PutF64(quaternion, kHeaderSize + 8 + 3 * 8, 0.9);  // w: |q| no longer 1
    Reseal(quaternion);
    CHECK(DecodeBytes(quaternion) == DecodeStatus::kBadValue);
    std::vector<uint8_t> code = Encoded(Samples()[6]);
    code[kHeaderSize] = 0;  // error code 0
    Reseal(code);
    CHECK(DecodeBytes(code) == DecodeStatus::kBadValue);
    std::vector<uint8_t> reserved = Encoded(Samples()[6]);
    reserved[kHeaderSize + 3] = 1;
    Reseal(reserved);
    CHECK(DecodeBytes(reserved) == DecodeStatus::kBadValue);
  }
  SECTION("decode leaves the output alone on failure") {
    std::vector<uint8_t> d = good;
    d[30] ^= 0x01;
    Message m{7, Side::kRight, GloveRequest{}};
    REQUIRE(Decode(d, m) != DecodeStatus::kOk);
    CHECK(m.sequence == 7);
    CHECK(m.side == Side::kRight);
    CHECK(m.type() == MessageType::kGloveRequest);
  }
}

TEST_CASE("sequence numbers compare in serial-number order", "[udp][protocol]") {
  CHECK(SequenceAfter(2, 1));
  CHECK_FALSE(SequenceAfter(1, 2));
  CHECK_FALSE(SequenceAfter(5, 5));
  CHECK(SequenceAfter(0, 0xFFFFFFFFU));  // wrap-around
  CHECK(SequenceAfter(3, 0xFFFFFFF0U));
  CHECK_FALSE(SequenceAfter(0xFFFFFFF0U, 3));
}

TEST_CASE("fuzz: random datagrams never decode by accident and never crash",
          "[udp][protocol][fuzz]") {
  std::mt19937_64 rng(20240601);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<std::size_t> length(0, 2 * kMaxMessageSize);
  std::array<int, kDecodeStatuses> seen{};

  SECTION("random byte strings of random length") {
    for (int i = 0; i < 20000; ++i) {
      std::vector<uint8_t> d(length(rng));
      for (uint8_t& b : d) b = static_cast<uint8_t>(byte(rng));
      Message m;
      const DecodeStatus s = Decode(d, m);
      ++seen[static_cast<int>(s)];
      CHECK(s != DecodeStatus::kOk);
    }
    CHECK(seen[static_cast<int>(DecodeStatus::kShort)] > 0);
    CHECK(seen[static_cast<int>(DecodeStatus::kBadMagic)] > 0);
  }

  SECTION("random bytes behind a sound header reach the payload checks") {
    // Valid magic, version, type, length and a correct checksum over random
    // payload bytes: exercises the value checks. Whatever decodes must
    // re-encode to the very same bytes (the encoding is canonical).
    std::uniform_int_distribution<int> type(0, 9);
    for (int i = 0; i < 20000; ++i) {
      const auto t = static_cast<MessageType>(type(rng));
      const std::size_t size = PayloadSize(t);
      std::vector<uint8_t> d(kHeaderSize + size);
      for (uint8_t& b : d) b = static_cast<uint8_t>(byte(rng));
      const std::array<uint8_t, 4> magic = kMagic;
      std::copy(magic.begin(), magic.end(), d.begin());
      d[4] = 1;
      d[5] = 0;
      d[6] = static_cast<uint8_t>(t);
      d[7] = 0;
      for (int k = 0; k < 4; ++k) d[12 + k] = static_cast<uint8_t>(size >> (8 * k));
      d[16] &= 1;
      if (i % 4 != 0) d[17] = d[18] = d[19] = 0;  // mostly sound reserved bytes
      // Half of the doubles made small finite numbers, so some payloads pass.
      for (std::size_t at = kHeaderSize; at + 8 <= d.size(); at += 8) {
        if (byte(rng) < 128) PutF64(d, at, std::uniform_real_distribution<double>(0.0, 10.0)(rng));
      }
      Reseal(d);
      Message m;
      const DecodeStatus s = Decode(d, m);
      ++seen[static_cast<int>(s)];
      if (s == DecodeStatus::kOk) {
        Buffer again{};
        const std::size_t n = Encode(m, again);
        REQUIRE(n == d.size());
        CHECK(std::memcmp(again.data(), d.data(), n) == 0);
      }
    }
    CHECK(seen[static_cast<int>(DecodeStatus::kOk)] > 0);
    CHECK(seen[static_cast<int>(DecodeStatus::kNonFinite)] > 0);
    CHECK(seen[static_cast<int>(DecodeStatus::kUnknownType)] > 0);
    CHECK(seen[static_cast<int>(DecodeStatus::kBadHeader)] > 0);
  }

  SECTION("single-byte corruptions and truncations of valid messages never decode") {
    for (const Message& m : Samples()) {
      const std::vector<uint8_t> good = Encoded(m);
      std::uniform_int_distribution<std::size_t> where(0, good.size() - 1);
      std::uniform_int_distribution<int> flip(1, 255);
      for (int i = 0; i < 3000; ++i) {
        std::vector<uint8_t> d = good;
        d[where(rng)] ^= static_cast<uint8_t>(flip(rng));
        Message out;
        const DecodeStatus s = Decode(d, out);
        ++seen[static_cast<int>(s)];
        // CRC-32 catches every error burst of up to 32 bits: a changed byte
        // can never leave the checksum matching.
        CHECK(s != DecodeStatus::kOk);
      }
      for (std::size_t n = 0; n < good.size(); ++n) {
        Message out;
        CHECK(Decode(std::span<const uint8_t>(good.data(), n), out) != DecodeStatus::kOk);
      }
    }
    CHECK(seen[static_cast<int>(DecodeStatus::kBadChecksum)] > 0);
  }

  SECTION("multi-byte corruptions decode only when the checksum still matches") {
    for (const Message& m : Samples()) {
      const std::vector<uint8_t> good = Encoded(m);
      std::uniform_int_distribution<std::size_t> where(0, good.size() - 1);
      for (int i = 0; i < 3000; ++i) {
        std::vector<uint8_t> d = good;
        for (int k = 0; k < 1 + i % 6; ++k) d[where(rng)] = static_cast<uint8_t>(byte(rng));
        Message out;
        const DecodeStatus s = Decode(d, out);
        if (s == DecodeStatus::kOk) {
          std::vector<uint8_t> resealed = d;
          Reseal(resealed);
          CHECK(resealed == d);  // the checksum matched after all
        }
      }
    }
  }
}
