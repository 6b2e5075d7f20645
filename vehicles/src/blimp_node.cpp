#include "haptel/vehicles/blimp_node.hpp"

#include <cmath>
#include <stdexcept>

#include "haptel/config/error.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/clock.hpp"

namespace haptel::vehicles {

namespace {
BlimpCommand FromMessage(const msg::BlimpCommand& m) {
  BlimpCommand c;
  c.elevator = m.elevator();
  c.rudder = m.rudder();
  c.power = m.power();
  c.helix = m.helix();
  c.tail_rotor = m.tail_rotor();
  c.camera_pan = m.camera_pan();
  c.camera_tilt = m.camera_tilt();
  return c;
}
/// A float's rounding past a range's end is not malformed.
constexpr double kRangeSlack = 1e-3;
}  // namespace

BlimpNode::BlimpNode(const VehicleConfig& config, std::unique_ptr<video::CameraSource> camera,
                     std::unique_ptr<BlimpAdapter> adapter)
    : config_(Validated(config)),
      adapter_(std::move(adapter)),
      commands_(config.watchdog_timeout_s) {
  if (adapter_ == nullptr) throw std::invalid_argument("BlimpNode: no adapter");
  if (camera == nullptr) throw std::invalid_argument("BlimpNode: no camera source");
  ticks_per_state_ = std::max(1, static_cast<int>(std::lround(config.sim_rate_hz / config.state_rate_hz)));
  // Nothing flies before the first command.
  adapter_->Failsafe();

  participant_ = std::make_unique<link::Participant>(config.link, "haptel-vehicle-" + config.name);
  state_writer_ = std::make_unique<link::BlimpStateWriter>(*participant_, link::TopicName(config.name, "state"),
                                                           link::Profile::kState);
  camera_ = std::make_unique<CameraStreamer>(config.camera, std::move(camera), *participant_, config.name);
  command_reader_ = std::make_unique<link::BlimpCommandReader>(
      *participant_, link::TopicName(config.name, "command"), link::Profile::kCommand,
      [this](const msg::BlimpCommand& cmd) { OnCommand(cmd); });
  control_ = std::make_unique<PeriodicThread>(
      PeriodicThread::Options{.name = "vehicle-control", .rate_hz = config.sim_rate_hz},
      [this](int64_t now) { ControlTick(now); });
}

BlimpNode::~BlimpNode() { Stop(); }

void BlimpNode::Start() {
  control_->Start();
  camera_->Start();
}

void BlimpNode::Stop() {
  if (stopped_.exchange(true)) return;
  camera_->Stop();
  control_->Stop();
  if (!failed_.load()) {
    try {
      adapter_->Failsafe();
      adapter_->Update(1e-3);
    } catch (const cli::HardwareLost&) {
      // The port is gone: nothing more can be sent; the controller's own
      // serial timeout takes the channels to neutral.
    }
  }
  PublishState(MonotonicNs());
}

void BlimpNode::OnCommand(const msg::BlimpCommand& cmd) {
  const BlimpCommand command = FromMessage(cmd);
  commands_.Offer(InRange(command, kRangeSlack), {cmd.session(), cmd.operator_name().c_str(), cmd.release()},
                  cmd.seq(), cmd.sent_ns(), Clamped(command), MonotonicNs());
}

void BlimpNode::ControlTick(int64_t now_ns) {
  if (failed_.load(std::memory_order_relaxed)) return;
  const bool expired = commands_.Poll(now_ns);
  const double dt = ControlStep(last_tick_ns_, now_ns, config_.sim_rate_hz);
  try {
    if (expired) {
      adapter_->Failsafe();
    } else {
      adapter_->Apply(commands_.applied().command);
    }
    adapter_->Update(dt);
  } catch (const cli::HardwareLost& e) {
    // A serial port that vanished: stop driving it and say so once; the
    // node's owner ends the process (exit 3).
    failure_ = e.what();
    failed_.store(true);
    return;
  }
  const BlimpAdapterState s = adapter_->State();
  // The camera looks where its head points, from the vehicle's pose.
  camera_->SetPose({.x = s.x,
                    .y = s.y,
                    .heading = s.yaw,
                    .z = s.z,
                    .pitch = s.pitch,
                    .roll = s.roll,
                    .pan = s.applied.camera_pan,
                    .tilt = s.applied.camera_tilt});
  if (tick_count_++ % static_cast<uint64_t>(ticks_per_state_) == 0) PublishState(now_ns);
}

void BlimpNode::PublishState(int64_t now_ns) {
  const BlimpAdapterState s = adapter_->State();
  msg::BlimpState& m = state_msg_;
  m.seq(++state_seq_);
  m.stamp_ns(now_ns);
  m.pose_valid(s.pose_valid);
  m.x(static_cast<float>(s.x));
  m.y(static_cast<float>(s.y));
  m.z(static_cast<float>(s.z));
  m.yaw(static_cast<float>(s.yaw));
  m.pitch(static_cast<float>(s.pitch));
  m.roll(static_cast<float>(s.roll));
  m.vx(static_cast<float>(s.vx));
  m.vy(static_cast<float>(s.vy));
  m.vz(static_cast<float>(s.vz));
  m.airspeed(static_cast<float>(s.airspeed));
  m.contact(s.contact);
  m.impact_speed(static_cast<float>(s.impact_speed));
  m.contacts(s.contacts);
  const BlimpCommand& a = s.applied;
  m.outputs({static_cast<float>(a.elevator), static_cast<float>(a.rudder), static_cast<float>(a.power),
             static_cast<float>(a.helix), static_cast<float>(a.tail_rotor), static_cast<float>(a.camera_pan),
             static_cast<float>(a.camera_tilt)});
  std::array<float, 7> pulses{};
  for (size_t i = 0; i < pulses.size(); ++i) pulses[i] = static_cast<float>(s.pulse_us[i]);
  m.pulse_us(pulses);
  m.failsafe(commands_.watchdog_expired());
  m.controller_errors(s.controller_errors);
  m.last_command_seq(commands_.applied().seq);
  m.last_command_sent_ns(commands_.applied().sent_ns);
  m.last_command_age_ns(commands_.AppliedAgeNs(now_ns));
  m.commands_received(commands_.accepted());
  const CommandOwnerInfo owner = commands_.owner();
  m.owner_session(owner.session);
  m.owner(owner.name);
  m.commands_refused(commands_.refused());
  const bool failed = failed_.load();
  m.fault(s.fault || failed);
  m.fault_message(failed ? failure_ : s.fault_message);
  state_writer_->Write(m);
  states_.fetch_add(1, std::memory_order_relaxed);
}

NodeCounters BlimpNode::Counters() const {
  return MakeNodeCounters(commands_, camera_->Counters(), states_.load());
}

std::string BlimpNode::AdapterFailure() const { return failed_.load() ? failure_ : std::string(); }

}  // namespace haptel::vehicles
