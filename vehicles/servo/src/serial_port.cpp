#include "haptel/servo/serial_port.hpp"

#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <utility>

namespace haptel::servo {
namespace {

std::string Errno(int e) { return "errno " + std::to_string(e) + ", " + std::strerror(e); }

struct Baud {
  int rate;
  speed_t constant;
};
constexpr std::array<Baud, 11> kBauds = {{{1200, B1200},
                                          {2400, B2400},
                                          {4800, B4800},
                                          {9600, B9600},
                                          {19200, B19200},
                                          {38400, B38400},
                                          {57600, B57600},
                                          {115200, B115200},
                                          {230400, B230400},
                                          {460800, B460800},
                                          {921600, B921600}}};

std::string BaudList() {
  std::string out;
  for (const Baud& b : kBauds) out += (out.empty() ? "" : ", ") + std::to_string(b.rate);
  return out;
}

/// Whether the descriptor has hung up (its device gone, its other end closed).
bool HungUp(int fd) {
  pollfd p{fd, POLLIN, 0};
  return ::poll(&p, 1, 0) > 0 && (p.revents & (POLLHUP | POLLERR | POLLNVAL)) != 0;
}

[[noreturn]] void Lost(const std::string& name, const char* what, int e) {
  throw SerialLost(name + ": " + what + " failed (" + Errno(e) + "): the port is gone");
}

/// write(2) without blocking: bytes taken, 0 when the buffer is full.
size_t WriteFd(int fd, const uint8_t* data, size_t size, const std::string& name, bool socket) {
  if (size == 0) return 0;
  for (;;) {
    const ssize_t n =
        socket ? ::send(fd, data, size, MSG_DONTWAIT | MSG_NOSIGNAL) : ::write(fd, data, size);
    if (n >= 0) return static_cast<size_t>(n);
    const int e = errno;
    if (e == EINTR) continue;
    if (e == EAGAIN || e == EWOULDBLOCK) return 0;
    Lost(name, "write", e);
  }
}

/// read(2) without blocking: bytes read, 0 when none wait. End of file is
/// lost unless `zero_when_idle` (a terminal in a VMIN=0 mode reads 0 when
/// idle): then only a hang-up is.
size_t ReadFd(int fd, uint8_t* data, size_t size, const std::string& name, bool zero_when_idle) {
  if (size == 0) return 0;
  for (;;) {
    const ssize_t n = ::read(fd, data, size);
    if (n > 0) return static_cast<size_t>(n);
    if (n == 0) {
      if (zero_when_idle && !HungUp(fd)) return 0;
      throw SerialLost(name + ": the port hung up (end of file): the port is gone");
    }
    const int e = errno;
    if (e == EINTR) continue;
    if (e == EAGAIN || e == EWOULDBLOCK) return 0;
    Lost(name, "read", e);
  }
}

void SetCloseOnExec(int fd) { ::fcntl(fd, F_SETFD, ::fcntl(fd, F_GETFD) | FD_CLOEXEC); }
void SetNonBlocking(int fd) { ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK); }

/// Raw mode: no echo, no line editing, no translation, 8 bits, reads return
/// as soon as one byte is there.
bool MakeRaw(int fd, speed_t speed) {
  termios t{};
  if (::tcgetattr(fd, &t) < 0) return false;
  ::cfmakeraw(&t);
  t.c_cflag &= ~static_cast<tcflag_t>(CSIZE | PARENB | CSTOPB | CRTSCTS);
  t.c_cflag |= CS8 | CLOCAL | CREAD;
  t.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);
  t.c_cc[VMIN] = 1;
  t.c_cc[VTIME] = 0;
  if (speed != B0 && (::cfsetispeed(&t, speed) < 0 || ::cfsetospeed(&t, speed) < 0)) return false;
  return ::tcsetattr(fd, TCSANOW, &t) == 0;
}

}  // namespace

bool SerialBaudSupported(int baud) {
  for (const Baud& b : kBauds) {
    if (b.rate == baud) return true;
  }
  return false;
}

