#pragma once
/// @file The session's link to its vehicle: the vehicle process it spawns
/// (or none, for a vehicle that runs elsewhere), the DDS participant, the
/// video receiver, and the command and state topics of the vehicle's
/// family (CommandChannel, over link's families.hpp) with their inbox.
///
/// Threads: DDS callbacks push states into the inbox (a short lock) and
/// frames into the video receiver; the session thread drains the inbox,
/// sends commands and asks whether the vehicle is still there.
#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

#include "haptel/config/link.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/core/child_process.hpp"
#include "haptel/core/histogram.hpp"
#include "haptel/link/discovered_writers.hpp"
#include "haptel/link/families.hpp"
#include "haptel/link/fault_transport.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/video/video_receiver.hpp"

namespace haptel::mediator {

/// What the operator side can tell of the link and the vehicle's health from
/// the states alone (the vehicle counts malformed and stale commands apart,
/// in its own stop summary; a state carries only how many it accepted).
struct LinkCounts {
  /// States that never arrived: gaps in their sequence numbers.
  uint64_t states_missed = 0;
  /// Times the vehicle's command watchdog tripped after commands had driven it.
  uint64_t watchdog_trips = 0;
  /// Commands the vehicle did not accept — lost on the way, malformed or
  /// stale — up to the last one it applied: the sequence numbers it echoed
  /// minus the commands it counted as accepted, from the first state that
  /// echoes one (commands sent before it listened are not counted). Only
  /// states naming this run's writer as the owner count: another writer's
  /// echo is of its own sequence, not this run's.
  uint64_t commands_dropped = 0;
  /// Video feedback the vehicle refused because another session than its
  /// owner sent it (a stranger on the domain), from the first state this
  /// run received.
  uint64_t video_feedback_refused = 0;
  /// Commands this run sent (safe and release commands included), and the
  /// states its reader took, whoever sent them: what a session file of the
  /// run holds on the command and state topics.
  uint64_t commands_sent = 0;
  uint64_t states_received = 0;
};

/// Vehicle states as they arrive (DDS thread), drained by the session loop.
/// Measures the command round trip from the echo each state carries, and
/// counts what the states show (LinkCounts). One for each family's state:
/// msg::VehicleState (the robot) and msg::BlimpState.
template <typename State>
class StateInboxOf {
 public:
  struct Entry {
    State state;
    int64_t received_ns;
  };
  /// This run's command writer (set before any state is pushed): only
  /// states that name it as the owner echo this run's commands. Unset (a
  /// test's inbox without a channel): every state does.
  void SetOwnWriter(const link::WriterId& writer) { own_writer_ = writer; }
  void Push(const State& s);
  std::deque<Entry> Drain();
  int64_t last_received_ns() const;
  /// Round trip of echoed commands minus their wait at the vehicle, µs
  /// (the histogram is safe to read while the DDS thread records).
  const Histogram& Rtt() const { return rtt_; }
  /// Forgets the round trips so far (a benchmark's warm-up).
  void ResetRtt() { rtt_.Reset(); }
  LinkCounts Counts() const;
  /// Watches for the first state that echoes a command sent at or after
  /// `sent_ns` (MonotonicNs; 0: stop watching): the vehicle obeying a
  /// command given from then on (a fleet's handover).
  void WatchEcho(int64_t sent_ns);
  /// When that state arrived (MonotonicNs); 0: none yet.
  int64_t EchoReceivedNs() const;

