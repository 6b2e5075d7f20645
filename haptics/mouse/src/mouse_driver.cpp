// The `mouse` driver in the device registry (haptel/haptics/device_drivers.hpp):
// the view window's pointer and keys as two hands (mouse_device.hpp).
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

#include "haptel/haptics/device_drivers.hpp"
#include "haptel/mouse/mouse_device.hpp"

namespace haptel::haptics {
namespace {

/// Whether a unix socket at `path` accepts a connection (a server answers).
bool SocketAnswers(const std::string& path) {
  sockaddr_un address{};
  if (path.size() >= sizeof address.sun_path) return false;
  const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return false;
  address.sun_family = AF_UNIX;
  std::memcpy(address.sun_path, path.c_str(), path.size());
  const bool answers =
      ::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0;
  ::close(fd);
  return answers;
}

/// "" when a display's server answers: a local X display (":N", its socket
/// /tmp/.X11-unix/XN), a remote one (host:N, taken on trust: the window
/// says if it cannot reach it), or a Wayland compositor. Else the line.
std::string DisplayMissing(const DeviceConfig&) {
  const char* display = std::getenv("DISPLAY");
  if (display != nullptr && display[0] != '\0') {
    if (display[0] != ':') return {};
    const std::string number(display + 1, std::strcspn(display + 1, "."));
    const std::string socket = "/tmp/.X11-unix/X" + number;
    if (SocketAnswers(socket)) return {};
    return std::string("the mouse device needs a display, and DISPLAY=") + display +
           " does not answer (no X server at " + socket + ")";
  }
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  if (wayland != nullptr && wayland[0] != '\0') {
    const char* runtime = std::getenv("XDG_RUNTIME_DIR");
    const std::filesystem::path socket =
        wayland[0] == '/' ? std::filesystem::path(wayland)
                          : std::filesystem::path(runtime != nullptr ? runtime : "") / wayland;
    if (SocketAnswers(socket.string())) return {};
    return "the mouse device needs a display, and WAYLAND_DISPLAY=" + std::string(wayland) +
           " does not answer (no compositor at " + socket.string() + ")";
  }
  return "the mouse device needs a display: neither DISPLAY nor WAYLAND_DISPLAY is set (run "
         "on a desktop, or under Xvfb)";
}

const RegisterDeviceDriver kMouseDriver{{
    .name = MouseDevice::kDriver,
    .simulated = false,
    .reads_trace = false,
    .reads_window = true,
    .calibration = CalibrationSource::kOptional,
    .check = nullptr,
    .available = DisplayMissing,
    .make = [](const DeviceConfig& config, const OperatorConfig&) -> std::unique_ptr<Device> {
      return std::make_unique<MouseDevice>(config);
    },
}};

}  // namespace
}  // namespace haptel::haptics
