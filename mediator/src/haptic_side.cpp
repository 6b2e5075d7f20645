#include "haptel/mediator/haptic_side.hpp"

#include <algorithm>
#include <sstream>

#include "haptel/calibration/calibration_procedure.hpp"
#include "haptel/config/error.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/log.hpp"
#include "haptel/haptics/calibrated_units.hpp"
#include "haptel/haptics/device_drivers.hpp"
#include "haptel/haptics/device_factory.hpp"
#include "haptel/haptics/gravity.hpp"
#include "haptel/haptics/servo_loop.hpp"
#include "haptel/haptics/sim_device.hpp"
#include "haptel/haptics/trace.hpp"

namespace haptel::mediator {

std::filesystem::path TraceCalibrationFile(const std::filesystem::path& trace) {
  return std::filesystem::path(trace.string() + ".calibration.yaml");
}

std::optional<DeviceCalibration> DeviceCalibrationFor(const DeviceConfig& device) {
  const std::string file = device.file.string();
  const haptics::CalibrationSource source = haptics::DriverOf(device).calibration;
  if (source == haptics::CalibrationSource::kOptional) {
    if (device.calibration.empty()) return std::nullopt;
    return LoadCalibration(device.calibration);
  }
  if (source == haptics::CalibrationSource::kSelf) {
    if (!device.calibration.empty()) return LoadCalibration(device.calibration);
    return haptics::IdentityCalibration(device.name);  // metres, radians, newtons already
  }
  if (source == haptics::CalibrationSource::kBesideTrace) {
    if (!device.calibration.empty()) return LoadCalibration(device.calibration);
    const std::filesystem::path beside = TraceCalibrationFile(device.replay.trace);
    if (!std::filesystem::exists(beside)) {
      throw ConfigError(file + ": key 'calibration': none given, and the trace '" +
                        device.replay.trace.string() + "' has no calibration beside it ('" +
                        beside.string() +
                        "'); record the trace with `haptel run --trace FILE`, which writes both");
    }
    return LoadCalibration(beside);
  }
  // A real device: only a measured calibration will do.
  if (device.calibration.empty()) {
    throw ConfigError(file + ": key 'calibration': device '" + device.name +
                      "' has no calibration file; make one with `haptel calibrate --device " +
                      file + " --out calibration/" + device.name + ".yaml` and name it here");
  }
  if (!std::filesystem::exists(device.calibration)) {
    throw ConfigError(file + ": key 'calibration': '" + device.calibration.string() +
                      "' does not exist; make it with `haptel calibrate --device " + file +
                      " --out " + device.calibration.string() + "`");
  }
  DeviceCalibration calibration = LoadCalibration(device.calibration);
  if (calibration.device != device.name) {
    throw ConfigError(file + ": key 'calibration': '" + device.calibration.string() +
                      "' was measured on device '" + calibration.device + "', not '" + device.name +
                      "' (stale); calibrate again with `haptel calibrate --device " + file +
                      " --out " + device.calibration.string() + "`");
  }
  return calibration;
}

HapticSide::HapticSide(const DeviceConfig& device,
                       const std::optional<DeviceCalibration>& calibration,
                       const std::optional<GravityGridData>& gravity, const OperatorConfig& muscle,
                       const std::filesystem::path& trace)
    : config_(device) {
  device_ = haptics::MakeDevice(device, muscle);
  sim_ = dynamic_cast<haptics::SimDevice*>(device_.get());
  replay_ = dynamic_cast<haptics::ReplayDevice*>(device_.get());
  if (replay_ != nullptr) replay_->HoldUntilBegin();
  if (calibration) {
    calibration_ = *calibration;
  } else if (sim_ != nullptr) {
    // No calibration file: calibrate the simulated device now, unattended,
    // as `haptel calibrate --auto` would (a fraction of a second).
    std::ostringstream quiet;
    haptics::CalibrationOptions options;
    options.auto_mode = true;
    calibration_ = haptics::RunCalibration(*sim_, options, quiet);
  } else {
    throw ConfigError(device.file.string() + ": no calibration for device '" + device.name + "'");
  }
  hal_ = std::make_unique<haptics::Hal>(calibration_);
  if (gravity) gravity_ = std::make_unique<haptics::GravityGrid>(*gravity);
  if (!trace.empty()) {
    trace_ = std::make_unique<haptics::TraceWriter>(trace);
    trace_->SetRecording(false);
    SaveCalibration(TraceCalibrationFile(trace), calibration_);
  }
  servo_ =
      std::make_unique<haptics::ServoLoop>(*device_, *hal_, device, calibration_, gravity_.get());
  servo_->SetTrace(trace_.get());
}

HapticSide::~HapticSide() { Stop(); }

void HapticSide::Start(bool progress) {
  servo_->Start();
  if (!progress) return;
  // Give the threads a moment to try for SCHED_FIFO, then say once what they could not get.
  SleepUntilNs(MonotonicNs() + SToNs(0.02));
  if (config_.servo.realtime_priority > 0 && !servo_->Stats().realtime) {
    log::Info("servo loop runs without SCHED_FIFO (no permission); timing may jitter under load");
  }
  if (config_.servo.lock_memory && !servo_->memory_locked()) {
    log::Info("servo loop runs without locked memory (mlockall refused); page faults may delay it");
  }
}

void HapticSide::Stop() {
  if (stopped_) return;
  stopped_ = true;
  hal_->ZeroForces();
  servo_->Stop();
}

void HapticSide::Tick(int64_t now_ns) {
  for (const haptics::Side side : {haptics::Side::kLeft, haptics::Side::kRight}) {
    if (device_->HasSide(side)) servo_->Tick(side, now_ns);
  }
}

void HapticSide::OnVehicleUp() {
  trace_engaged_ = -1;
  if (trace_) trace_->SetRecording(true);
  if (replay_ != nullptr) replay_->Begin(MonotonicNs());
}

void HapticSide::RecordEngaged(int64_t now_ns, bool engaged) {
  if (!trace_ || trace_engaged_ == static_cast<int>(engaged)) return;
  trace_engaged_ = static_cast<int>(engaged);
  trace_->PushEngaged(now_ns, engaged);
}

bool HapticSide::replay_finished() const {
  return replay_ != nullptr && replay_->finished(MonotonicNs());
}

bool HapticSide::lost() const {
  for (int i = 0; i < haptics::kSides; ++i) {
    const auto side = static_cast<haptics::Side>(i);
    if (config_.sides[i] && hal_->lost(side)) return true;
  }
  return false;
}

double HapticSide::silent_s() const {
  const int64_t now = MonotonicNs();
  double silent = 0.0;
  for (int i = 0; i < haptics::kSides; ++i) {
    const auto side = static_cast<haptics::Side>(i);
    std::array<haptics::TrackerSample, 1> last{};
    if (config_.sides[i] && hal_->lost(side) && hal_->TrackerHistory(side, last) == 1) {
      silent = std::max(silent, NsToS(now - last[0].t_ns));
    }
  }
  return silent;
}

LoopStats HapticSide::Stats() const { return servo_->Stats(); }

haptics::ServoCounters HapticSide::Counters(haptics::Side side) const {
  if (!config_.sides[haptics::Index(side)]) return {};
  return servo_->Counters(side);
}

haptics::ServoCounters HapticSide::Counters() const {
  haptics::ServoCounters sum;
  for (int i = 0; i < haptics::kSides; ++i) {
    if (!config_.sides[i]) continue;
    const haptics::ServoCounters c = servo_->Counters(static_cast<haptics::Side>(i));
    sum.cycles += c.cycles;
    sum.slow_reads += c.slow_reads;
    sum.device_lost_ticks += c.device_lost_ticks;
    sum.no_data_ticks += c.no_data_ticks;
    sum.write_failures += c.write_failures;
    sum.setpoint_read_fallbacks += c.setpoint_read_fallbacks;
    sum.passivity_ticks += c.passivity_ticks;
    sum.passivity_dissipated_j += c.passivity_dissipated_j;
    sum.passivity_max_alpha =
        std::max(sum.passivity_max_alpha, c.passivity_max_alpha);  // the largest, not a sum
    sum.passivity_link_ticks += c.passivity_link_ticks;
    sum.passivity_device_ticks += c.passivity_device_ticks;
    sum.passivity_device_dissipated_j += c.passivity_device_dissipated_j;
    sum.passivity_device_max_alpha =
        std::max(sum.passivity_device_max_alpha, c.passivity_device_max_alpha);
    sum.safety.non_finite += c.safety.non_finite;
    sum.safety.clamped += c.safety.clamped;
    sum.safety.rate_limited += c.safety.rate_limited;
    sum.safety.stale_ticks += c.safety.stale_ticks;
  }
  return sum;
}

}  // namespace haptel::mediator

namespace haptel::mediator {

const Histogram& HapticSide::ServoPeriods() const {
  const bool right = device_->HasSide(haptics::Side::kRight);
  return servo_->period_histogram(right ? haptics::Side::kRight : haptics::Side::kLeft);
}

const Histogram& HapticSide::ServoCuePeriods() const {
  const bool right = device_->HasSide(haptics::Side::kRight);
  return servo_->cue_period_histogram(right ? haptics::Side::kRight : haptics::Side::kLeft);
}

}  // namespace haptel::mediator
