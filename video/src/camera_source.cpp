#include "haptel/video/camera_source.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

#include "haptel/config/error.hpp"

namespace haptel::video {

namespace {

namespace fs = std::filesystem;

/// OpenCV logs its own warnings to stderr when a capture cannot be opened
/// ("VIDEOIO(V4L2:/dev/video9): can't open camera by index"); the error we
/// throw says it better, in one line. Silences OpenCV while opening only.
class QuietOpenCv {
 public:
  QuietOpenCv()
      : previous_(cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT)) {}
  ~QuietOpenCv() { cv::utils::logging::setLogLevel(previous_); }
  QuietOpenCv(const QuietOpenCv&) = delete;
  QuietOpenCv& operator=(const QuietOpenCv&) = delete;

 private:
  cv::utils::logging::LogLevel previous_;
};

bool IsIndex(const std::string& device) {
  return !device.empty() && device.find_first_not_of("0123456789") == std::string::npos;
}

/// Why `path` cannot be a V4L2 device, or "" when it looks like one.
std::string DeviceProblem(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    return errno == EACCES ? "permission denied" : "no such device";
  }
  if (!S_ISCHR(st.st_mode)) return "not a device";
  if (::access(path.c_str(), R_OK | W_OK) != 0) {
    return "permission denied; is the user in the 'video' group?";
  }
  return "";
}

/// Why `path` cannot be a video file, or "" when it is a readable file.
std::string FileProblem(const fs::path& path) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (!fs::exists(st)) return "no such file";
  if (!fs::is_regular_file(st)) return "not a file";
  if (::access(path.c_str(), R_OK) != 0) return "permission denied";
  return "";
}

}  // namespace

CaptureCamera::CaptureCamera(const CameraConfig& config, const std::string& config_file)
    : config_(Validated(config)), config_file_(config_file) {
  const auto fail = [&](const std::string& key, const std::string& why) {
    throw ConfigError(config_file_ + ": key 'camera." + key + "': cannot open " + target_ + " (" +
                      why + ")");
  };

  if (config_.source == CameraSourceKind::kDevice) {
    const std::string& d = config_.device;  // not empty: CameraConfig::ValidateOrThrow
    target_ = IsIndex(d) ? "/dev/video" + d : d;
    if (const std::string why = DeviceProblem(target_); !why.empty()) fail("device", why);
    // OpenCV waits up to 10 s (its default) for each frame of a device that
    // stopped sending; a second is enough to call a grab failed, and keeps the
    // camera loop responsive. It reads this once, at the first capture; the
    // user's own setting wins.
    ::setenv("OPENCV_VIDEOIO_V4L_SELECT_TIMEOUT", "1", 0);
    bool opened = false;
    {
      const QuietOpenCv quiet;
      try {
        opened =
            IsIndex(d) ? capture_.open(std::stoi(d), cv::CAP_V4L2) : capture_.open(d, cv::CAP_V4L2);
      } catch (const cv::Exception&) {
        opened = false;
      }
    }
    if (!opened || !capture_.isOpened()) fail("device", "not a V4L2 video capture device, or busy");
    // Requests; the device picks the nearest it supports. Two buffers: one
    // being filled while the other is read, so a frame is at most one old.
    capture_.set(cv::CAP_PROP_FRAME_WIDTH, config_.width);
    capture_.set(cv::CAP_PROP_FRAME_HEIGHT, config_.height);
    capture_.set(cv::CAP_PROP_FPS, config_.rate_hz);
    capture_.set(cv::CAP_PROP_BUFFERSIZE, 2);
    native_size_ = {static_cast<int>(capture_.get(cv::CAP_PROP_FRAME_WIDTH)),
                    static_cast<int>(capture_.get(cv::CAP_PROP_FRAME_HEIGHT))};
    return;
  }

  if (config_.source == CameraSourceKind::kFile) {
    target_ = config_.file.string();  // not empty: CameraConfig::ValidateOrThrow
    if (const std::string why = FileProblem(config_.file); !why.empty()) fail("file", why);
    if (!OpenFile()) fail("file", "not a video OpenCV can read");
    // The first frame now: a file with none is an error at set-up, not an
    // end of video on the first tick.
    if (!Read()) fail("file", "no frame could be read from it");
    pending_ = true;
    native_size_ = raw_.size();
    return;
  }

  throw std::invalid_argument("CaptureCamera: source '" +
                              std::string(CameraSourceName(config_.source)) +
                              "' is not a device or a file");
}

