#include "haptel/udp/udp_protocol.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

namespace haptel::haptics::udp {

namespace {

// Header offsets (PROTOCOL.md, "Header").
constexpr std::size_t kOffMagic = 0;
constexpr std::size_t kOffVersion = 4;
constexpr std::size_t kOffType = 6;
constexpr std::size_t kOffSequence = 8;
constexpr std::size_t kOffLength = 12;
constexpr std::size_t kOffSide = 16;
constexpr std::size_t kOffReserved = 17;  // 3 bytes, zero
constexpr std::size_t kOffChecksum = 20;
static_assert(kOffChecksum + 4 == kHeaderSize);
static_assert(std::variant_size_v<Payload> == 7);

constexpr std::array<uint32_t, 256> MakeCrcTable() {
  std::array<uint32_t, 256> table{};
  for (uint32_t i = 0; i < 256; ++i) {
    uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1U) != 0 ? 0xEDB88320U ^ (c >> 1) : c >> 1;
    table[i] = c;
  }
  return table;
}
constexpr std::array<uint32_t, 256> kCrcTable = MakeCrcTable();

/// Bounds-checked little-endian writer over a span: the caller checks the
/// total size first, so every Put stays inside.
class Writer {
 public:
  explicit Writer(std::span<uint8_t> out) : out_(out) {}
  void U8(uint8_t v) { out_[pos_++] = v; }
  void U16(uint16_t v) {
    for (int i = 0; i < 2; ++i) out_[pos_++] = static_cast<uint8_t>(v >> (8 * i));
  }
  void U32(uint32_t v) {
    for (int i = 0; i < 4; ++i) out_[pos_++] = static_cast<uint8_t>(v >> (8 * i));
  }
  void U64(uint64_t v) {
    for (int i = 0; i < 8; ++i) out_[pos_++] = static_cast<uint8_t>(v >> (8 * i));
  }
  void I64(int64_t v) { U64(static_cast<uint64_t>(v)); }
  void F64(double v) { U64(std::bit_cast<uint64_t>(v)); }
  template <std::size_t N>
  void F64s(const std::array<double, N>& values) {
    for (double v : values) F64(v);
  }
  std::size_t pos() const { return pos_; }

 private:
  std::span<uint8_t> out_;
  std::size_t pos_ = 0;
};

/// Little-endian reader over a span whose size the caller has checked.
class Reader {
 public:
  explicit Reader(std::span<const uint8_t> in) : in_(in) {}
  uint8_t U8() { return in_[pos_++]; }
  uint16_t U16() {
    uint16_t v = 0;
    for (int i = 0; i < 2; ++i)
      v = static_cast<uint16_t>(v | (static_cast<uint16_t>(in_[pos_++]) << (8 * i)));
    return v;
  }
  uint32_t U32() {
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<uint32_t>(in_[pos_++]) << (8 * i);
    return v;
  }
  uint64_t U64() {
    uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= static_cast<uint64_t>(in_[pos_++]) << (8 * i);
    return v;
  }
  int64_t I64() { return static_cast<int64_t>(U64()); }
  /// Reads a double; clears `finite` when it is NaN or infinite.
  double F64(bool& finite) {
    const double v = std::bit_cast<double>(U64());
    if (!std::isfinite(v)) finite = false;
    return v;
  }
  template <std::size_t N>
  void F64s(std::array<double, N>& values, bool& finite) {
    for (double& v : values) v = F64(finite);
  }

