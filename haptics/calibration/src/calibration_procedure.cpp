#include "haptel/calibration/calibration_procedure.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <optional>
#include <random>
#include <sstream>

#include "haptel/config/device.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/gravity_grid.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/run.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/gravity/gravity_procedure.hpp"
#include "haptel/haptics/device_drivers.hpp"
#include "haptel/haptics/device_factory.hpp"
#include "haptel/haptics/device_ticker.hpp"
#include "haptel/haptics/sim_device.hpp"

namespace haptel::haptics {

namespace {

constexpr int64_t kMs = 1'000'000;
constexpr const char* kSideNames[kSides] = {"left", "right"};
constexpr const char* kAxisNames[3] = {"x", "y", "z"};
/// The glove is a slow channel: read it at the servo loop's slow rate.
constexpr int64_t kGlovePeriodNs = 6 * kMs;
/// Unattended: the wrist counts as settled when its reading has not changed
/// for this long; it is docked in the jig after at most kSettleTimeoutNs.
constexpr int64_t kSettledNs = 100 * kMs;
constexpr int64_t kSettleTimeoutNs = 3000 * kMs;
/// Time the docked arm is left before it is read.
constexpr int64_t kDockNs = 100 * kMs;

/// Everything one side's steps need.
struct Session {
  Device& device;
  SimDevice* sim;  ///< non-null in auto mode
  Side side;
  const CalibrationOptions& options;
  std::ostream& log;
  std::istream& in;
  DeviceTicker& ticker;

  const char* name() const { return kSideNames[Index(side)]; }

  [[noreturn]] void Lost() const {
    throw CalibrationError(std::string("the ") + name() + " arm stopped answering");
  }

  /// Waits for the operator's Enter.
  void WaitEnter() const {
    std::string line;
    if (!std::getline(in, line))
      throw CalibrationError("the input ended before the calibration was done");
  }

  /// One wrist reading one tick later, the wrist force held at zero.
  Vec3d ReadWrist() const {
    WristRaw raw;
    const int64_t now = ticker.Next(kMs);
    const DeviceStatus status = device.ReadWrist(side, now, raw);
    if (status == DeviceStatus::kLost) Lost();
    if (device.WriteWristForce(side, Vec3d{}) == DeviceStatus::kLost) Lost();
    return raw.position;
  }

  Vec3d MeanWrist(int samples) const {
    Vec3d sum{};
    for (int k = 0; k < samples; ++k) {
      const Vec3d p = ReadWrist();
      for (int i = 0; i < 3; ++i) sum[i] += p[i];
    }
    for (double& v : sum) v /= samples;
    return sum;
  }