 private:
  mutable std::mutex mutex_;
  link::WriterId own_writer_;  ///< set before the DDS thread pushes
  int64_t echo_watch_ns_ = 0;
  int64_t echo_received_ns_ = 0;
  std::deque<Entry> entries_;
  int64_t last_received_ns_ = 0;
  uint64_t last_echo_seq_ = 0;
  LinkCounts counts_;
  bool have_state_ = false;
  uint64_t last_state_seq_ = 0;
  bool watchdog_was_tripped_ = true;
  // The baseline of commands_dropped: the first state echoing an applied command.
  bool have_baseline_ = false;
  uint64_t first_echo_seq_ = 0;
  uint64_t first_accepted_ = 0;
  uint64_t dropped_before_ = 0;  ///< counted against earlier baselines
  // The baseline of video_feedback_refused: the first state (of this vehicle process).
  uint64_t feedback_refused_base_ = 0;
  uint64_t feedback_refused_before_ = 0;  ///< counted against earlier baselines
  Histogram rtt_{10.0, 200000};  // 10 µs bins up to 2 s (a faulted link: 400 ms each way and more)
};
using StateInbox = StateInboxOf<msg::VehicleState>;
using BlimpStateInbox = StateInboxOf<msg::BlimpState>;

/// What the session asks of its vehicle's topics, whatever the family.
class LinkChannel {
 public:
  virtual ~LinkChannel() = default;
  /// Round trip of echoed commands minus their wait at the vehicle, µs.
  virtual const Histogram& Rtt() const = 0;
  virtual void ResetRtt() = 0;
  virtual int64_t last_received_ns() const = 0;
  virtual LinkCounts Counts() const = 0;
  /// Participants writing the state or reading the commands (discovery).
  virtual int VehiclesOnTopic() const = 0;
  /// Sends the family's safe command (every value zero: motors stopped,
  /// every channel neutral); `release` frees the vehicle for another operator.
  virtual void SendSafe(bool release) = 0;
  /// StateInboxOf::WatchEcho and EchoReceivedNs.
  virtual void WatchEcho(int64_t sent_ns) = 0;
  virtual int64_t EchoReceivedNs() const = 0;
  /// The command writer's identity (its DDS GUID; link::kInProcessWriter
  /// on no DDS): what the vehicle binds its ownership to.
  virtual link::WriterId writer() const = 0;
};

/// One family's command writer and state reader (Messages: link's
/// RobotMessages or BlimpMessages), stamping each command with the run's
/// session and sequence.
template <class Messages>
class CommandChannel final : public LinkChannel {
 public:
  using Command = typename Messages::Command;
  using Inbox = StateInboxOf<typename Messages::StateMsg>;
  CommandChannel(link::Participant& participant, const std::string& vehicle, uint64_t session,
                 const std::string& operator_name);
  /// A channel on no DDS: each command message goes to `sink` as it is
  /// sent, and states come only as the caller delivers them (a vehicle
  /// stepped in this process; one vehicle answers). `tap` (null: none) is
  /// handed both as DDS would have carried them, on `vehicle`'s topics.
  CommandChannel(std::function<void(const typename Messages::CommandMsg&)> sink, uint64_t session,
                 const std::string& operator_name, link::SampleTap* tap = nullptr,
                 const std::string& vehicle = "");
  /// Sends `command` stamped now.
  void Send(const Command& command);
  /// A state from the vehicle stepped in this process (a channel on no
  /// DDS), as if it had arrived now: tapped, then into the inbox.
  void Deliver(const typename Messages::StateMsg& state);
  Inbox& inbox() { return inbox_; }
  const Inbox& inbox() const { return inbox_; }

  const Histogram& Rtt() const override { return inbox_.Rtt(); }
  void ResetRtt() override { inbox_.ResetRtt(); }
  int64_t last_received_ns() const override { return inbox_.last_received_ns(); }
  LinkCounts Counts() const override {
    LinkCounts counts = inbox_.Counts();
    counts.commands_sent = seq_;
    counts.states_received = reader_ ? reader_->received() : 0;
    return counts;
  }
  int VehiclesOnTopic() const override;
  void SendSafe(bool release) override;
  void WatchEcho(int64_t sent_ns) override { inbox_.WatchEcho(sent_ns); }
  int64_t EchoReceivedNs() const override { return inbox_.EchoReceivedNs(); }
  link::WriterId writer() const override { return writer_id_; }

