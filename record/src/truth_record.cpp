#include "haptel/record/truth_record.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <stdexcept>

namespace haptel::record {

TruthRecord TruthRecord::Load(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot read the truth record");
  TruthRecord record;
  record.file_ = file;
  std::string line;
  int number = 0;
  bool columns = false;
  std::string torn;  // a last line without its newline: the vehicle stopped mid-write
  while (std::getline(in, line)) {
    ++number;
    const auto fail = [&](const std::string& expected) {
      throw std::runtime_error(file.string() + ":" + std::to_string(number) + ": expected " +
                               expected);
    };
    try {
      if (!columns) {
        if (IsTruthColumnLine(line)) {
          columns = true;
        } else if (!ParseTruthHeaderLine(line, record.params_)) {
          fail("a header line ('# key value') or the column line");
        }
        continue;
      }
      if (in.eof()) break;  // no newline after it: torn
      record.rows_.push_back(ParseTruthRow(line));
    } catch (const std::invalid_argument& e) {
      fail(e.what());
    }
  }
  if (!columns) {
    throw std::runtime_error(file.string() +
                             ": expected a truth record's header and column line; the file ends "
                             "before them");
  }
  return record;
}

bool TruthRecord::Covers(double t_s) const {
  if (rows_.empty()) return false;
  const double first = 1e-9 * static_cast<double>(rows_.front().operator_ns);
  const double last = 1e-9 * static_cast<double>(rows_.back().operator_ns);
  return t_s >= first && t_s <= last;
}

TruthRow TruthRecord::PoseAt(double t_s) const {
  if (rows_.empty()) throw std::logic_error("truth record " + file_.string() + ": no rows");
  const int64_t t_ns = static_cast<int64_t>(std::llround(t_s * 1e9));
  const auto after =
      std::lower_bound(rows_.begin(), rows_.end(), t_ns,
                       [](const TruthRow& r, int64_t t) { return r.operator_ns < t; });
  TruthRow out;
  if (after == rows_.begin()) {
    out = rows_.front();
  } else if (after == rows_.end()) {
    out = rows_.back();
  } else {
    const TruthRow& a = *(after - 1);
    const TruthRow& b = *after;
    const double span = static_cast<double>(b.operator_ns - a.operator_ns);
    const double u = span > 0 ? static_cast<double>(t_ns - a.operator_ns) / span : 0.0;
    const auto lerp = [u](double p, double q) { return p + (q - p) * u; };
    out.x = lerp(a.x, b.x);
    out.y = lerp(a.y, b.y);
    out.z = lerp(a.z, b.z);
    const double turn = std::remainder(b.heading - a.heading, 2.0 * std::numbers::pi);
    out.heading = std::remainder(a.heading + turn * u, 2.0 * std::numbers::pi);
    out.speed = lerp(a.speed, b.speed);
    out.yaw_rate = lerp(a.yaw_rate, b.yaw_rate);
  }
  out.operator_ns = t_ns;
  return out;
}

}  // namespace haptel::record