bool CaptureCamera::OpenFile() {
  const QuietOpenCv quiet;
  try {
    if (capture_.open(target_, cv::CAP_FFMPEG) && capture_.isOpened()) return true;
    return capture_.open(target_, cv::CAP_ANY) && capture_.isOpened();
  } catch (const cv::Exception&) {
    return false;
  }
}

bool CaptureCamera::Read() {
  try {
    return capture_.read(raw_) && !raw_.empty();
  } catch (const cv::Exception&) {
    return false;
  }
}

bool CaptureCamera::Rewind() {
  // Seeking to frame 0 is cheap; a file that cannot seek (or whose seek lands
  // elsewhere) is opened again instead.
  bool seeked = false;
  try {
    seeked =
        capture_.set(cv::CAP_PROP_POS_FRAMES, 0) && capture_.get(cv::CAP_PROP_POS_FRAMES) == 0.0;
  } catch (const cv::Exception&) {
    seeked = false;
  }
  if (seeked && Read()) return true;
  capture_.release();
  return OpenFile() && Read();
}

bool CaptureCamera::ReadFrame() {
  if (pending_) {
    pending_ = false;
    return true;
  }
  if (Read()) return true;
  if (config_.source == CameraSourceKind::kDevice) return false;  // try again next tick
  // A file's end (a frame that cannot be decoded ends it too).
  if (config_.loop && Rewind()) {
    ++loops_;
    return true;
  }
  ended_ = true;
  capture_.release();
  return false;
}

bool CaptureCamera::Grab(const CameraPose& /*pose*/, cv::Mat& bgr_out) {
  if (ended_ || !ReadFrame()) return false;
  const cv::Size size(config_.width, config_.height);
  cv::Mat bgr = raw_;
  if (raw_.depth() != CV_8U) {  // not from V4L2 or FFmpeg's usual decoders, but possible
    cv::Mat eight;
    raw_.convertTo(eight, CV_8U);
    bgr = eight;
  }
  if (bgr.channels() == 1) {
    cv::Mat colour;
    cv::cvtColor(bgr, colour, cv::COLOR_GRAY2BGR);
    bgr = colour;
  } else if (bgr.channels() == 4) {
    cv::Mat colour;
    cv::cvtColor(bgr, colour, cv::COLOR_BGRA2BGR);
    bgr = colour;
  } else if (bgr.channels() != 3) {
    return false;
  }
  if (bgr.size() == size) {
    bgr.copyTo(bgr_out);
  } else {
    // Area averaging when shrinking (no aliasing), bilinear when enlarging.
    const bool shrinking = bgr.cols > size.width || bgr.rows > size.height;
    cv::resize(bgr, bgr_out, size, 0, 0, shrinking ? cv::INTER_AREA : cv::INTER_LINEAR);
  }
  return true;
}

std::string CaptureCamera::Describe() const {
  return std::string(config_.source == CameraSourceKind::kDevice ? "device " : "file ") + target_;
}

std::unique_ptr<CameraSource> MakeCameraSource(const CameraConfig& config, const Track* track,
                                               const std::string& config_file) {
  switch (config.source) {
    case CameraSourceKind::kSynthetic:
      if (track == nullptr) {
        throw std::invalid_argument(config_file +
                                    ": camera.source synthetic needs a track to render");
      }
      return std::make_unique<SyntheticSource>(*track, config);
    case CameraSourceKind::kDevice:
    case CameraSourceKind::kFile:
      return std::make_unique<CaptureCamera>(config, config_file);
  }
  throw std::invalid_argument(config_file + ": camera.source: unknown kind");
}

GrabMonitor::Event GrabMonitor::OnGrab(bool ok, int64_t now_ns) {
  if (ok) {
    in_a_row_ = 0;
    stalled_now_ = false;
    return Event::kNone;
  }
  ++failures_;
  if (in_a_row_++ == 0) first_failure_ns_ = now_ns;
  if (stalled_now_ || in_a_row_ < min_failures_ || now_ns - first_failure_ns_ < min_duration_ns_) {
    return Event::kNone;
  }
  stalled_now_ = true;
  ++stalls_;
  if (reported_) return Event::kNone;
  reported_ = true;
  return Event::kStalled;
}

}  // namespace haptel::video
