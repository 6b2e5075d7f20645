#pragma once
/// @file The UDP device protocol's wire format (haptics/udp/PROTOCOL.md): a fixed
/// little-endian 24-byte header — magic, version, type, sequence, payload
/// length, side, CRC-32 — followed by a fixed-size payload per message type.
///
/// Encode and Decode work on caller-provided buffers, never allocate, never
/// throw and never read or write outside the spans they are given. Decode
/// trusts nothing: a datagram is accepted only when its size, magic, version,
/// length, checksum, type, side, reserved bytes and every payload value check
/// out; otherwise it returns the first check that failed.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <variant>

#include "haptel/haptics/types.hpp"

namespace haptel::haptics::udp {

/// "HPTL" in the first four bytes of every datagram.
inline constexpr std::array<uint8_t, 4> kMagic{'H', 'P', 'T', 'L'};
/// The newest protocol version this code speaks (and sends unless told
/// otherwise). Version 2 adds each end's two-port energy report (EnergyReport)
/// to WRIST_REQUEST, WRIST_FORCE and WRIST_REPLY; everything else is as in 1.
inline constexpr uint16_t kVersion = 2;
/// The oldest version this code still speaks: a v1 peer still works (without
/// the energy reports). Datagrams of any other version are kBadVersion.
inline constexpr uint16_t kMinVersion = 1;
inline constexpr std::size_t kHeaderSize = 24;

enum class MessageType : uint16_t {
  kWristRequest = 1,  ///< client → server: read the wrist; carries the current force commands
  kWristReply = 2,    ///< server → client: wrist pose and device time
  kGloveRequest = 3,  ///< client → server: read glove sensors and grasp strings
  kGloveReply = 4,    ///< server → client: 22 glove sensors, 5 grasp values, device time
  kWristForce = 5,    ///< client → server, one-way: wrist force command
  kFingerForce = 6,   ///< client → server, one-way: finger force commands
  kError = 7,         ///< server → client: the request was understood but not served
};

/// Why a server did not serve a well-formed request.
enum class ErrorCode : uint16_t {
  kBusy = 1,         ///< another client holds this arm
  kWrongSide = 2,    ///< the request names the arm this server does not serve
  kDeviceLost = 3,   ///< the arm behind the server stopped answering
  kUnsupported = 4,  ///< a message type this server does not serve
};
inline constexpr int kErrorCodes = 5;  ///< array size for per-code counters (index 0 unused)

/// Result of Decode, in the order the checks are made.
enum class DecodeStatus : uint8_t {
  kOk = 0,
  kShort,        ///< fewer bytes than the header, or than header + payload length
  kBadMagic,     ///< not "HPTL"
  kBadVersion,   ///< another protocol version
  kBadLength,    ///< payload length too big, trailing bytes, or not the type's size
  kBadChecksum,  ///< CRC-32 mismatch
  kBadHeader,    ///< side not 0/1, or reserved bytes not zero
  kUnknownType,  ///< a type this version does not define (sequence and side still filled in)
  kNonFinite,    ///< a NaN or infinity in a payload double
  kBadValue,     ///< a finite value out of its domain (negative finger force,
                 ///< non-unit quaternion, unknown error code, reserved payload bytes)
};
inline constexpr int kDecodeStatuses = 10;
std::string_view ToString(DecodeStatus status);
std::string_view ToString(MessageType type);
std::string_view ToString(ErrorCode code);

// --- Payloads (device units, as the Device interface carries them). ---

/// Version 2: one end's two-port passivity report (haptel/haptics/twoport.hpp),
/// in SI (J, N·s/m), per axis of the arm. Every quantity is a monotone counter
/// within an epoch, so the newest report supersedes every older one and a
/// lost or reordered datagram costs nothing: a receiver keeps the per-field
/// maximum (Merge). The client owns the epoch: it starts a new one when its
/// end restarts (device lost, controller reset); the server, seeing a new
/// epoch, restarts its end too and echoes it, so both ends count from zero
/// together. 80 bytes on the wire (PROTOCOL.md).
struct EnergyReport {
  bool active = false;        ///< this end runs its observer; when false the rest means nothing
  uint32_t epoch = 0;         ///< set by the client; the server echoes the client's
  Vec3d energy_in{};          ///< J per axis: what entered the channel at this end (E_in), ≥ 0
  Vec3d charged{};            ///< J per axis: deficit this end could not dissipate itself, ≥ 0
  double dissipated_j = 0.0;  ///< J, this end's controller over all axes, ≥ 0
  uint64_t acted_ticks = 0;   ///< ticks this end's controller acted
  double max_alpha = 0.0;     ///< the largest damping (N·s/m) this end's controller added, ≥ 0
};

/// `held` brought up to date by `arrived` of the same epoch (per-field
/// maximum: the counters are monotone); an arrived report of another epoch
/// replaces it whole.
EnergyReport Merge(const EnergyReport& held, const EnergyReport& arrived);

struct WristRequest {
  Vec3d wrist_force{};                           ///< command in force now
  std::array<double, kFingers> finger_forces{};  ///< commands in force now, each ≥ 0
  EnergyReport energy{};                         ///< version 2 only: the loop's end
};
struct WristReply {
  int64_t device_ns = 0;  ///< the server's clock (not comparable with the client's)
  Vec3d position{};
  std::array<double, 4> orientation{1, 0, 0, 0};  ///< unit quaternion (w, x, y, z)
  EnergyReport energy{};                          ///< version 2 only: the device's end
};
struct GloveRequest {};
struct GloveReply {
  int64_t device_ns = 0;
  std::array<double, kGloveJoints> sensors{};
  std::array<double, kFingers> grasp{};
};
struct WristForce {
  Vec3d command{};
  EnergyReport energy{};  ///< version 2 only: the loop's end
};
struct FingerForce {
  std::array<double, kFingers> command{};  ///< each ≥ 0
};
struct ErrorReply {
  ErrorCode code = ErrorCode::kUnsupported;
};

/// Alternative order matches MessageType − 1.
using Payload = std::variant<WristRequest, WristReply, GloveRequest, GloveReply, WristForce,
                             FingerForce, ErrorReply>;

struct Message {
  uint32_t sequence = 0;
  Side side = Side::kLeft;
  Payload payload;
  /// kMinVersion…kVersion. Encode writes it (a version-1 message leaves the
  /// energy reports out); Decode sets it from the header.
  uint16_t version = kVersion;
  MessageType type() const { return static_cast<MessageType>(payload.index() + 1); }
};

/// Payload sizes in bytes, fixed per type and version (version 1's; version
/// 2 adds kEnergyReportSize to WRIST_REQUEST, WRIST_REPLY and WRIST_FORCE).
inline constexpr std::size_t kEnergyReportSize = 4 + 4 + 6 * 8 + 8 + 8 + 8;
inline constexpr std::size_t kWristRequestSize = 8 * 8;
inline constexpr std::size_t kWristReplySize = 8 + 7 * 8;
inline constexpr std::size_t kGloveRequestSize = 0;
inline constexpr std::size_t kGloveReplySize = 8 + (kGloveJoints + kFingers) * 8;
inline constexpr std::size_t kWristForceSize = 3 * 8;
inline constexpr std::size_t kFingerForceSize = kFingers * 8;
inline constexpr std::size_t kErrorReplySize = 4;
inline constexpr std::size_t kMaxPayloadSize = kGloveReplySize;
inline constexpr std::size_t kMaxMessageSize = kHeaderSize + kMaxPayloadSize;

/// A buffer any message fits in.
using Buffer = std::array<uint8_t, kMaxMessageSize>;

/// Payload size of a type in `version`; 0 for an unknown type or version
/// (and for kGloveRequest).
std::size_t PayloadSize(MessageType type, uint16_t version = kVersion);

/// A quaternion is accepted when | |q| − 1 | ≤ this.
inline constexpr double kQuaternionNormTolerance = 1e-3;

/// Writes `message` into `out`; returns the datagram's size, or 0 (nothing
/// usable written) when `out` is too small or a value would not decode
/// (non-finite, negative finger force, non-unit quaternion).
std::size_t Encode(const Message& message, std::span<uint8_t> out);

/// Parses one datagram. `out` is written only on kOk, except that on
/// kUnknownType `out.sequence` and `out.side` are set (the header is sound,
/// so a server may answer ERROR kUnsupported to that sequence).
DecodeStatus Decode(std::span<const uint8_t> datagram, Message& out);

/// CRC-32 (IEEE 802.3, reflected, as zlib's crc32): `crc` is a previous
/// result to continue from (0 to start).
uint32_t Crc32(std::span<const uint8_t> bytes, uint32_t crc = 0);

/// Serial-number order (RFC 1982): true when `a` is after `b`, modulo 2³².
constexpr bool SequenceAfter(uint32_t a, uint32_t b) {
  return a != b && static_cast<int32_t>(a - b) > 0;
}

}  // namespace haptel::haptics::udp
