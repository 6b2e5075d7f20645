#pragma once
/// @file Small PNG plots for benchmark reports, drawn with OpenCV (no display).
#include <filesystem>
#include <string>
#include <vector>

namespace haptel::bench {

struct Series {
  std::string name;
  std::vector<double> x;
  std::vector<double> y;
};

struct PlotOptions {
  std::string title;
  std::string x_label;
  std::string y_label;
  bool log_y = false;
  int width = 900;
  int height = 520;
};

/// Draws the series as lines with a legend and writes a PNG (creating the
/// folder). Throws std::runtime_error when the file cannot be written.
void PlotLines(const std::filesystem::path& file, const std::vector<Series>& series,
               const PlotOptions& options);

/// Where benchmark outputs go: build/bench/ under the working directory.
std::filesystem::path BenchDir();

}  // namespace haptel::bench
