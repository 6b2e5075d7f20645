#pragma once
/// @file A CAN bus as the robot's adapter sees it: classic frames
/// (`struct can_frame`, 16 bytes) sent and received without blocking.
///
/// SocketCanBus is the real one (PF_CAN, SOCK_RAW, bound to an interface,
/// error frames on). A socket pair (AF_UNIX, SOCK_SEQPACKET) carries the same
/// 16-byte frames, one per packet, between the adapter and a simulated bus's
/// nodes (the simulated CAN robot, tests): everything above the bus is the
/// same code either way.
#include <linux/can.h>
#include <linux/can/error.h>

#include <cstdint>
#include <memory>
#include <string>
#include <utility>

#include "haptel/core/cli.hpp"

namespace haptel::vehicles {

/// The bus cannot be opened: no CAN support in the kernel, no such
/// interface. A set-up error (exit 2), one line.
class CanUnavailable : public cli::InputError {
 public:
  using cli::InputError::InputError;
};

/// The bus went away while in use (interface down, socket closed).
class CanBusLost : public cli::HardwareLost {
 public:
  using cli::HardwareLost::HardwareLost;
};

class CanBus {
 public:
  virtual ~CanBus() = default;
  /// Queues one frame; false when the bus's buffer is full (counted by the caller).
  virtual bool Send(const can_frame& frame) = 0;
  /// The next received frame, if one is waiting (never blocks). Throws
  /// CanBusLost when the bus is gone.
  virtual bool Receive(can_frame& frame) = 0;
  /// "can0", "socketpair"
  virtual std::string name() const = 0;
};

/// A raw SocketCAN socket bound to `interface`, with every error class
/// delivered as error frames (CAN_RAW_ERR_FILTER). Throws CanUnavailable with
/// the reason, e.g. "the kernel has no CAN support (socket(PF_CAN) failed:
/// errno 97, Address family not supported by protocol)".
class SocketCanBus final : public CanBus {
 public:
  explicit SocketCanBus(const std::string& interface);
  ~SocketCanBus() override;
  SocketCanBus(const SocketCanBus&) = delete;
  SocketCanBus& operator=(const SocketCanBus&) = delete;
  bool Send(const can_frame& frame) override;
  bool Receive(can_frame& frame) override;
  std::string name() const override { return interface_; }

 private:
  std::string interface_;
  int fd_ = -1;
};

/// One end of a socket pair carrying can_frames.
class SocketPairBus final : public CanBus {
 public:
  explicit SocketPairBus(int fd);
  ~SocketPairBus() override;
  SocketPairBus(const SocketPairBus&) = delete;
  SocketPairBus& operator=(const SocketPairBus&) = delete;
  bool Send(const can_frame& frame) override;
  bool Receive(can_frame& frame) override;
  std::string name() const override { return "socketpair"; }

 private:
  int fd_ = -1;
};

/// Two connected ends: what one sends, the other receives.
std::pair<std::unique_ptr<CanBus>, std::unique_ptr<CanBus>> MakeSocketPairBus();

/// A data frame with an 11-bit id and `len` bytes of `data`.
can_frame MakeFrame(uint32_t id, const uint8_t* data, uint8_t len);

}  // namespace haptel::vehicles
