#include "haptel/vehicles/can_bus.hpp"

#include <fcntl.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace haptel::vehicles {
namespace {

std::string Errno(int e) { return "errno " + std::to_string(e) + ", " + std::strerror(e); }

bool SendPacket(int fd, const can_frame& frame) {
  const ssize_t n = ::send(fd, &frame, sizeof frame, MSG_DONTWAIT | MSG_NOSIGNAL);
  if (n == static_cast<ssize_t>(sizeof frame)) return true;
  if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == ENOBUFS)) return false;
  throw CanBusLost("CAN bus: send failed (" + Errno(errno) + ")");
}

bool ReceivePacket(int fd, can_frame& frame) {
  for (;;) {
    const ssize_t n = ::recv(fd, &frame, sizeof frame, MSG_DONTWAIT);
    if (n == static_cast<ssize_t>(sizeof frame)) return true;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return false;
    if (n < 0 && errno == EINTR) continue;
    if (n == 0) throw CanBusLost("CAN bus: the other end closed");
    if (n < 0) throw CanBusLost("CAN bus: receive failed (" + Errno(errno) + ")");
    // A short packet is not a frame: dropped here, the next one is read.
  }
}

}  // namespace

SocketCanBus::SocketCanBus(const std::string& interface) : interface_(interface) {
  fd_ = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (fd_ < 0) {
    const int e = errno;
    if (e == EAFNOSUPPORT) {
      throw CanUnavailable("CAN interface " + interface +
                           ": the kernel has no CAN support (socket(PF_CAN) failed: " + Errno(e) +
                           "); load the can and can_raw modules");
    }
    throw CanUnavailable("CAN interface " + interface + ": socket(PF_CAN) failed (" + Errno(e) +
                         ")");
  }
  ifreq request{};
  std::strncpy(request.ifr_name, interface.c_str(), IFNAMSIZ - 1);
  if (::ioctl(fd_, SIOCGIFINDEX, &request) < 0) {
    const int e = errno;
    ::close(fd_);
    throw CanUnavailable("CAN interface " + interface + ": no such interface (" + Errno(e) + ")");
  }
  // Every error class as error frames: bus-off, error-passive, restarts.
  const can_err_mask_t errors = CAN_ERR_MASK;
  ::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errors, sizeof errors);
  sockaddr_can address{};
  address.can_family = AF_CAN;
  address.can_ifindex = request.ifr_ifindex;
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) < 0) {
    const int e = errno;
    ::close(fd_);
    throw CanUnavailable("CAN interface " + interface + ": bind failed (" + Errno(e) + ")");
  }
}

SocketCanBus::~SocketCanBus() {
  if (fd_ >= 0) ::close(fd_);
}

bool SocketCanBus::Send(const can_frame& frame) { return SendPacket(fd_, frame); }
bool SocketCanBus::Receive(can_frame& frame) { return ReceivePacket(fd_, frame); }

SocketPairBus::SocketPairBus(int fd) : fd_(fd) {}
SocketPairBus::~SocketPairBus() {
  if (fd_ >= 0) ::close(fd_);
}
bool SocketPairBus::Send(const can_frame& frame) { return SendPacket(fd_, frame); }
bool SocketPairBus::Receive(can_frame& frame) { return ReceivePacket(fd_, frame); }

std::pair<std::unique_ptr<CanBus>, std::unique_ptr<CanBus>> MakeSocketPairBus() {
  int fds[2] = {-1, -1};
  if (::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, fds) < 0) {
    throw std::runtime_error("CAN socket pair: " + Errno(errno));
  }
  // Room for a burst of frames (a 16-byte frame costs far more in skb overhead).
  const int buffer = 1 << 20;
  for (const int fd : fds) {
    ::setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &buffer, sizeof buffer);
    ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &buffer, sizeof buffer);
  }
  return {std::make_unique<SocketPairBus>(fds[0]), std::make_unique<SocketPairBus>(fds[1])};
}

can_frame MakeFrame(uint32_t id, const uint8_t* data, uint8_t len) {
  can_frame f{};
  f.can_id = id & CAN_SFF_MASK;
  f.can_dlc = len > CAN_MAX_DLEN ? CAN_MAX_DLEN : len;
  if (data != nullptr) std::memcpy(f.data, data, f.can_dlc);
  return f;
}

}  // namespace haptel::vehicles
