#pragma once
/// @file A byte stream to a servo controller: a real serial port (a USB
/// CDC-ACM or USB-serial device), any open descriptor, or a pseudo-terminal
/// pair whose master end plays the controller (the simulated blimp and the
/// tests: everything above the stream is the same code either way).
///
/// Reads and writes never block. Set-up errors throw SerialUnavailable (bad
/// input, exit 2); a port that goes away while in use throws SerialLost
/// (the vehicle node's exit 3).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

#include "haptel/core/cli.hpp"
#include "haptel/core/unique_fd.hpp"

namespace haptel::servo {

/// The port cannot be opened or configured: no such device, no permission,
/// in use, not a serial port, an unsupported baud rate. One line naming the
/// path and the reason.
class SerialUnavailable : public cli::InputError {
 public:
  using cli::InputError::InputError;
};

/// The port went away while in use (the device unplugged, the pty's other
/// end closed): a read or write failed with EIO, ENXIO, EBADF and the like,
/// or the port hung up.
class SerialLost : public cli::HardwareLost {
 public:
  using cli::HardwareLost::HardwareLost;
};

/// The shared file descriptor owner (core/unique_fd.hpp).
using UniqueFd = haptel::UniqueFd;

class ByteStream {
 public:
  virtual ~ByteStream() = default;
  /// Queues up to `size` bytes; returns how many were taken (0 when the
  /// output buffer is full). Never blocks. Throws SerialLost.
  virtual size_t Write(const uint8_t* data, size_t size) = 0;
  /// Up to `size` waiting bytes; 0 when none. Never blocks. Throws SerialLost.
  virtual size_t Read(uint8_t* data, size_t size) = 0;
  /// "/dev/ttyACM0", "pty master /dev/pts/3"
  virtual std::string name() const = 0;
};

/// The serial baud rates a SerialPort can set.
bool SerialBaudSupported(int baud);

/// A serial device opened O_RDWR | O_NOCTTY | O_NONBLOCK, exclusive
/// (TIOCEXCL), raw (cfmakeraw), 8N1, `baud`, CLOCAL | CREAD, no flow
/// control, its buffers flushed. Throws SerialUnavailable with the path and
/// the reason, e.g. "serial port /dev/ttyACM0: cannot open (errno 2, No
/// such file or directory)".
class SerialPort final : public ByteStream {
 public:
  SerialPort(const std::string& path, int baud);
  size_t Write(const uint8_t* data, size_t size) override;
  size_t Read(uint8_t* data, size_t size) override;
  std::string name() const override { return path_; }

 private:
  std::string path_;
  UniqueFd fd_;
};

/// A stream over an already-open descriptor (a pipe, a socket, a pty's
/// master end), which it owns and makes non-blocking. End of file counts
/// as lost. Over a socket writes never raise SIGPIPE; over a pipe whose
/// reader has gone they do, as any write does, unless it is ignored.
class FdStream final : public ByteStream {
 public:
  FdStream(UniqueFd fd, std::string name);
  size_t Write(const uint8_t* data, size_t size) override;
  size_t Read(uint8_t* data, size_t size) override;
  std::string name() const override { return name_; }

 private:
  UniqueFd fd_;
  std::string name_;
  bool socket_ = false;
};

/// A pseudo-terminal pair (openpty), both ends raw: the master end plays
/// the device, and the slave's path is the "serial port" the adapter opens.
/// The simulated blimp (config sim-blimp-maestro) runs the real adapter on
/// the slave and the simulated controller on the master.
///
/// The pair keeps its own slave descriptor open until CloseSlave(): while
/// it is, the master never sees a hang-up, even when the adapter closes
/// the port and reopens it. Throws SerialUnavailable when no pty is to be had.
class PtyPair {
 public:
  PtyPair();

  /// "/dev/pts/N": open this with SerialPort.
  const std::string& slave_path() const { return slave_path_; }
  /// The master end's descriptor (non-blocking); -1 once taken or closed.
  int master_fd() const { return master_.get(); }
  /// Our slave descriptor; -1 once closed.
  int slave_fd() const { return slave_.get(); }

  /// The master end as a stream (the controller's side); master_fd() is -1 after.
  std::unique_ptr<ByteStream> TakeMaster();
  /// Closes our slave descriptor, leaving the slave to whoever opened
  /// slave_path() (once no one holds it, reading the master fails: lost).
  void CloseSlave() { slave_.reset(); }
  /// Closes the master end: the device unplugged. Every open slave
  /// descriptor hangs up, so a SerialPort on it throws SerialLost.
  void CloseMaster() { master_.reset(); }

 private:
  UniqueFd master_;
  UniqueFd slave_;
  std::string slave_path_;
};

}  // namespace haptel::servo