 private:
  Inbox inbox_;
  link::WriterId writer_id_ = link::kInProcessWriter;
  typename Messages::CommandMsg message_;
  uint64_t seq_ = 0;
  std::function<void(const typename Messages::CommandMsg&)> sink_;  ///< set: no DDS
  /// With no DDS, what the link would have tapped (nothing on DDS: its
  /// writer and reader tap their own).
  std::unique_ptr<link::Tapped<typename Messages::CommandMsg, typename Messages::CommandType>>
      sent_tap_;
  std::unique_ptr<link::Tapped<typename Messages::StateMsg, typename Messages::StateType>>
      received_tap_;
  // Last: destroyed first, so no DDS callback outlives the inbox.
  std::unique_ptr<typename Messages::CommandWriter> writer_;
  std::unique_ptr<typename Messages::StateReader> reader_;
};
using RobotChannel = CommandChannel<link::RobotMessages>;
using BlimpChannel = CommandChannel<link::BlimpMessages>;

struct VehicleLinkOptions {
  VehicleConfig vehicle;
  LinkConfig link;
  /// The world the spawned simulator drives or flies in (a track, a course).
  std::filesystem::path track_file;
  /// haptel-vehicle to spawn; empty: the vehicle runs elsewhere.
  std::filesystem::path program;
  /// Decode the video (only when something shows or records it).
  bool decode_video = true;
  /// Publish who commands the vehicle on haptel/<vehicle>/selected
  /// (PublishSelected): a fleet's command mux does.
  bool publish_selected = false;
  /// A robot stepped in this process (a simulated-time run): set, nothing
  /// is spawned and nothing joins DDS; each command message goes here as
  /// it is sent, the states are pushed into the robot channel's inbox by
  /// the caller, and no video comes.
  std::function<void(const msg::TreadCommand&)> in_process_robot;
  /// Taps every sample the link sends and receives (a session file's
  /// recorder; null: none). It must outlive the link.
  link::SampleTap* tap = nullptr;
};

/// The writer of haptel/<vehicle>/selected (the IDL's SelectedSource).
class SelectedWriter;
/// The latest status on haptel/<vehicle>/can_log (the IDL's CanLogStatus).
class CanLogInbox;

class VehicleLink {
 public:
  /// Spawns the vehicle (if a program is given) and joins the DDS domain
  /// with the topics of the vehicle's family. Throws std::runtime_error when
  /// either cannot be done.
  explicit VehicleLink(const VehicleLinkOptions& options);
  /// Stops the vehicle: a safe command, then the spawned process ends.
  ~VehicleLink();
  VehicleLink(const VehicleLink&) = delete;
  VehicleLink& operator=(const VehicleLink&) = delete;

  VehicleFamily family() const { return options_.vehicle.family(); }
  /// The command and state topics of the vehicle's family (Messages:
  /// link::RobotMessages or link::BlimpMessages); std::logic_error when
  /// the vehicle is of the other family.
  template <class Messages>
  CommandChannel<Messages>& channel();
  /// Sends a robot's tread commands (each in [-1, 1]) stamped now.
  void Send(const TreadCommand& command) { channel<link::RobotMessages>().Send(command); }
  /// Sends a blimp's command stamped now.
  void Send(const BlimpCommand& command) { channel<link::BlimpMessages>().Send(command); }
  /// The family's safe command: motors stopped, every channel neutral.
  void SendSafe() { channel_->SendSafe(false); }
  /// Safe command (releasing the vehicle), then ends the spawned process. Safe to call twice.
  void Stop();

