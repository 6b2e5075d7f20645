#include "haptel/vehicles/blimp_adapters.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "haptel/servo/calibration.hpp"

namespace haptel::vehicles {

std::array<double, kBlimpChannels> ChannelValues(const BlimpCommand& c) {
  return {c.elevator,
          c.rudder,
          c.power,
          c.helix,
          c.tail_rotor,
          c.camera_pan / kBlimpCameraPanMax,
          c.camera_tilt / kBlimpCameraTiltMax};
}

BlimpCommand CommandFromChannels(const std::array<double, kBlimpChannels>& v) {
  BlimpCommand c;
  c.elevator = v[0];
  c.rudder = v[1];
  c.power = v[2];
  c.helix = v[3];
  c.tail_rotor = v[4];
  c.camera_pan = v[5] * kBlimpCameraPanMax;
  c.camera_tilt = v[6] * kBlimpCameraTiltMax;
  return Clamped(c);
}

void PoseFromSim(const models::SimBlimp& sim, BlimpAdapterState& s) {
  s.pose_valid = true;
  const Eigen::Vector3d p = sim.position();
  const Eigen::Vector3d v = sim.ground_velocity();
  s.x = p.x();
  s.y = p.y();
  s.z = p.z();
  s.yaw = sim.yaw();
  s.pitch = sim.pitch();
  s.roll = sim.roll();
  s.vx = v.x();
  s.vy = v.y();
  s.vz = v.z();
  s.airspeed = sim.airspeed();
  s.contact = sim.in_contact();
  s.impact_speed = sim.last_impact_speed();
  s.contacts = static_cast<uint32_t>(sim.contacts());
}

AirshipConfig AirshipInReality(const AirshipConfig& airship, const DrawnReality& r) {
  AirshipConfig a = airship;
  a.wind.mean[0] = r.wind_x;
  a.wind.mean[1] = r.wind_y;
  a.wind.gust_rms = r.gust_rms;
  if (r.volume > 0.0) a.volume = r.volume;
  a.payload_mass = r.payload_mass;
  // Another robot of the make, another gust pattern; the twin keeps the file's.
  if (r.seed != 0) a.wind.seed = a.wind.seed ^ (r.seed * 0x9E3779B97F4A7C15ULL) % (1U << 30);
  return a;
}

void TruthFromSim(const models::SimBlimp& sim, TruthRow* row) {
  const Eigen::Vector3d p = sim.position();
  const Eigen::Vector3d v = sim.ground_velocity();
  const models::AirshipState& s = sim.airship().state();
  row->x = p.x();
  row->y = p.y();
  row->z = p.z();
  row->heading = sim.yaw();
  row->speed = std::hypot(v.x(), v.y());
  row->yaw_rate = (s.attitude * s.rates).z();
}

SimBlimpAdapter::SimBlimpAdapter(const AirshipConfig& airship, const BlimpCourseConfig& course,
                                 const DrawnReality& reality)
    : reality_(reality), sim_(AirshipInReality(airship, reality), course) {}

bool SimBlimpAdapter::Truth(TruthRow* row) const {
  TruthFromSim(sim_, row);
  return true;
}

BlimpAdapterState SimBlimpAdapter::State() const {
  BlimpAdapterState s;
  PoseFromSim(sim_, s);
  s.applied = sim_.applied();
  return s;
}

ServoBlimpAdapter::ServoBlimpAdapter(const ServoControllerConfig& config,
                                     std::unique_ptr<servo::ByteStream> port)
    : config_(config), output_(config, std::move(port)) {
  Apply(BlimpCommand{});
  output_.Send(pulse_us_);
}

void ServoBlimpAdapter::Apply(const BlimpCommand& command) {
  applied_ = output_.untrusted() ? BlimpCommand{} : Clamped(command);
  const std::array<double, kBlimpChannels> pulses =
      servo::PulsesFromCommands(config_, ChannelValues(applied_));
  // A change (a new command, the failsafe's neutral) goes out at the next
  // update, not at the next refresh: the watchdog's neutral is not held back.
  if (pulses != pulse_us_) next_send_s_ = std::min(next_send_s_, time_s_);
  pulse_us_ = pulses;
}

void ServoBlimpAdapter::AimCamera(size_t camera, const CameraAim& aim) {
  const std::vector<CameraServoChannel>& axes = config_.camera_channels;
  for (size_t i = 0; i < axes.size(); ++i) {
    if (axes[i].camera != static_cast<int>(camera)) continue;
    const double pulse =
        output_.untrusted()
            ? axes[i].output.neutral_us
            : servo::PulseFromCommand(axes[i].output, servo::CameraAxisCommand(axes[i], aim));
    // A change goes out at the next update, as a command's does.
    if (pulse != output_.camera_pulse_us(i)) next_send_s_ = std::min(next_send_s_, time_s_);
    output_.SetCameraPulse(i, pulse);
  }
}

void ServoBlimpAdapter::Update(double dt) {
  time_s_ += dt;
  if (time_s_ >= next_send_s_) {
    next_send_s_ = std::max(next_send_s_ + kSendPeriod_s, time_s_ - kSendPeriod_s);
    output_.Send(pulse_us_);
  }
  const bool trusted = !output_.untrusted();
  output_.Update(time_s_);
  // Judged untrustworthy just now: neutral at once, not at the next command.
  if (trusted && output_.untrusted()) {
    Apply(BlimpCommand{});
    for (size_t i = 0; i < config_.camera_channels.size(); ++i)
      output_.SetCameraPulse(i, config_.camera_channels[i].output.neutral_us);
    next_send_s_ = time_s_ + kSendPeriod_s;
    output_.Send(pulse_us_);
  }
}

BlimpAdapterState ServoBlimpAdapter::State() const {
  BlimpAdapterState s;
  s.applied = applied_;
  for (int i = 0; i < kBlimpChannels; ++i) s.pulse_us[i] = pulse_us_[i];
  s.controller_errors = output_.last_errors();
  if (output_.untrusted()) {
    s.fault = true;
    s.fault_message = output_.untrusted_reason();
  }
  return s;
}

SimulatedServoBlimp::SimulatedServoBlimp(const ServoControllerConfig& config,
                                         const AirshipConfig& airship,
                                         const BlimpCourseConfig& course,
                                         const DrawnReality& reality)
    : reality_(reality), config_(config), sim_(AirshipInReality(airship, reality), course) {
  // The adapter opens the pty's far end by its path, as it would a device.
  adapter_ = std::make_unique<ServoBlimpAdapter>(
      config_, std::make_unique<servo::SerialPort>(pty_.slave_path(), config_.baud));
  controller_ = std::make_unique<servo::SimServoController>(config_, pty_.TakeMaster());
}

void SimulatedServoBlimp::Update(double dt) {
  time_s_ += dt;
  adapter_->Update(dt);
  controller_->Update(time_s_);
  // The controller's pulses, read back through each channel's calibration,
  // are what the airship's actuators do.
  std::array<double, kBlimpChannels> values{};
  for (int i = 0; i < kBlimpChannels; ++i) {
    values[i] = servo::CommandFromPulse(config_.channels[i], controller_->pulse_us()[i]);
  }
  sim_.Step(dt, CommandFromChannels(values));
}

bool SimulatedServoBlimp::CameraAimed(size_t camera, CameraAim* aim) const {
  bool any = false;
  for (const CameraServoChannel& axis : config_.camera_channels) {
    if (axis.camera != static_cast<int>(camera)) continue;
    const double pulse = controller_->output_pulse_us(axis.output.channel);
    servo::SetCameraAxis(axis, servo::CommandFromPulse(axis.output, pulse), aim);
    any = true;
  }
  return any;
}

BlimpAdapterState SimulatedServoBlimp::State() const {
  BlimpAdapterState s = adapter_->State();
  PoseFromSim(sim_, s);
  s.applied = sim_.applied();
  return s;
}

}  // namespace haptel::vehicles
