#include "haptel/config/calibration.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <system_error>

#include "haptel/config/archives.hpp"
#include "haptel/config/check.hpp"
#include "haptel/config/yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

void ArmCalibration::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  // Finger commands and forces are both >= 0: the slope must be positive.
  constexpr double kMaxForceSlope = 1e4;  // N per device unit
  if (!(finger_force_slope > 0.0 && finger_force_slope <= kMaxForceSlope)) {
    check::Fail("finger_force_slope", "a positive number in (0, " +
                                          std::to_string(static_cast<int>(kMaxForceSlope)) + "]");
  }
}

void DeviceCalibration::ValidateOrThrow() const { config_detail::CheckFields(*this); }

DeviceCalibration LoadCalibration(const std::filesystem::path& file) {
  return config_detail::LoadFile<DeviceCalibration>(file);
}

void SaveCalibration(const std::filesystem::path& file, const DeviceCalibration& calibration) {
  try {
    calibration.ValidateOrThrow();
  } catch (const ConfigFieldError& e) {
    throw ConfigError(file.string() + ": refusing to write an invalid calibration: " + e.what());
  }
  if (calibration.device.empty() || calibration.user.empty()) {
    throw ConfigError(file.string() +
                      ": refusing to write a calibration without a device and user name");
  }

  YAML::Emitter out;
  out.SetDoublePrecision(17);  // enough digits for every double to read back bit for bit
  out << YAML::Comment(
             "Haptel calibration, written by `haptel calibrate`; read by the device driver.\n"
             "tracker: metres = tracker_scale * raw + tracker_offset, per axis (x, y, z)\n"
             "glove: radians = glove_gain * counts + glove_offset, per sensor (22)\n"
             "force: newtons = force_slope * command, per axis; force_residual = RMS of that fit, "
             "N\n"
             "fingers: newtons = finger_force_slope * command")
      << YAML::Newline;
  out << YAML::BeginMap;
  config_detail::YamlWriteArchive archive(out);
  const_cast<DeviceCalibration&>(calibration).Serialize(&archive);
  out << YAML::EndMap;
  if (!out.good())
    throw ConfigError(file.string() + ": cannot format the calibration: " + out.GetLastError());

  std::error_code ec;
  if (file.has_parent_path()) {
    std::filesystem::create_directories(file.parent_path(), ec);
    if (ec) {
      throw ConfigError(file.string() + ": cannot create folder " + file.parent_path().string() +
                        ": " + ec.message());
    }
  }
  // Write beside the target and rename: a reader never sees half a file.
  std::filesystem::path tmp = file;
  tmp += ".tmp";
  {
    std::ofstream stream(tmp, std::ios::trunc);
    stream << out.c_str() << "\n";
    stream.close();
    if (!stream) throw ConfigError(tmp.string() + ": cannot write the file");
  }
  std::filesystem::rename(tmp, file, ec);
  if (ec) {
    const std::string why = ec.message();
    std::filesystem::remove(tmp, ec);
    throw ConfigError(file.string() + ": cannot write the file: " + why);
  }
}

}  // namespace haptel
