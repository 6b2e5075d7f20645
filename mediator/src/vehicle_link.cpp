#include "haptel/mediator/vehicle_link.hpp"

#include <pwd.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <random>

#include "haptel/core/clock.hpp"
#include "haptel/link/security.hpp"

namespace haptel::mediator {

namespace {
/// The vehicle's command watchdog holds it stopped (robot) or in its failsafe (blimp).
bool WatchdogTripped(const msg::VehicleState& s) { return s.watchdog_tripped(); }
bool WatchdogTripped(const msg::BlimpState& s) { return s.failsafe(); }
}  // namespace

template <typename State>
void StateInboxOf<State>::Push(const State& s) {
  const int64_t now = MonotonicNs();
  std::lock_guard lock(mutex_);
  // Round trip of the command this state echoes, minus the time it waited
  // at the vehicle: no shared clock needed.
  if (s.last_command_seq() != 0 && s.last_command_seq() != last_echo_seq_) {
    last_echo_seq_ = s.last_command_seq();
    rtt_.Record(static_cast<double>(now - s.last_command_sent_ns() - s.last_command_age_ns()) * 1e-3);
  }
  if (have_state_ && s.seq() > last_state_seq_) {
    counts_.states_missed += s.seq() - last_state_seq_ - 1;
  } else if (have_state_) {
    have_baseline_ = false;  // a vehicle that started again: its counts start again
  }
  have_state_ = true;
  last_state_seq_ = s.seq();
  if (WatchdogTripped(s) && !watchdog_was_tripped_) ++counts_.watchdog_trips;
  watchdog_was_tripped_ = WatchdogTripped(s);
  // Commands sent before the vehicle listened are not its to drop: count from
  // the first state that echoes an applied command.
  if (!have_baseline_ && s.last_command_seq() != 0) {
    have_baseline_ = true;
    dropped_before_ = counts_.commands_dropped;
    first_echo_seq_ = s.last_command_seq();
    first_accepted_ = s.commands_received();
  }
  if (have_baseline_ && s.last_command_seq() >= first_echo_seq_ &&
      s.commands_received() >= first_accepted_) {
    const uint64_t echoed = s.last_command_seq() - first_echo_seq_;
    const uint64_t accepted = s.commands_received() - first_accepted_;
    if (echoed > accepted) {
      counts_.commands_dropped =
          std::max(counts_.commands_dropped, dropped_before_ + echoed - accepted);
    }
  }
  entries_.push_back({s, now});
  last_received_ns_ = now;
}

template <typename State>
LinkCounts StateInboxOf<State>::Counts() const {
  std::lock_guard lock(mutex_);
  return counts_;
}

template <typename State>
std::deque<typename StateInboxOf<State>::Entry> StateInboxOf<State>::Drain() {
  std::lock_guard lock(mutex_);
  std::deque<Entry> out;
  out.swap(entries_);
  return out;
}

template <typename State>
int64_t StateInboxOf<State>::last_received_ns() const {
  std::lock_guard lock(mutex_);
  return last_received_ns_;
}

template class StateInboxOf<msg::VehicleState>;
template class StateInboxOf<msg::BlimpState>;


namespace {

/// A random session id, never 0.
uint64_t NewSession() {
  std::random_device random;
  uint64_t id = 0;
  while (id == 0) id = (static_cast<uint64_t>(random()) << 32) ^ random();
  return id;
}

/// "haptel run, user@host pid N": what another operator is told of this one.
std::string OperatorName() {
  char host[64] = "?";
  gethostname(host, sizeof host - 1);
  const char* user = std::getenv("USER");
  if (user == nullptr) {
    const passwd* entry = getpwuid(getuid());
    if (entry != nullptr) user = entry->pw_name;
  }
  std::string name = "haptel run, " + std::string(user != nullptr ? user : "?") + "@" + host + " pid " +
                     std::to_string(getpid());
  if (name.size() > 63) name.resize(63);
  return name;
}

}  // namespace

VehicleLink::VehicleLink(const VehicleLinkOptions& options)
    : options_(options), session_(NewSession()) {
  const std::string who = OperatorName();
  command_.session(session_);
  command_.operator_name(who);
  blimp_command_.session(session_);
  blimp_command_.operator_name(who);
  if (!options_.program.empty()) {
    std::vector<std::string> arguments{"--config", options_.vehicle.file.string(), "--track",
                                       options_.track_file.string(), "--name", options_.vehicle.name, "--domain",
                                       std::to_string(options_.link.domain_id)};
    // The run's link faults on both ends: each delays and drops what it receives.
    if (options_.link.fault.enabled) arguments.insert(arguments.end(), {"--link-fault", LinkFaultText(options_.link.fault)});
    if (!options_.link.security.empty()) arguments.insert(arguments.end(), {"--security", options_.link.security.string()});
    if (!options_.link.discovery_server.empty()) {
      arguments.insert(arguments.end(), {"--discovery-server", options_.link.discovery_server});
    }
    process_ = std::make_unique<ChildProcess>(options_.program.string(), arguments);
  }
  LinkConfig link = options_.link;
  link.security_identity = link::OperatorIdentity();
  participant_ = std::make_unique<link::Participant>(link, "haptel-mediator");
  if (IsBlimpKind(options_.vehicle.kind)) {
    blimp_commands_ = std::make_unique<link::BlimpCommandWriter>(*participant_, link::TopicName(name(), "command"),
                                                                 link::Profile::kCommand);
    blimp_states_ = std::make_unique<link::BlimpStateReader>(
        *participant_, link::TopicName(name(), "state"), link::Profile::kState,
        [this](const msg::BlimpState& s) { blimp_inbox_.Push(s); });
  } else {
    commands_ = std::make_unique<link::CommandWriter>(*participant_, link::TopicName(name(), "command"),
                                                      link::Profile::kCommand);
    states_ = std::make_unique<link::StateReader>(*participant_, link::TopicName(name(), "state"),
                                                  link::Profile::kState,
                                                  [this](const msg::VehicleState& s) { inbox_.Push(s); });
  }
  video_ = std::make_unique<VideoReceiver>(*participant_, link::TopicName(name(), "video"), options_.decode_video);
}

VehicleLink::~VehicleLink() { Stop(); }

void VehicleLink::Send(double left, double right) {
  if (!commands_) return;
  command_.seq(++seq_);
  command_.left(static_cast<float>(left));
  command_.right(static_cast<float>(right));
  command_.sent_ns(MonotonicNs());
  commands_->Write(command_);
}

void VehicleLink::Send(const BlimpCommand& command) {
  if (!blimp_commands_) return;
  msg::BlimpCommand& m = blimp_command_;
  m.seq(++seq_);
  m.elevator(static_cast<float>(command.elevator));
  m.rudder(static_cast<float>(command.rudder));
  m.power(static_cast<float>(command.power));
  m.helix(static_cast<float>(command.helix));
  m.tail_rotor(static_cast<float>(command.tail_rotor));
  m.camera_pan(static_cast<float>(command.camera_pan));
  m.camera_tilt(static_cast<float>(command.camera_tilt));
  m.sent_ns(MonotonicNs());
  blimp_commands_->Write(m);
}

void VehicleLink::Stop() {
  if (stopped_) return;
  stopped_ = true;
  // The last commands stop the vehicle and release it for the next operator
  // (twice: they are best effort; a lost release frees it after
  // CommandOwner::kFreeAfter_s anyway).
  command_.release(true);
  blimp_command_.release(true);
  for (int i = 0; i < 2; ++i) {
    Send(0.0, 0.0);
    Send(BlimpCommand{});
  }
  if (process_) process_->Terminate();
}

int VehicleLink::VehiclesOnTopic() const {
  if (blimp()) return std::max(blimp_states_->matched(), blimp_commands_->matched());
  return std::max(states_->matched(), commands_->matched());
}

bool VehicleLink::ProcessAlive() { return !process_ || process_->Alive(); }

int VehicleLink::pid() const { return process_ ? process_->pid() : 0; }

std::string VehicleLink::ExitDescription() const { return process_ ? process_->ExitDescription() : "running elsewhere"; }

}  // namespace haptel::mediator
