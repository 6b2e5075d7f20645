#pragma once
/// @file Writes a simulated vehicle's truth record (config/truth_format.hpp;
/// read back by record/truth_record.hpp): the drawn reality as its header,
/// then one row per control tick. Rows are formatted into a stack buffer
/// and go through stdio's buffer (no allocation per row); the header is
/// flushed at once, so a vehicle stopped early still names its reality.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "haptel/config/reality.hpp"
#include "haptel/config/truth_format.hpp"

namespace haptel::vehicles {

class TruthWriter {
 public:
  /// Creates `file` (replacing one there) and writes the header; throws
  /// std::runtime_error naming the file and the OS's reason.
  TruthWriter(const std::filesystem::path& file, const DrawnReality& reality);
  /// Appends a row; a failed write is counted, not thrown (the control loop
  /// goes on).
  void Write(const TruthRow& row);
  /// Rows not written (a full disk).
  uint64_t failed() const { return failed_; }

 private:
  struct Close {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  std::unique_ptr<std::FILE, Close> out_;
  uint64_t failed_ = 0;
};

}  // namespace haptel::vehicles