 private:
  std::span<const uint8_t> in_;
  std::size_t pos_ = 0;
};

template <std::size_t N>
bool AllFinite(const std::array<double, N>& values) {
  for (double v : values) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

template <std::size_t N>
bool AllNonNegative(const std::array<double, N>& values) {
  for (double v : values) {
    if (!(v >= 0.0)) return false;
  }
  return true;
}

bool UnitQuaternion(const std::array<double, 4>& q) {
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  return std::abs(norm - 1.0) <= kQuaternionNormTolerance;
}

bool KnownErrorCode(ErrorCode code) {
  const auto c = static_cast<uint16_t>(code);
  return c >= 1 && c < kErrorCodes;
}

/// The energy report's doubles, in wire order.
std::array<double, 8> ReportDoubles(const EnergyReport& e) {
  return {e.energy_in[0], e.energy_in[1], e.energy_in[2], e.charged[0],
          e.charged[1],   e.charged[2],   e.dissipated_j, e.max_alpha};
}

/// An energy report Decode would accept: finite, none negative (they are
/// counters of energy and damping). Only checked where the version carries it.
bool ValidReport(const EnergyReport& e) {
  const std::array<double, 8> v = ReportDoubles(e);
  return AllFinite(v) && AllNonNegative(v);
}

/// Whether a payload would be accepted by Decode (finite, in its domain) in `version`.
bool Valid(const Payload& payload, uint16_t version) {
  const bool v2 = version >= 2;
  struct {
    bool v2;
    bool operator()(const WristRequest& p) const {
      return AllFinite(p.wrist_force) && AllFinite(p.finger_forces) &&
             AllNonNegative(p.finger_forces) && (!v2 || ValidReport(p.energy));
    }
    bool operator()(const WristReply& p) const {
      return AllFinite(p.position) && AllFinite(p.orientation) && UnitQuaternion(p.orientation) &&
             (!v2 || ValidReport(p.energy));
    }
    bool operator()(const GloveRequest&) const { return true; }
    bool operator()(const GloveReply& p) const {
      return AllFinite(p.sensors) && AllFinite(p.grasp);
    }
    bool operator()(const WristForce& p) const {
      return AllFinite(p.command) && (!v2 || ValidReport(p.energy));
    }
    bool operator()(const FingerForce& p) const {
      return AllFinite(p.command) && AllNonNegative(p.command);
    }
    bool operator()(const ErrorReply& p) const { return KnownErrorCode(p.code); }
  } check{v2};
  return std::visit(check, payload);
}

constexpr uint32_t kReportActive = 1U;  ///< flags bit 0; the other bits are reserved, zero

void WriteReport(Writer& w, const EnergyReport& e) {
  w.U32(e.active ? kReportActive : 0U);
  w.U32(e.epoch);
  w.F64s(e.energy_in);
  w.F64s(e.charged);
  w.F64(e.dissipated_j);
  w.U64(e.acted_ticks);
  w.F64(e.max_alpha);
}

/// Reads an energy report; kOk, kNonFinite or kBadValue (reserved flags, a negative value).
DecodeStatus ReadReport(Reader& r, EnergyReport& e) {
  bool finite = true;
  const uint32_t flags = r.U32();
  e.epoch = r.U32();
  r.F64s(e.energy_in, finite);
  r.F64s(e.charged, finite);
  e.dissipated_j = r.F64(finite);
  e.acted_ticks = r.U64();
  e.max_alpha = r.F64(finite);
  e.active = (flags & kReportActive) != 0;
  if (!finite) return DecodeStatus::kNonFinite;
  if ((flags & ~kReportActive) != 0 || !AllNonNegative(ReportDoubles(e)))
    return DecodeStatus::kBadValue;
  return DecodeStatus::kOk;
}

void WritePayload(Writer& w, const Payload& payload, uint16_t version) {
  struct {
    Writer& w;
    bool v2;
    void operator()(const WristRequest& p) const {
      w.F64s(p.wrist_force);
      w.F64s(p.finger_forces);
      if (v2) WriteReport(w, p.energy);
    }
    void operator()(const WristReply& p) const {
      w.I64(p.device_ns);
      w.F64s(p.position);
      w.F64s(p.orientation);
      if (v2) WriteReport(w, p.energy);
    }
    void operator()(const GloveRequest&) const {}
    void operator()(const GloveReply& p) const {
      w.I64(p.device_ns);
      w.F64s(p.sensors);
      w.F64s(p.grasp);
    }
    void operator()(const WristForce& p) const {
      w.F64s(p.command);
      if (v2) WriteReport(w, p.energy);
    }
    void operator()(const FingerForce& p) const { w.F64s(p.command); }
    void operator()(const ErrorReply& p) const {
      w.U16(static_cast<uint16_t>(p.code));
      w.U16(0);  // reserved
    }
  } write{w, version >= 2};
  std::visit(write, payload);
}

/// Reads the payload of a known type whose size has been checked.
DecodeStatus ReadPayload(MessageType type, uint16_t version, Reader& r, Payload& out) {
  bool finite = true;
  const bool v2 = version >= 2;
  switch (type) {
    case MessageType::kWristRequest: {
      WristRequest p;
      r.F64s(p.wrist_force, finite);
      r.F64s(p.finger_forces, finite);
      const DecodeStatus report = v2 ? ReadReport(r, p.energy) : DecodeStatus::kOk;
      if (!finite || report == DecodeStatus::kNonFinite) return DecodeStatus::kNonFinite;
      if (!AllNonNegative(p.finger_forces) || report != DecodeStatus::kOk)
        return DecodeStatus::kBadValue;
      out = p;
      return DecodeStatus::kOk;
    }
    case MessageType::kWristReply: {
      WristReply p;
      p.device_ns = r.I64();
      r.F64s(p.position, finite);
      r.F64s(p.orientation, finite);
      const DecodeStatus report = v2 ? ReadReport(r, p.energy) : DecodeStatus::kOk;
      if (!finite || report == DecodeStatus::kNonFinite) return DecodeStatus::kNonFinite;
      if (!UnitQuaternion(p.orientation) || report != DecodeStatus::kOk)
        return DecodeStatus::kBadValue;
      out = p;
      return DecodeStatus::kOk;
    }
    case MessageType::kGloveRequest:
      out = GloveRequest{};
      return DecodeStatus::kOk;
    case MessageType::kGloveReply: {
      GloveReply p;
      p.device_ns = r.I64();
      r.F64s(p.sensors, finite);
      r.F64s(p.grasp, finite);
      if (!finite) return DecodeStatus::kNonFinite;
      out = p;
      return DecodeStatus::kOk;
    }
    case MessageType::kWristForce: {
      WristForce p;
      r.F64s(p.command, finite);
      const DecodeStatus report = v2 ? ReadReport(r, p.energy) : DecodeStatus::kOk;
      if (!finite || report == DecodeStatus::kNonFinite) return DecodeStatus::kNonFinite;
      if (report != DecodeStatus::kOk) return DecodeStatus::kBadValue;
      out = p;
      return DecodeStatus::kOk;
    }
    case MessageType::kFingerForce: {
      FingerForce p;
      r.F64s(p.command, finite);
      if (!finite) return DecodeStatus::kNonFinite;
      if (!AllNonNegative(p.command)) return DecodeStatus::kBadValue;
      out = p;
      return DecodeStatus::kOk;
    }
    case MessageType::kError: {
      ErrorReply p;
      p.code = static_cast<ErrorCode>(r.U16());
      const uint16_t reserved = r.U16();
      if (!KnownErrorCode(p.code) || reserved != 0) return DecodeStatus::kBadValue;
      out = p;
      return DecodeStatus::kOk;
    }
  }
  return DecodeStatus::kUnknownType;
}

/// CRC of a datagram with its checksum field taken as zero.
uint32_t DatagramCrc(std::span<const uint8_t> datagram) {
  constexpr std::array<uint8_t, 4> kZero{};
  uint32_t crc = Crc32(datagram.first(kOffChecksum));
  crc = Crc32(kZero, crc);
  return Crc32(datagram.subspan(kHeaderSize), crc);
}

}  // namespace

std::string_view ToString(DecodeStatus status) {
  switch (status) {
    case DecodeStatus::kOk:
      return "ok";
    case DecodeStatus::kShort:
      return "short";
    case DecodeStatus::kBadMagic:
      return "bad_magic";
    case DecodeStatus::kBadVersion:
      return "bad_version";
    case DecodeStatus::kBadLength:
      return "bad_length";
    case DecodeStatus::kBadChecksum:
      return "bad_checksum";
    case DecodeStatus::kUnknownType:
      return "unknown_type";
    case DecodeStatus::kBadHeader:
      return "bad_header";
    case DecodeStatus::kNonFinite:
      return "non_finite";
    case DecodeStatus::kBadValue:
      return "bad_value";
  }
  return "?";
}

std::string_view ToString(MessageType type) {
  switch (type) {
    case MessageType::kWristRequest:
      return "WRIST_REQUEST";
    case MessageType::kWristReply:
      return "WRIST_REPLY";
    case MessageType::kGloveRequest:
      return "GLOVE_REQUEST";
    case MessageType::kGloveReply:
      return "GLOVE_REPLY";
    case MessageType::kWristForce:
      return "WRIST_FORCE";
    case MessageType::kFingerForce:
      return "FINGER_FORCE";
    case MessageType::kError:
      return "ERROR";
  }
  return "?";
}

std::string_view ToString(ErrorCode code) {
  switch (code) {
    case ErrorCode::kBusy:
      return "busy";
    case ErrorCode::kWrongSide:
      return "wrong_side";
    case ErrorCode::kDeviceLost:
      return "device_lost";
    case ErrorCode::kUnsupported:
      return "unsupported";
  }
  return "?";
}

EnergyReport Merge(const EnergyReport& held, const EnergyReport& arrived) {
  if (arrived.epoch != held.epoch) return arrived;
  EnergyReport m = arrived;
  for (int i = 0; i < 3; ++i) {
    m.energy_in[i] = std::max(held.energy_in[i], arrived.energy_in[i]);
    m.charged[i] = std::max(held.charged[i], arrived.charged[i]);
  }
  m.dissipated_j = std::max(held.dissipated_j, arrived.dissipated_j);
  m.acted_ticks = std::max(held.acted_ticks, arrived.acted_ticks);
  m.max_alpha = std::max(held.max_alpha, arrived.max_alpha);
  return m;
}

std::size_t PayloadSize(MessageType type, uint16_t version) {
  if (version < kMinVersion || version > kVersion) return 0;
  const std::size_t report = version >= 2 ? kEnergyReportSize : 0;
  switch (type) {
    case MessageType::kWristRequest:
      return kWristRequestSize + report;
    case MessageType::kWristReply:
      return kWristReplySize + report;
    case MessageType::kGloveRequest:
      return kGloveRequestSize;
    case MessageType::kGloveReply:
      return kGloveReplySize;
    case MessageType::kWristForce:
      return kWristForceSize + report;
    case MessageType::kFingerForce:
      return kFingerForceSize;
    case MessageType::kError:
      return kErrorReplySize;
  }
  return 0;
}

uint32_t Crc32(std::span<const uint8_t> bytes, uint32_t crc) {
  crc = ~crc;
  for (uint8_t b : bytes) crc = kCrcTable[(crc ^ b) & 0xFFU] ^ (crc >> 8);
  return ~crc;
}

std::size_t Encode(const Message& message, std::span<uint8_t> out) {
  const MessageType type = message.type();
  if (message.version < kMinVersion || message.version > kVersion) return 0;
  const std::size_t payload_size = PayloadSize(type, message.version);
  const std::size_t total = kHeaderSize + payload_size;
  if (out.size() < total || !Valid(message.payload, message.version)) return 0;
  if (message.side != Side::kLeft && message.side != Side::kRight) return 0;
  Writer w(out);
  for (uint8_t b : kMagic) w.U8(b);
  w.U16(message.version);
  w.U16(static_cast<uint16_t>(type));
  w.U32(message.sequence);
  w.U32(static_cast<uint32_t>(payload_size));
  w.U8(static_cast<uint8_t>(Index(message.side)));
  for (int i = 0; i < 3; ++i) w.U8(0);  // reserved
  w.U32(0);                             // checksum, filled in below
  WritePayload(w, message.payload, message.version);
  const std::span<uint8_t> datagram = out.first(total);
  const uint32_t crc = DatagramCrc(datagram);
  for (int i = 0; i < 4; ++i) datagram[kOffChecksum + i] = static_cast<uint8_t>(crc >> (8 * i));
  return total;
}

DecodeStatus Decode(std::span<const uint8_t> datagram, Message& out) {
  if (datagram.size() < kHeaderSize) return DecodeStatus::kShort;
  Reader h(datagram);
  for (uint8_t b : kMagic) {
    if (h.U8() != b) return DecodeStatus::kBadMagic;
  }
  const uint16_t version = h.U16();
  const uint16_t raw_type = h.U16();
  const uint32_t sequence = h.U32();
  const uint32_t length = h.U32();
  const uint8_t side = h.U8();
  const uint8_t reserved[3] = {h.U8(), h.U8(), h.U8()};
  const uint32_t checksum = h.U32();
  if (version < kMinVersion || version > kVersion) return DecodeStatus::kBadVersion;
  if (length > kMaxPayloadSize) return DecodeStatus::kBadLength;
  if (datagram.size() < kHeaderSize + length) return DecodeStatus::kShort;
  if (datagram.size() > kHeaderSize + length) return DecodeStatus::kBadLength;
  if (DatagramCrc(datagram) != checksum) return DecodeStatus::kBadChecksum;
  if (side > 1 || reserved[0] != 0 || reserved[1] != 0 || reserved[2] != 0)
    return DecodeStatus::kBadHeader;
  const auto type = static_cast<MessageType>(raw_type);
  if (raw_type < 1 || raw_type > std::variant_size_v<Payload>) {
    out.sequence = sequence;  // the header is sound: a server may answer kUnsupported
    out.side = static_cast<Side>(side);
    return DecodeStatus::kUnknownType;
  }
  if (length != PayloadSize(type, version)) return DecodeStatus::kBadLength;
  Reader p(datagram.subspan(kHeaderSize));
  Payload payload;
  const DecodeStatus status = ReadPayload(type, version, p, payload);
  if (status != DecodeStatus::kOk) return status;
  out.version = version;
  out.sequence = sequence;
  out.side = static_cast<Side>(side);
  out.payload = payload;
  return DecodeStatus::kOk;
}

}  // namespace haptel::haptics::udp
