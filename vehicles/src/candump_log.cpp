#include "haptel/vehicles/candump_log.hpp"

#include <cerrno>
#include <cinttypes>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "haptel/core/log.hpp"

namespace haptel::vehicles {
namespace {

int HexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

}  // namespace

std::string FormatCandumpFrame(const can_frame& frame) {
  char text[48];
  int n = 0;
  if ((frame.can_id & CAN_ERR_FLAG) != 0) {
    n = std::snprintf(text, sizeof text, "%08X#", frame.can_id & (CAN_ERR_MASK | CAN_ERR_FLAG));
  } else if ((frame.can_id & CAN_EFF_FLAG) != 0) {
    n = std::snprintf(text, sizeof text, "%08X#", frame.can_id & CAN_EFF_MASK);
  } else {
    n = std::snprintf(text, sizeof text, "%03X#", frame.can_id & CAN_SFF_MASK);
  }
  if ((frame.can_id & CAN_RTR_FLAG) != 0) {
    text[n++] = 'R';
    text[n] = '\0';
    return text;
  }
  const int len = frame.can_dlc > CAN_MAX_DLEN ? CAN_MAX_DLEN : frame.can_dlc;
  for (int i = 0; i < len; ++i)
    n += std::snprintf(text + n, sizeof text - static_cast<size_t>(n), "%02X", frame.data[i]);
  return text;
}

bool ParseCandumpFrame(const std::string& text, can_frame& frame) {
  const size_t hash = text.find('#');
  if (hash != 3 && hash != 8) return false;
  uint32_t id = 0;
  for (size_t i = 0; i < hash; ++i) {
    const int d = HexDigit(text[i]);
    if (d < 0) return false;
    id = id << 4 | static_cast<uint32_t>(d);
  }
  can_frame f{};
  if (hash == 3) {
    if (id > CAN_SFF_MASK) return false;
    f.can_id = id;
  } else if ((id & CAN_ERR_FLAG) != 0) {
    f.can_id = id & (CAN_ERR_MASK | CAN_ERR_FLAG);
  } else {
    f.can_id = (id & CAN_EFF_MASK) | CAN_EFF_FLAG;
  }
  const std::string data = text.substr(hash + 1);
  if (data.size() >= 1 && data[0] == 'R') {
    if ((f.can_id & CAN_ERR_FLAG) != 0) return false;
    f.can_id |= CAN_RTR_FLAG;
    f.can_dlc = 0;
    frame = f;
    return data.size() == 1;
  }
  if (data.size() % 2 != 0 || data.size() > 2 * CAN_MAX_DLEN) return false;
  for (size_t i = 0; i < data.size(); i += 2) {
    const int hi = HexDigit(data[i]);
    const int lo = HexDigit(data[i + 1]);
    if (hi < 0 || lo < 0) return false;
    f.data[i / 2] = static_cast<uint8_t>(hi << 4 | lo);
  }
  f.can_dlc = static_cast<uint8_t>(data.size() / 2);
  frame = f;
  return true;
}

std::vector<LoggedFrame> ReadCandumpLog(const std::filesystem::path& file, size_t* malformed) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error("cannot read the CAN log " + file.string());
  std::vector<LoggedFrame> frames;
  size_t bad = 0;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    // (sec.usec) interface frame
    LoggedFrame f;
    char stamp[40] = "";
    char interface[32] = "";
    char frame_text[64] = "";
    if (std::sscanf(line.c_str(), "(%39[0-9.]) %31s %63s", stamp, interface, frame_text) != 3 ||
        std::strchr(stamp, '.') == nullptr || !ParseCandumpFrame(frame_text, f.frame)) {
      ++bad;
      continue;
    }
    f.t_s = std::strtod(stamp, nullptr);
    f.interface = interface;
    frames.push_back(f);
  }
  if (malformed != nullptr) *malformed = bad;
  return frames;
}

CandumpWriter::CandumpWriter(const std::filesystem::path& file, std::string interface)
    : path_(file), interface_(std::move(interface)) {
  std::error_code ignored;
  if (file.has_parent_path()) std::filesystem::create_directories(file.parent_path(), ignored);
  file_ = std::fopen(file.c_str(), "w");
  if (file_ == nullptr) {
    throw std::runtime_error("cannot write the CAN log " + file.string() + ": " +
                             std::strerror(errno));
  }
}

CandumpWriter::~CandumpWriter() { Close(); }

void CandumpWriter::Fail(int errno_value) {
  // The lines since the last good flush may be partly in the file (a short
  // write); they count as lost, so frames_written() stays what is certain.
  error_ = "cannot write " + path_.string() + ": " + std::strerror(errno_value) + " (after " +
           std::to_string(flushed_) + " frames)";
  if (file_ != nullptr) std::fclose(file_);  // its own error, if any, is the same disk's
  file_ = nullptr;
  log::Error("the CAN bus log is not recorded whole: " + error_);
}

void CandumpWriter::Flush() {
  if (file_ == nullptr) return;
  errno = 0;
  if (std::fflush(file_) != 0 || std::ferror(file_) != 0) {
    Fail(errno != 0 ? errno : EIO);
    return;
  }
  flushed_ = lines_;
}

void CandumpWriter::Write(const can_frame& frame, int64_t wall_ns) {
  ++lines_;
  if (file_ == nullptr) return;  // ended by a failed write (or closed): lost
  const int64_t sec = wall_ns / 1'000'000'000;
  const int64_t usec = (wall_ns % 1'000'000'000) / 1000;
  errno = 0;
  // stdio writes when its buffer fills: a failure can show here too.
  if (std::fprintf(file_, "(%" PRId64 ".%06" PRId64 ") %s %s\n", sec, usec, interface_.c_str(),
                   FormatCandumpFrame(frame).c_str()) < 0) {
    Fail(errno != 0 ? errno : EIO);
    return;
  }
  if (flushed_wall_ns_ == 0) flushed_wall_ns_ = wall_ns;
  if (lines_ % kFlushEvery == 0 || wall_ns - flushed_wall_ns_ >= kFlushPeriod_ns) {
    flushed_wall_ns_ = wall_ns;
    Flush();
  }
}

bool CandumpWriter::Close() {
  if (file_ == nullptr) return error_.empty();
  Flush();
  if (file_ == nullptr) return false;
  std::FILE* file = file_;
  file_ = nullptr;
  errno = 0;
  if (std::fclose(file) != 0) {  // a network file system reports a full disk here
    Fail(errno != 0 ? errno : EIO);
    return false;
  }
  return true;
}

}  // namespace haptel::vehicles
