#include "video_source.hpp"

#include <fstream>
#include <opencv2/videoio.hpp>
#include <sstream>
#include <stdexcept>
#include <string>

namespace haptel::bench {

void WriteLosslessSource(const std::filesystem::path& file, const std::vector<cv::Mat>& frames,
                         double rate_hz) {
  cv::VideoWriter writer(file.string(), cv::CAP_FFMPEG, cv::VideoWriter::fourcc('F', 'F', 'V', '1'),
                         rate_hz, frames.front().size());
  if (!writer.isOpened())
    throw std::runtime_error("cannot write the source video " + file.string() + " (FFV1)");
  for (const cv::Mat& f : frames) writer.write(f);
}

void WriteVehicleFileWithSource(const VehicleConfig& vehicle, CameraCodec codec,
                                const std::filesystem::path& source,
                                const std::filesystem::path& out) {
  std::ifstream in(vehicle.file);
  if (!in) throw std::runtime_error("cannot read the vehicle file " + vehicle.file.string());
  std::ostringstream o;
  bool in_camera = false, source_done = false, codec_done = false;
  std::string line;
  while (std::getline(in, line)) {
    const bool top_level = !line.empty() && line[0] != ' ' && line[0] != '#';
    if (top_level) in_camera = line.rfind("camera:", 0) == 0;
    const size_t key = line.find_first_not_of(' ');
    const std::string indent = line.substr(0, key == std::string::npos ? 0 : key);
    if (top_level && line.rfind("world:", 0) == 0 && !vehicle.world.empty()) {
      o << "world: " << std::filesystem::absolute(vehicle.world).string() << "\n";
    } else if (in_camera && key != std::string::npos && line.compare(key, 7, "source:") == 0) {
      o << indent << "source: file\n"
        << indent << "file: " << std::filesystem::absolute(source).string() << "\n"
        << indent << "loop: true\n";
      source_done = true;
    } else if (in_camera && key != std::string::npos &&
               (line.compare(key, 5, "file:") == 0 || line.compare(key, 5, "loop:") == 0)) {
      continue;  // replaced above
    } else if (in_camera && key != std::string::npos && line.compare(key, 6, "codec:") == 0) {
      o << indent << "codec: " << CameraCodecName(codec) << "\n";
      codec_done = true;
    } else {
      o << line << "\n";
    }
  }
  if (!source_done || !codec_done) {
    throw std::runtime_error(vehicle.file.string() +
                             ": expected camera.source and camera.codec lines to replace");
  }
  std::ofstream file(out);
  file << o.str();
  if (!file.flush()) throw std::runtime_error("cannot write " + out.string());
}

}  // namespace haptel::bench