  std::array<double, kGloveJoints> MeanGlove(int samples) const {
    std::array<double, kGloveJoints> sum{};
    int got = 0;
    for (int k = 0; k < samples * 10 && got < samples; ++k) {
      GloveRaw raw;
      const DeviceStatus status = device.ReadGlove(side, ticker.Next(kGlovePeriodNs), raw);
      if (status == DeviceStatus::kLost) Lost();
      if (status != DeviceStatus::kOk) continue;
      for (int j = 0; j < kGloveJoints; ++j) sum[j] += raw.sensors[j];
      ++got;
    }
    if (got == 0) throw CalibrationError(std::string("the ") + name() + " glove gives no readings");
    for (double& v : sum) v /= got;
    return sum;
  }
};

// ---------------------------------------------------------------- glove ----

/// Captures a posture. Unattended, a `fumbled` posture is made only half-way
/// from another one (the fist, or for the fist the flat hand).
std::array<double, kGloveJoints> CaptureGlove(const Session& s, int posture, bool fumbled) {
  const auto& postures = GlovePostures();
  const GlovePosture& p = postures[static_cast<size_t>(posture)];
  if (s.sim != nullptr) {
    const GlovePosture& from = postures[static_cast<size_t>(posture == 1 ? 0 : 1)];
    std::array<double, kGloveJoints> angles = p.angles;
    if (fumbled) {
      for (int j = 0; j < kGloveJoints; ++j) angles[j] = 0.5 * (p.angles[j] + from.angles[j]);
    }
    s.sim->SetGlovePosture(s.side, angles);
    s.log << "  " << s.name() << " hand: '" << p.name << "'"
          << (fumbled ? " (fumbled: half-way from '" + std::string(from.name) + "')" : "") << "\n";
  } else {
    s.log << "  " << s.name() << " hand, posture '" << p.name << "': " << p.how
          << ". Hold it and press Enter." << std::endl;
    s.WaitEnter();
  }
  return s.MeanGlove(s.options.glove_samples);
}

void CalibrateGlove(const Session& s, ArmCalibration& arm) {
  s.log << "Glove, " << s.name() << " hand: " << kGlovePostureCount << " postures\n";
  GloveCalibrator calibrator;
  const auto& postures = GlovePostures();
  std::vector<int> order(kGlovePostureCount);
  for (int i = 0; i < kGlovePostureCount; ++i) order[static_cast<size_t>(i)] = i;
  if (s.sim != nullptr) {
    std::mt19937 rng(s.options.seed + 7919u * static_cast<unsigned>(Index(s.side)));
    std::shuffle(order.begin(), order.end(), rng);
  }
  for (size_t k = 0; k < order.size(); ++k) {
    const bool fumbled = s.sim != nullptr && k == 0;
    calibrator.Capture(postures[static_cast<size_t>(order[k])].name,
                       CaptureGlove(s, order[k], fumbled));
  }
  // Redo postures: the operator names them; unattended, the fumbled first one.
  if (s.sim != nullptr) {
    const auto& p = postures[static_cast<size_t>(order[0])];
    s.log << "  redoing '" << p.name << "'\n";
    calibrator.Recapture(p.name, CaptureGlove(s, order[0], false));
  } else {
    for (;;) {
      s.log << "  Redo a posture? Type its name (flat, fist, spread, bent) or press Enter to go on."
            << std::endl;
      std::string line;
      if (!std::getline(s.in, line))
        throw CalibrationError("the input ended before the calibration was done");
      line.erase(0, line.find_first_not_of(" \t\r"));
      line.erase(line.find_last_not_of(" \t\r") + 1);
      if (line.empty()) break;
      const int index = GlovePostureIndex(line);
      if (index < 0) {
        s.log << "  no posture '" << line << "'\n";
        continue;
      }
      calibrator.Recapture(line, CaptureGlove(s, index, false));
    }
  }
  const GloveFit fit = calibrator.Fit();
  fit.ApplyTo(arm);
  double worst = 0.0;
  int worst_sensor = 0;
  for (int j = 0; j < kGloveJoints; ++j) {
    if (fit.sensors[j].check_error > worst) {
      worst = fit.sensors[j].check_error;
      worst_sensor = j;
    }
  }
  s.log << "  fitted 22 sensors; largest disagreement of a posture with its sensor's line: "
        << worst << " rad (" << kGloveSensorNames[static_cast<size_t>(worst_sensor)] << ")\n";
}

// -------------------------------------------------------------- tracker ----

Vec3d CaptureReference(const Session& s, const Vec3d& target) {
  if (s.sim != nullptr) {
    // The operator carries the wrist over until it is still, then it is
    // docked in the jig (which fixes it at the reference) and read.
    s.sim->SetOperatorTarget(s.side, target);
    Vec3d last = s.ReadWrist();
    int64_t still_ns = 0;
    for (int64_t t = 0; t < kSettleTimeoutNs && still_ns < kSettledNs; t += kMs) {
      const Vec3d p = s.ReadWrist();
      still_ns = (p == last) ? still_ns + kMs : 0;
      last = p;
    }
    s.sim->Dock(s.side, target);
    for (int64_t t = 0; t < kDockNs; t += kMs) s.ReadWrist();
  } else {
    s.log << "  Put the " << s.name() << " wrist in the jig at (" << target[0] << ", " << target[1]
          << ", " << target[2] << ") m and press Enter." << std::endl;
    s.WaitEnter();
  }
  return s.MeanWrist(s.options.wrist_samples);
}

void CalibrateTracker(const Session& s, ArmCalibration& arm) {
  s.log << "Tracker, " << s.name() << " arm: " << s.options.references.size()
        << " reference poses\n";
  std::vector<TrackerReference> references;
  for (const Vec3d& target : s.options.references)
    references.push_back({CaptureReference(s, target), target});
  const TrackerFit fit = FitTracker(references);
  fit.ApplyTo(arm);
  for (int i = 0; i < 3; ++i) {
    s.log << "  " << kAxisNames[i] << ": scale " << fit.scale[i] << " m/unit"
          << (fit.scale_fitted[i] ? "" : " (default: references do not span this axis)")
          << ", offset " << fit.offset[i] << " m, residual " << fit.residual_rms[i] * 1e3
          << " mm\n";
  }
}

// ---------------------------------------------------------------- force ----

double AskGauge(const Session& s, int axis) {
  for (;;) {
    s.log << "  Gauge reading along " << kAxisNames[axis] << " (N, signed): " << std::flush;
    std::string line;
    if (!std::getline(s.in, line))
      throw CalibrationError("the input ended before the calibration was done");
    std::istringstream parse(line);
    double value = 0.0;
    std::string rest;
    if (parse >> value && !(parse >> rest) && std::isfinite(value)) return value;
    s.log << "  not a number: '" << line << "'\n";
  }
}

void CalibrateForce(const Session& s, ArmCalibration& arm) {
  const double top = s.options.force_fraction * s.device.description().wrist_force_limit;
  if (!(top > 0.0)) throw CalibrationError("force: the device has no wrist force to calibrate");
  s.log << "Force, " << s.name() << " arm: single-axis commands up to " << top << "\n";
  std::vector<ForceSample> samples;
  for (int axis = 0; axis < 3; ++axis) {
    for (double level : {-1.0, -0.75, -0.5, -0.25, 0.25, 0.5, 0.75, 1.0}) {
      ForceSample sample;
      sample.command[axis] = level * top;
      if (s.sim != nullptr) {
        sample.newtons = s.sim->MeasureForce(s.side, sample.command);
      } else {
        if (s.device.WriteWristForce(s.side, sample.command) == DeviceStatus::kLost) s.Lost();
        s.log << "  command " << kAxisNames[axis] << " = " << sample.command[axis] << "\n";
        sample.newtons[axis] = AskGauge(s, axis);
        if (s.device.WriteWristForce(s.side, Vec3d{}) == DeviceStatus::kLost) s.Lost();
      }
      samples.push_back(sample);
    }
  }
  const ForceFit fit = FitForce(samples);
  fit.ApplyTo(arm);
  s.log << "  slopes " << fit.slope[0] << ", " << fit.slope[1] << ", " << fit.slope[2]
        << " N/unit, residual " << fit.residual << " N\n";
}

std::string Percent(double relative) {
  std::ostringstream out;
  out << std::showpos << std::fixed << std::setprecision(4) << relative * 100.0 << " %";
  return out.str();
}

}  // namespace

std::vector<Vec3d> DefaultTrackerReferences() {
  std::vector<Vec3d> out{kReferenceCentre};
  for (int i = 0; i < 3; ++i) {
    for (double sign : {-1.0, 1.0}) {
      Vec3d p = kReferenceCentre;
      p[i] += sign * kReferenceHalfSpan;
      out.push_back(p);
    }
  }
  return out;
}

DeviceCalibration RunCalibration(Device& device, const CalibrationOptions& options,
                                 std::ostream& log, std::istream& in) {
  SimDevice* sim = nullptr;
  if (options.auto_mode) {
    sim = dynamic_cast<SimDevice*>(&device);
    if (sim == nullptr)
      throw CalibrationError("unattended calibration (--auto) needs the sim device");
  }
  if (options.glove_samples < 1 || options.wrist_samples < 1) {
    throw CalibrationError("glove_samples and wrist_samples must be at least 1");
  }
  DeviceCalibration result = options.base;
  result.device = device.description().name;
  result.user = options.user;
  DeviceTicker ticker(sim != nullptr);
  for (int i = 0; i < kSides; ++i) {
    const Side side = static_cast<Side>(i);
    if (!device.HasSide(side)) continue;
    const Session session{device, sim, side, options, log, in, ticker};
    ArmCalibration& arm = result.arms[i];
    if (options.glove && device.description().has_glove) CalibrateGlove(session, arm);
    if (options.tracker) CalibrateTracker(session, arm);
    if (options.force) CalibrateForce(session, arm);
  }
  return result;
}

DeviceCalibration RunCalibration(Device& device, const CalibrationOptions& options,
                                 std::ostream& log) {
  return RunCalibration(device, options, log, std::cin);
}

TruthErrors CompareWithTruth(const ArmCalibration& c, const SimArmTruth& t) {
  TruthErrors e;
  for (int i = 0; i < 3; ++i) {
    e.tracker_scale_rel =
        std::max(e.tracker_scale_rel, std::abs(c.tracker_scale[i] / t.tracker_scale[i] - 1.0));
    e.tracker_offset_m =
        std::max(e.tracker_offset_m, std::abs(c.tracker_offset[i] - t.tracker_offset[i]));
    e.force_slope_rel =
        std::max(e.force_slope_rel, std::abs(c.force_slope[i] / t.force_slope[i] - 1.0));
  }
  const auto& postures = GlovePostures();
  for (size_t j = 0; j < kGloveJoints; ++j) {
    e.glove_gain_rel =
        std::max(e.glove_gain_rel, std::abs(c.glove_gain[j] / t.glove_gain[j] - 1.0));
    e.glove_offset_rad =
        std::max(e.glove_offset_rad, std::abs(c.glove_offset[j] - t.glove_offset[j]));
    // The error is linear in the reading: its largest value over the
    // postures' range is at one end of it.
    double lo = postures[0].angles[j];
    double hi = lo;
    for (const auto& p : postures) {
      lo = std::min(lo, p.angles[j]);
      hi = std::max(hi, p.angles[j]);
    }
    for (double angle : {lo, hi}) {
      const double raw = (angle - t.glove_offset[j]) / t.glove_gain[j];
      e.glove_angle_rad =
          std::max(e.glove_angle_rad, std::abs(c.glove_gain[j] * raw + c.glove_offset[j] - angle));
    }
  }
  return e;
}

void PrintCalibrationSummary(std::ostream& out, const DeviceCalibration& calibration,
                             const Device& device) {
  const auto* sim = dynamic_cast<const SimDevice*>(&device);
  const std::ios::fmtflags flags = out.flags();
  const std::streamsize precision = out.precision();
  out << "Calibration of '" << calibration.device << "' for user '" << calibration.user << "'\n";
  for (int s = 0; s < kSides; ++s) {
    if (!device.HasSide(static_cast<Side>(s))) continue;
    const ArmCalibration& c = calibration.arms[s];
    out << "\n" << kSideNames[s] << " arm" << std::string(18, ' ') << std::setw(16) << "recovered";
    if (sim != nullptr) out << std::setw(16) << "true" << std::setw(16) << "error";
    out << "\n";
    auto row = [&](const std::string& label, double value, std::optional<double> truth,
                   const std::string& error) {
      out << "  " << std::left << std::setw(24) << label << std::right << std::setw(16)
          << std::setprecision(7) << value;
      if (sim != nullptr) {
        out << std::setw(16);
        if (truth) {
          out << *truth;
        } else {
          out << "";
        }
        out << std::setw(16) << error;
      }
      out << "\n";
    };
    const SimArmTruth* t = sim != nullptr ? &sim->truth(static_cast<Side>(s)) : nullptr;
    for (int i = 0; i < 3; ++i) {
      const double truth = t != nullptr ? t->tracker_scale[i] : 0.0;
      row(std::string("tracker scale ") + kAxisNames[i] + " (m/unit)", c.tracker_scale[i], truth,
          t != nullptr ? Percent(c.tracker_scale[i] / truth - 1.0) : "");
    }
    for (int i = 0; i < 3; ++i) {
      const double truth = t != nullptr ? t->tracker_offset[i] : 0.0;
      std::ostringstream err;
      err << std::showpos << std::fixed << std::setprecision(4)
          << (c.tracker_offset[i] - truth) * 1e3 << " mm";
      row(std::string("tracker offset ") + kAxisNames[i] + " (m)", c.tracker_offset[i], truth,
          t != nullptr ? err.str() : "");
    }
    for (int i = 0; i < 3; ++i) {
      const double truth = t != nullptr ? t->force_slope[i] : 0.0;
      row(std::string("force slope ") + kAxisNames[i] + " (N/unit)", c.force_slope[i], truth,
          t != nullptr ? Percent(c.force_slope[i] / truth - 1.0) : "");
    }
    row("force residual (N)", c.force_residual, std::nullopt, "");
    row("finger slope (N/unit)", c.finger_force_slope, t != nullptr ? t->finger_force_slope : 0.0,
        t != nullptr ? "not measured" : "");
    double gain_lo = c.glove_gain[0];
    double gain_hi = gain_lo;
    for (double g : c.glove_gain) {
      gain_lo = std::min(gain_lo, g);
      gain_hi = std::max(gain_hi, g);
    }
    out << "  glove gains " << std::setprecision(4) << gain_lo << " .. " << gain_hi
        << " rad/count (22 sensors)\n";
    if (t != nullptr) {
      const TruthErrors e = CompareWithTruth(c, *t);
      out << "  worst glove errors: gain " << Percent(e.glove_gain_rel) << ", offset "
          << std::setprecision(3) << e.glove_offset_rad << " rad, angle over the postures' range "
          << e.glove_angle_rad << " rad\n";
    }
  }
  out.flags(flags);
  out.precision(precision);
}

namespace {

/// The calibration gravity is sampled in: the device file's `calibration:`,
/// or, for the sim device with none, one measured unattended now (as
/// `haptel run` does). A real device names one (CalibrateMain checks first).
DeviceCalibration CalibrationForGravity(const DeviceConfig& config, Device& device) {
  if (!config.calibration.empty()) return LoadCalibration(config.calibration);
  CalibrationOptions options;
  options.auto_mode = true;
  std::ostringstream quiet;
  return RunCalibration(device, options, quiet);
}

/// `haptel calibrate --gravity`: samples the grid and writes it to `out_file`.
int SampleGravityGrid(const DeviceConfig& config, Device& device, bool auto_mode, int counts,
                      const std::filesystem::path& out_file) {
  const Side side = config.sides[Index(Side::kRight)] ? Side::kRight : Side::kLeft;
  const DeviceCalibration calibration = CalibrationForGravity(config, device);
  GravitySamplerConfig sampler;
  sampler.counts = {counts, counts, counts};
  sampler.device = config.name;
  GravityProcedureOptions options;
  options.auto_mode = auto_mode;
  options.rate_hz = config.servo.rate_hz;
  const GravitySampleReport report = SampleGravity(device, side, calibration.arms[Index(side)],
                                                   sampler, options, std::cout, std::cin);
  if (!report.ok) {
    std::cerr << "haptel calibrate: " << report.error << "\n";
    return cli::kExitFailed;
  }
  SaveGravityGrid(out_file, report.grid);
  double low = report.grid.force_z.front();
  double high = low;
  for (double f : report.grid.force_z) {
    low = std::min(low, f);
    high = std::max(high, f);
  }
  std::cout << "  " << report.vertices.size() << " vertices held still, upward force " << low
            << " .. " << high << " N; " << report.sim_time_s << " s of device time, "
            << report.wall_time_s << " s wall-clock\n"
            << "wrote " << out_file.string() << "\n";
  if (out_file != config.gravity) {
    std::cout << "name it in " << config.file.string() << "'s 'gravity:' key to use it\n";
  }
  return cli::kExitOk;
}

}  // namespace

int CalibrateMain(int argc, const char* const* argv) {
  constexpr const char* kUsage =
      "usage: haptel calibrate [options]\n"
      "  --device FILE  device configuration (default config/devices/sim.yaml)\n"
      "  --out FILE     file to write (default calibration/<device>.yaml; with --gravity,\n"
      "                 the file the device file's 'gravity:' names)\n"
      "  --auto         unattended: the sim device's simulated operator does every step\n"
      "  --user NAME    whose calibration this is (default 'default')\n"
      "  --gravity      sample the gravity-compensation grid instead (the right arm, or the\n"
      "                 left on a device without one): at each vertex the arm is let go and\n"
      "                 held still by the force found; needs the device's calibration file\n"
      "                 (the sim device with --auto calibrates itself when it names none)\n"
      "  --counts N     with --gravity: vertices per axis, 2 to 50 (default 5)\n";
  return cli::Main({"haptel calibrate", kUsage}, argc, argv, [&] {
    DeviceConfig config;
    std::filesystem::path out_file;
    CalibrationOptions options;
    bool gravity = false;
    int counts = 5;
    cli::ReadInput([&] {
      const Args args(argc, argv, {"device", "out", "user", "counts"}, {"auto", "gravity"});
      const auto& words = args.positional();
      if (words.size() > 1 || (words.size() == 1 && words[0] != "calibrate")) {
        throw UsageError("unexpected argument '" + words.back() + "'");
      }
      const std::filesystem::path device_file =
          args.Value("device").value_or(ShippedFile("config/devices/sim.yaml"));
      config = LoadDevice(device_file);
      options.auto_mode = args.Flag("auto");
      gravity = args.Flag("gravity");
      const bool simulated = haptics::DriverOf(config).simulated;
      if (simulated && !options.auto_mode) {
        throw UsageError("the sim device has nobody to hold its arms: use --auto");
      }
      if (!simulated && options.auto_mode) {
        throw UsageError("--auto needs the sim device (" + device_file.string() +
                         " names driver '" + config.driver +
                         "'); a real device is calibrated with an operator at the prompts");
      }
      if (!gravity && args.Value("counts")) throw UsageError("--counts goes with --gravity");
      counts = args.Int("counts", 2, 50).value_or(counts);
      options.user = args.Value("user").value_or("default");
      if (gravity && !options.auto_mode && config.calibration.empty()) {
        throw ConfigError(device_file.string() +
                          ": key 'calibration': expected the device's calibration file, which "
                          "gravity is sampled through; make one with `haptel calibrate --device " +
                          device_file.string() + " --out calibration/" + config.name +
                          ".yaml` and name it here");
      }
      if (gravity) {
        out_file = args.Value("out").value_or(config.gravity.string());
        if (out_file.empty()) {
          throw ConfigError(device_file.string() +
                            ": key 'gravity': expected the grid file to write (e.g. gravity: "
                            "calibration/" +
                            config.name +
                            "-gravity.yaml); the device file names none (or give "
                            "--out FILE)");
        }
      } else {
        out_file = args.Value("out").value_or(
            (std::filesystem::path("calibration") / (config.name + ".yaml")).string());
      }
      // Now, not after the sampling: a FIFO would be waited on for ever.
      CheckFileOption("out", out_file, "a file name to write, such as out.yaml");
    });
    const std::unique_ptr<Device> device = MakeDevice(config);
    if (gravity) return SampleGravityGrid(config, *device, options.auto_mode, counts, out_file);
    const DeviceCalibration calibration = RunCalibration(*device, options, std::cout);
    SaveCalibration(out_file, calibration);
    std::cout << "\n";
    PrintCalibrationSummary(std::cout, calibration, *device);
    std::cout << "\nwrote " << out_file.string() << "\n";
    return cli::kExitOk;
  });
}

}  // namespace haptel::haptics
