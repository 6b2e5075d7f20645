#include "haptel/vehicles/truth_writer.hpp"

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

namespace haptel::vehicles {

TruthWriter::TruthWriter(const std::filesystem::path& file, const DrawnReality& reality)
    : out_(std::fopen(file.c_str(), "w")) {
  if (!out_) {
    throw std::runtime_error("cannot write the truth record '" + file.string() +
                             "': " + std::strerror(errno));
  }
  const std::string header = TruthHeaderText(reality);
  if (std::fwrite(header.data(), 1, header.size(), out_.get()) != header.size() ||
      std::fflush(out_.get()) != 0) {
    throw std::runtime_error("cannot write the truth record '" + file.string() +
                             "': " + std::strerror(errno));
  }
}

void TruthWriter::Write(const TruthRow& row) {
  char line[256];
  const size_t n = FormatTruthRow(row, line, sizeof line);
  if (n == 0 || std::fwrite(line, 1, n, out_.get()) != n) ++failed_;
}

}  // namespace haptel::vehicles
