#pragma once
/// @file A simulated vehicle's truth record, read after the run for scoring
/// (the prediction's error against where the vehicle truly was, estimated
/// parameters against the drawn ones). The vehicle writes it when given
/// `--truth FILE` (haptel run passes SessionSetup::truth_file); its format
/// is config/truth_format.hpp. Nothing on the operator side reads it while
/// the run goes on.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "haptel/config/reality.hpp"
#include "haptel/config/truth_format.hpp"

namespace haptel::record {

class TruthRecord {
 public:
  /// Reads a truth record; throws std::runtime_error naming the file, the
  /// line and what was expected (a missing file, a torn last row is
  /// dropped: the vehicle may have been stopped mid-write).
  static TruthRecord Load(const std::filesystem::path& file);

  /// Every drawn value (the header), under DrawnReality's names.
  const DrawnReality& params() const { return params_; }
  /// The reality's name ("lab") and seed, as the vehicle drew them.
  const std::string& reality() const { return params_.name; }
  uint64_t seed() const { return params_.seed; }
  /// The rows in time order.
  const std::vector<TruthRow>& rows() const { return rows_; }
  bool empty() const { return rows_.empty(); }

  /// Where the vehicle truly was at `t_s`, seconds of the operator host's
  /// clock (NsToS(MonotonicNs())): linearly interpolated between rows (the
  /// heading the shorter way round); the first or last row outside them.
  /// operator_ns is `t_s`'s. std::logic_error when there are no rows.
  TruthRow PoseAt(double t_s) const;
  /// Whether `t_s` lies within the rows' time span.
  bool Covers(double t_s) const;

 private:
  std::filesystem::path file_;
  DrawnReality params_;
  std::vector<TruthRow> rows_;
};

}  // namespace haptel::record
