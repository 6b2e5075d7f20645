#include "haptel/mediator/vehicle_link.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdlib>

#include "haptel/core/clock.hpp"
#include "haptel/core/process_identity.hpp"
#include "haptel/link/security.hpp"

namespace haptel::mediator {

class SelectedWriter : public link::Writer<msg::SelectedSource, msg::SelectedSourcePubSubType> {
  using Writer::Writer;
};

/// The CAN log's status as the DDS thread delivers it, taken by the session.
class CanLogInbox {
 public:
  CanLogInbox(link::Participant& participant, const std::string& vehicle)
      : reader_(participant, link::TopicName(vehicle, "can_log"), link::Profile::kLatched,
                [this](const msg::CanLogStatus& s) {
                  std::lock_guard lock(mutex_);
                  latest_ = s;
                  fresh_ = true;
                }) {}
  bool Take(msg::CanLogStatus& out) {
    std::lock_guard lock(mutex_);
    if (!fresh_) return false;
    out = latest_;
    fresh_ = false;
    return true;
  }

 private:
  std::mutex mutex_;
  msg::CanLogStatus latest_;
  bool fresh_ = false;
  // Last: destroyed first, so no DDS callback outlives the rest.
  link::CanLogReader reader_;
};

namespace {
/// The vehicle's command watchdog holds it stopped (robot) or in its failsafe (blimp).
bool WatchdogTripped(const msg::VehicleState& s) { return link::RobotMessages::WatchdogTripped(s); }
bool WatchdogTripped(const msg::BlimpState& s) { return link::BlimpMessages::WatchdogTripped(s); }
}  // namespace

template <typename State>
void StateInboxOf<State>::Push(const State& s) {
  const int64_t now = MonotonicNs();
  std::lock_guard lock(mutex_);
  // The command this state echoes is this run's only while the vehicle
  // obeys this run's writer; another's (a stranger's, with its own clock and
  // sequence) says nothing of this run's commands.
  const bool ours = own_writer_.empty() || link::WriterId{s.owner_writer()} == own_writer_;
  // Round trip of the command this state echoes, minus the time it waited
  // at the vehicle: no shared clock needed.
  if (ours && s.last_command_seq() != 0 && s.last_command_seq() != last_echo_seq_) {
    last_echo_seq_ = s.last_command_seq();
    rtt_.Record(static_cast<double>(now - s.last_command_sent_ns() - s.last_command_age_ns()) *
                1e-3);
  }
  const uint64_t feedback_refused = s.video_feedback_refused();
  if (have_state_ && s.seq() > last_state_seq_) {
    counts_.states_missed += s.seq() - last_state_seq_ - 1;
  } else if (have_state_) {
    have_baseline_ = false;  // a vehicle that started again: its counts start again
    feedback_refused_before_ = counts_.video_feedback_refused;
    feedback_refused_base_ = 0;
  } else {
    feedback_refused_base_ =
        feedback_refused;  // an attached vehicle's earlier ones are not this run's
  }
  if (feedback_refused >= feedback_refused_base_) {
    counts_.video_feedback_refused =
        std::max(counts_.video_feedback_refused,
                 feedback_refused_before_ + feedback_refused - feedback_refused_base_);
  }
  have_state_ = true;
  last_state_seq_ = s.seq();
  if (WatchdogTripped(s) && !watchdog_was_tripped_) ++counts_.watchdog_trips;
  watchdog_was_tripped_ = WatchdogTripped(s);
  // Commands sent before the vehicle listened are not its to drop: count from
  // the first state that echoes an applied command of this run's (again
  // after a state that did not: the vehicle's count of accepted commands
  // then holds another writer's).
  if (!ours) {
    have_baseline_ = false;
  } else if (!have_baseline_ && s.last_command_seq() != 0) {
    have_baseline_ = true;
    dropped_before_ = counts_.commands_dropped;
    first_echo_seq_ = s.last_command_seq();
    first_accepted_ = s.commands_received();
  }
  if (ours && have_baseline_ && s.last_command_seq() >= first_echo_seq_ &&
      s.commands_received() >= first_accepted_) {
    const uint64_t echoed = s.last_command_seq() - first_echo_seq_;
    const uint64_t accepted = s.commands_received() - first_accepted_;
    if (echoed > accepted) {
      counts_.commands_dropped =
          std::max(counts_.commands_dropped, dropped_before_ + echoed - accepted);
    }
  }
  if (ours && echo_watch_ns_ != 0 && echo_received_ns_ == 0 && s.last_command_seq() != 0 &&
      s.last_command_sent_ns() >= echo_watch_ns_) {
    echo_received_ns_ = now;
  }
  entries_.push_back({s, now});
  last_received_ns_ = now;
}

template <typename State>
void StateInboxOf<State>::WatchEcho(int64_t sent_ns) {
  std::lock_guard lock(mutex_);
  echo_watch_ns_ = sent_ns;
  echo_received_ns_ = 0;
}

template <typename State>
int64_t StateInboxOf<State>::EchoReceivedNs() const {
  std::lock_guard lock(mutex_);
  return echo_received_ns_;
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

template <class Messages>
CommandChannel<Messages>::CommandChannel(link::Participant& participant, const std::string& vehicle,
                                         uint64_t session, const std::string& operator_name) {
  message_.session(session);
  message_.operator_name(operator_name);
  writer_ = std::make_unique<typename Messages::CommandWriter>(
      participant, link::TopicName(vehicle, "command"), link::Profile::kCommand);
  writer_id_ = writer_->id();
  inbox_.SetOwnWriter(writer_id_);
  reader_ = std::make_unique<typename Messages::StateReader>(
      participant, link::TopicName(vehicle, "state"), link::Profile::kState,
      [this](const typename Messages::StateMsg& s) { inbox_.Push(s); });
}

template <class Messages>
CommandChannel<Messages>::CommandChannel(
    std::function<void(const typename Messages::CommandMsg&)> sink, uint64_t session,
    const std::string& operator_name, link::SampleTap* tap, const std::string& vehicle)
    : sink_(std::move(sink)) {
  inbox_.SetOwnWriter(writer_id_);
  message_.session(session);
  message_.operator_name(operator_name);
  if (tap != nullptr) {
    sent_tap_ = std::make_unique<typename decltype(sent_tap_)::element_type>(
        tap, link::TopicName(vehicle, "command"), link::TapDirection::kSent);
    received_tap_ = std::make_unique<typename decltype(received_tap_)::element_type>(
        tap, link::TopicName(vehicle, "state"), link::TapDirection::kReceived);
  }
}

template <class Messages>
void CommandChannel<Messages>::Deliver(const typename Messages::StateMsg& state) {
  if (received_tap_) (*received_tap_)(state, MonotonicNs());
  inbox_.Push(state);
}

template <class Messages>
void CommandChannel<Messages>::Send(const Command& command) {
  message_.seq(++seq_);
  Messages::Encode(command, message_);
  message_.sent_ns(MonotonicNs());
  if (sink_) {
    if (sent_tap_) (*sent_tap_)(message_, MonotonicNs());
    sink_(message_);
  } else {
    writer_->Write(message_);
  }
}

template <class Messages>
void CommandChannel<Messages>::SendSafe(bool release) {
  message_.release(release);
  Send(Command{});
}

template <class Messages>
int CommandChannel<Messages>::VehiclesOnTopic() const {
  if (sink_) return 1;
  return std::max(reader_->matched(), writer_->matched());
}

template class CommandChannel<link::RobotMessages>;
template class CommandChannel<link::BlimpMessages>;

VehicleLink::VehicleLink(const VehicleLinkOptions& options)
    : options_(options), session_(NewSessionId()) {
  operator_name_ = ProcessOperatorName("haptel run");
  if (options_.in_process_robot) {
    if (family() != VehicleFamily::kRobot) {
      throw std::logic_error("vehicle link: '" + name() + "' is a " + ToString(family()) +
                             "; only a robot steps in this process");
    }
    channel_ = std::make_unique<RobotChannel>(options_.in_process_robot, session_, operator_name_,
                                              options_.tap, name());
    video_ = std::make_unique<video::VideoReceiver>();
    return;
  }
  if (!options_.program.empty()) {
    std::vector<std::string> arguments{
        "--config", options_.vehicle.file.string(), "--track", options_.track_file.string(),
        "--name", options_.vehicle.name, "--domain", std::to_string(options_.link.domain_id),
        // Which of its cameras stream (a camera set-up may leave some out).
        "--cameras", CameraNames(options_.vehicle)};
    // The run's link faults on both ends: each delays and drops what it receives.
    if (options_.link.fault.enabled)
      arguments.insert(arguments.end(), {"--link-fault", LinkFaultText(options_.link.fault)});
    // The vehicle's hidden truth: passed on, never read here.
    const VehicleConfig& v = options_.vehicle;
    if (!v.reality.empty()) arguments.insert(arguments.end(), {"--reality", v.reality.string()});
    if (v.reality_seed)
      arguments.insert(arguments.end(), {"--reality-seed", std::to_string(*v.reality_seed)});
    if (!v.truth_file.empty())
      arguments.insert(arguments.end(), {"--truth", v.truth_file.string()});
    if (!options_.link.security.empty())
      arguments.insert(arguments.end(), {"--security", options_.link.security.string()});
    if (!options_.link.discovery_server.empty()) {
      arguments.insert(arguments.end(), {"--discovery-server", options_.link.discovery_server});
    }
    process_ = std::make_unique<ChildProcess>(options_.program.string(), arguments);
  }
  LinkConfig link = options_.link;
  link.security_identity = link::OperatorIdentity();
  participant_ = std::make_unique<link::Participant>(link, "haptel-mediator", &discovered_);
  participant_->SetTap(options_.tap);  // before any writer or reader: each is tapped
  const std::string who = ProcessOperatorName("haptel run");
  switch (family()) {
    case VehicleFamily::kRobot:
      channel_ = std::make_unique<RobotChannel>(*participant_, name(), session_, who);
      can_log_ = std::make_unique<CanLogInbox>(*participant_, name());
      break;
    case VehicleFamily::kBlimp:
      channel_ = std::make_unique<BlimpChannel>(*participant_, name(), session_, who);
      break;
  }
  video_ = std::make_unique<video::VideoReceiver>(*participant_, name(), session_,
                                                  options_.decode_video);
  operator_name_ = who;
  if (options_.publish_selected) {
    selected_ = std::make_unique<SelectedWriter>(*participant_, link::TopicName(name(), "selected"),
                                                 link::Profile::kLatched);
  }
}

std::string VehicleLink::ForeignStateType() const {
  std::string expected;
  switch (family()) {
    case VehicleFamily::kRobot:
      expected = link::RobotMessages::StateType().getName();
      break;
    case VehicleFamily::kBlimp:
      expected = link::BlimpMessages::StateType().getName();
      break;
  }
  return discovered_.OtherTypeOn(link::TopicName(name(), "state"), expected);
}

bool VehicleLink::PublishSelected(const std::string& source, const std::string& lock) {
  if (!selected_) return false;
  msg::SelectedSource m;
  m.vehicle(name());
  m.source(source);
  m.lock(lock);
  m.stamp_ns(WallNs());
  m.operator_name(operator_name_);
  return selected_->Write(m);
}

int VehicleLink::selected_readers() const { return selected_ ? selected_->matched() : 0; }

bool VehicleLink::TakeCanLog(msg::CanLogStatus& out) { return can_log_ && can_log_->Take(out); }

VehicleLink::~VehicleLink() { Stop(); }

void VehicleLink::Stop() {
  if (stopped_) return;
  stopped_ = true;
  // The last commands stop the vehicle and release it for the next operator
  // (twice: they are best effort; a lost release frees it after
  // CommandOwner::kFreeAfter_s anyway).
  for (int i = 0; i < 2; ++i) channel_->SendSafe(true);
  if (process_) process_->Terminate();
}

link::FaultCounts VehicleLink::FaultCounts() const {
  const link::FaultLine* line = participant_ ? participant_->fault_line() : nullptr;
  return line != nullptr ? line->Counts() : link::FaultCounts{};
}

link::FaultLine* VehicleLink::fault_line() const {
  return participant_ ? participant_->fault_line() : nullptr;
}

bool VehicleLink::ProcessAlive() { return !process_ || process_->Alive(); }

int VehicleLink::pid() const { return process_ ? process_->pid() : 0; }

std::string VehicleLink::ExitDescription() const {
  return process_ ? process_->ExitDescription() : "running elsewhere";
}

}  // namespace haptel::mediator