  const Histogram& Rtt() const { return channel_->Rtt(); }
  void ResetRtt() { channel_->ResetRtt(); }
  int64_t last_received_ns() const { return channel_->last_received_ns(); }
  LinkCounts Counts() const { return channel_->Counts(); }
  /// What this side's fault transport did to what it received (all zero
  /// without a link fault); the vehicle reports its own side on its stderr.
  link::FaultCounts FaultCounts() const;
  /// This side's fault line (null without a link fault): what the operator
  /// receives (states, video) passes it, so its FaultLine::SetRate is the
  /// rate the video arrives at (a capacity schedule).
  link::FaultLine* fault_line() const;
  /// The participant the link's topics are on (a vehicle's further camera
  /// is received on it too: haptel bench video's two cameras).
  link::Participant& participant() { return *participant_; }
  /// The first state echoing a command sent at or after `sent_ns`: when it
  /// arrived (0: none yet). See StateInboxOf::WatchEcho.
  void WatchEcho(int64_t sent_ns) { channel_->WatchEcho(sent_ns); }
  int64_t EchoReceivedNs() const { return channel_->EchoReceivedNs(); }
  const video::VideoReceiver& video() const { return *video_; }
  video::VideoReceiver& video() { return *video_; }
  /// False once a spawned vehicle process has exited (always true for a
  /// vehicle that runs elsewhere).
  bool ProcessAlive();
  /// The spawned process's pid (0: none) and how it ended.
  int pid() const;
  std::string ExitDescription() const;
  const std::string& name() const { return options_.vehicle.name; }
  /// The kind its vehicle file says.
  const std::string& kind() const { return options_.vehicle.kind; }
  int domain() const { return options_.link.domain_id; }

  /// This run's operator session (random, never 0): every command carries
  /// it and the operator's name ("haptel run, user@host pid N"), and the
  /// vehicle obeys one session at a time (its state names the owner). The
  /// last command, in Stop, releases the vehicle.
  uint64_t session() const { return session_; }
  /// This run's command writer (LinkChannel::writer): the vehicle obeys it
  /// and names it in its states (owner_writer) while this run drives. The
  /// session is a label anyone can copy; this is not.
  link::WriterId command_writer() const { return channel_->writer(); }
  /// How many vehicles answer under this name: the participants writing its
  /// state or reading its commands (DDS discovery). More than one is a
  /// conflict: two vehicles named alike on one domain.
  int VehiclesOnTopic() const { return channel_->VehiclesOnTopic(); }
  /// The DDS type of a writer on this vehicle's state topic that is not
  /// its family's state ("" when none was seen): a vehicle of another kind
  /// answering under this name (its state never matches our reader).
  std::string ForeignStateType() const;

  /// Publishes who commands the vehicle now on haptel/<vehicle>/selected
  /// (reliable, transient local: a reader that joins later gets the last):
  /// `source` the selected input ("" when none is), `lock` the lock that
  /// holds it ("" when none does). Only with
  /// VehicleLinkOptions::publish_selected (else nothing). Session thread;
  /// it allocates (the strings): call it on a change and now and then,
  /// never from a real-time loop. False when DDS refused the sample.
  bool PublishSelected(const std::string& source, const std::string& lock);
  /// Readers of the selected topic matched now (0 without the writer).
  int selected_readers() const;
  /// The vehicle's CAN bus log, as its own topic (haptel/<vehicle>/can_log:
  /// a CAN robot that keeps one) last said: into `out` and true when a
  /// status came since the last call. Only a robot on DDS has the topic.
  bool TakeCanLog(msg::CanLogStatus& out);

 private:
  VehicleLinkOptions options_;
  uint64_t session_ = 0;
  std::unique_ptr<ChildProcess> process_;
  link::DiscoveredWriters discovered_;  ///< the participant's listener: outlives it
  std::unique_ptr<link::Participant> participant_;
  std::unique_ptr<LinkChannel> channel_;
  std::unique_ptr<video::VideoReceiver> video_;
  std::unique_ptr<SelectedWriter> selected_;
  std::unique_ptr<CanLogInbox> can_log_;
  std::string operator_name_;
  bool stopped_ = false;
};

template <class Messages>
CommandChannel<Messages>& VehicleLink::channel() {
  if (family() != Messages::kFamily) {
    throw std::logic_error(std::string("vehicle link: '") + name() + "' is a " +
                           ToString(family()) + ", not a " + ToString(Messages::kFamily));
  }
  return static_cast<CommandChannel<Messages>&>(*channel_);
}

extern template class CommandChannel<link::RobotMessages>;
extern template class CommandChannel<link::BlimpMessages>;

}  // namespace haptel::mediator