SerialPort::SerialPort(const std::string& path, int baud) : path_(path) {
  const std::string what = "serial port " + (path.empty() ? std::string("(no path)") : path);
  speed_t speed = B0;
  for (const Baud& b : kBauds) {
    if (b.rate == baud) speed = b.constant;
  }
  if (speed == B0) {
    throw SerialUnavailable(what + ": baud " + std::to_string(baud) +
                            " is not supported; expected one of " + BaudList());
  }
  if (path.empty())
    throw SerialUnavailable(what + ": no serial port given (set servo.port or --serial-port)");
  fd_.reset(::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC));
  if (!fd_) {
    const int e = errno;
    const char* hint = e == EACCES  ? " (is the user in the dialout group?)"
                       : e == EBUSY ? " (another program has it open)"
                                    : "";
    throw SerialUnavailable(what + ": cannot open (" + Errno(e) + ")" + hint);
  }
  termios probe{};
  if (::tcgetattr(fd_.get(), &probe) < 0) {
    const int e = errno;
    throw SerialUnavailable(what + ": not a serial port (tcgetattr: " + Errno(e) + ")");
  }
  // Exclusive: a second program opening the port fails with EBUSY instead
  // of interleaving its commands with ours.
  ::ioctl(fd_.get(), TIOCEXCL);
  if (!MakeRaw(fd_.get(), speed)) {
    const int e = errno;
    throw SerialUnavailable(what + ": cannot set raw 8N1 at " + std::to_string(baud) + " baud (" +
                            Errno(e) + ")");
  }
  ::tcflush(fd_.get(), TCIOFLUSH);
}

size_t SerialPort::Write(const uint8_t* data, size_t size) {
  return WriteFd(fd_.get(), data, size, path_, false);
}

size_t SerialPort::Read(uint8_t* data, size_t size) {
  return ReadFd(fd_.get(), data, size, path_, true);
}

FdStream::FdStream(UniqueFd fd, std::string name) : fd_(std::move(fd)), name_(std::move(name)) {
  if (!fd_) throw SerialUnavailable(name_ + ": no open descriptor");
  SetNonBlocking(fd_.get());
  struct stat st {};
  socket_ = ::fstat(fd_.get(), &st) == 0 && S_ISSOCK(st.st_mode);
}

size_t FdStream::Write(const uint8_t* data, size_t size) {
  return WriteFd(fd_.get(), data, size, name_, socket_);
}

size_t FdStream::Read(uint8_t* data, size_t size) {
  return ReadFd(fd_.get(), data, size, name_, false);
}

PtyPair::PtyPair() {
  int master = -1;
  int slave = -1;
  if (::openpty(&master, &slave, nullptr, nullptr, nullptr) < 0) {
    throw SerialUnavailable("pseudo-terminal: openpty failed (" + Errno(errno) + ")");
  }
  master_.reset(master);
  slave_.reset(slave);
  SetCloseOnExec(master);
  SetCloseOnExec(slave);
  SetNonBlocking(master);
  std::array<char, 128> name{};
  if (::ptsname_r(master, name.data(), name.size()) != 0) {
    throw SerialUnavailable("pseudo-terminal: ptsname failed (" + Errno(errno) + ")");
  }
  slave_path_ = name.data();
  // Termios ioctls on the master act on the slave's settings: both raw.
  if (!MakeRaw(slave, B0) || !MakeRaw(master, B0)) {
    throw SerialUnavailable("pseudo-terminal " + slave_path_ + ": cannot set raw mode (" +
                            Errno(errno) + ")");
  }
}

std::unique_ptr<ByteStream> PtyPair::TakeMaster() {
  if (!master_)
    throw SerialUnavailable("pseudo-terminal " + slave_path_ + ": the master end is already taken");
  return std::make_unique<FdStream>(std::move(master_), "pty master " + slave_path_);
}

}  // namespace haptel::servo
