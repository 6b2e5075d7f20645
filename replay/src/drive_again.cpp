#include "haptel/replay/drive_again.hpp"

#include <fastdds/rtps/common/SerializedPayload.h>

#include <cmath>
#include <cstring>
#include <optional>
#include <string>

#include "haptel/config/track.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/geometry2d.hpp"
#include "haptel/core/loop_meter.hpp"
#include "haptel/mediator/lap_timer.hpp"
#include "haptel/mediator/vehicle_link.hpp"
#include "haptel/msg/haptelPubSubTypes.h"
#include "haptel/record/session_cdr.hpp"
#include "haptel/record/session_channels.hpp"
#include "haptel/session/sessionPubSubTypes.h"

namespace haptel::replay {
namespace {

namespace channels = record::session;

using record::DecodeCdr;

/// The channel of schema `schema` (and `direction`, when the channel says
/// one), or empty.
std::string TopicOf(const mcap::Reader& reader, std::string_view schema,
                    std::string_view direction) {
  for (const auto& [id, channel] : reader.channels()) {
    const auto s = reader.schemas().find(channel.schema_id);
    if (s == reader.schemas().end() || s->second.name != schema) continue;
    const auto d = channel.metadata.find("direction");
    if (d != channel.metadata.end() && d->second != direction) continue;
    return channel.topic;
  }
  return {};
}

constexpr int64_t kTickNs = 5'000'000;  ///< the drive's loop: 200 Hz
/// The sender's SCHED_FIFO priority, as the session thread's whose commands
/// it sends again (mediator/src/session.cpp): starved on a loaded host, a
/// command came late past the vehicle's 0.2-s watchdog and the open-loop
/// path was not the record's. Given up for good after a tick of ten periods.
constexpr int kSenderPriority = 60;
constexpr int64_t kLoseRealtimePeriods = 10;
constexpr double kSettleS = 1.0;  ///< after the last command
/// After the settle time, the drive waits at most this much longer for a
/// state saying the vehicle is at rest: on a loaded host the states came
/// up to a second behind, and the drive ended before the one that crossed
/// the gate had arrived.
constexpr double kCatchUpS = 10.0;
/// At rest: its motors at level 0 and its speed below this (m/s).
constexpr double kRestSpeed = 0.005;
/// A vehicle must answer this long after the start (the run's own start-up
/// timeout, session_loop.hpp's VehicleHealth::kStartupTimeout_s).
constexpr double kStartupTimeoutS = 15.0;

}  // namespace

RecordedDrive ReadRecordedDrive(const mcap::Reader& reader) {
  const std::string file = reader.path().string();
  const std::string command_topic =
      TopicOf(reader, std::string(channels::kDdsSchemaPrefix) + "TreadCommand", "sent");
  const std::string state_topic =
      TopicOf(reader, std::string(channels::kDdsSchemaPrefix) + "VehicleState", "received");
  if (command_topic.empty() || state_topic.empty()) {
    throw cli::InputError(file + ": no robot commands sent (" +
                          std::string(channels::kDdsSchemaPrefix) +
                          "TreadCommand) or no robot state received (VehicleState): nothing to "
                          "drive again (only a robot's session is driven again)");
  }
  RecordedDrive recorded;
  uint64_t undecoded = 0;
  reader.ForEachMessage(0, UINT64_MAX,
                        {command_topic, state_topic, std::string(channels::kLapEventsTopic)},
                        [&](const mcap::MessageView& m) {
                          if (m.channel->topic == state_topic) {
                            if (recorded.first_state_ns == 0)
                              recorded.first_state_ns = m.log_time_ns;
                            return;
                          }
                          if (m.channel->topic == command_topic) {
                            msg::TreadCommand c;
                            if (!DecodeCdr<msg::TreadCommandPubSubType>(m, c)) {
                              ++undecoded;
                              return;
                            }
                            if (c.release()) return;  // the run's end: this drive releases its own
                            if (recorded.first_state_ns == 0) {
                              ++recorded.commands_before_up;
                              return;
                            }
                            recorded.commands.push_back({m.log_time_ns, {c.left(), c.right()}});
                            return;
                          }
                          session::Event e;
                          if (!DecodeCdr<session::EventPubSubType>(m, e)) {
                            ++undecoded;
                            return;
                          }
                          if (recorded.gates < 0) recorded.gates = 0;
                          if (e.kind() == "gate") ++recorded.gates;
                          if (e.kind() == "finish") {
                            recorded.completed = true;
                            recorded.lap_time_s = e.value();
                          }
                        });
  if (undecoded > 0) {
    throw cli::InputError(file + ": " + std::to_string(undecoded) +
                          " commands or lap events do not decode against their schema");
  }
  if (recorded.commands.empty()) {
    throw cli::InputError(file + ": no command was sent after the vehicle first answered (" +
                          command_topic + "): nothing to drive again");
  }
  return recorded;
}

DriveReport DriveAgain(const RecordedDrive& recorded, const mediator::SessionSetup& setup,
                       const std::atomic<bool>& interrupted) {
  mediator::VehicleLinkOptions options;
  options.vehicle = setup.vehicle;
  options.link = setup.run.link;
  options.track_file = setup.track.file;
  options.program = setup.attach ? std::filesystem::path() : setup.vehicle_program;
  options.decode_video = false;
  mediator::VehicleLink link(options);
  auto& channel = link.channel<link::RobotMessages>();
  const Track track(setup.track);
  mediator::LapTimer lap(track);  // keeps a reference to the track

  DriveReport report;
  report.commands_before_up = recorded.commands_before_up;
  report.commands_s =
      NsToS(static_cast<int64_t>(recorded.commands.back().log_ns - recorded.first_state_ns));
  report.gates_total = lap.gates_total();
  report.recorded_gates = recorded.gates;
  report.recorded_completed = recorded.completed;
  report.recorded_lap_time_s = recorded.lap_time_s;

  const int64_t t0 = MonotonicNs();
  int64_t up_ns = 0;        // when this vehicle first answered this sender (0: not yet)
  int64_t heard_from = -1;  // its commands received in its first state
  bool at_rest = false;     // the newest state: motors at level 0, not moving
  size_t next = 0;          // the commands due so far
  size_t sent = 0;          // the commands due when one was last sent
  int64_t tick = t0;
  std::optional<RealtimeWhile> realtime(std::in_place, kSenderPriority);
  for (;;) {
    tick += kTickNs;
    SleepUntilNs(tick);
    const int64_t now = MonotonicNs();
    if (interrupted.load()) break;
    for (const auto& entry : channel.inbox().Drain()) {
      const msg::VehicleState& s = entry.state;
      // Up once it has heard this sender (the safe commands below: its count
      // of commands grew since its first state): a state can arrive before
      // the command topic's reader has matched the sender, and the drive's
      // first commands were then lost on a loaded host, its turn coming
      // early on a shorter straight.
      if (heard_from < 0) heard_from = static_cast<int64_t>(s.commands_received());
      if (up_ns == 0 && static_cast<int64_t>(s.commands_received()) > heard_from)
        up_ns = entry.received_ns;
      const double ts = NsToS(entry.received_ns - t0);
      if (s.pose_valid()) lap.Update(ts, Vec2(s.x(), s.y()));
      lap.UpdateContact(ts, s.bumper_left() || s.bumper_right());
      if (s.watchdog_tripped() && sent > 0 && next < recorded.commands.size())
        ++report.watchdog_stops;
      at_rest = s.motor_left_level() == 0 && s.motor_right_level() == 0 &&
                std::abs(s.speed()) < kRestSpeed;
    }
    if (lap.completed()) break;
    if (up_ns == 0) {
      if (NsToS(now - t0) > kStartupTimeoutS) {
        throw std::runtime_error("vehicle '" + setup.vehicle.name + "' did not answer within " +
                                 std::to_string(static_cast<int>(kStartupTimeoutS)) +
                                 " s on domain " + std::to_string(setup.run.link.domain_id));
      }
      link.SendSafe();  // stopped, as the run's commands were before it answered
      continue;
    }
    const int64_t since_up = now - up_ns;
    while (next < recorded.commands.size() &&
           static_cast<int64_t>(recorded.commands[next].log_ns - recorded.first_state_ns) <=
               since_up) {
      ++next;
    }
    if (next > sent) {
      // The latest command due, once: a late loop sends one, it does not catch up.
      link.Send(recorded.commands[next - 1].command);
      ++report.commands_sent;
      sent = next;
    }
    // Done once every command was sent, the vehicle had time to settle, and
    // its states have caught up with it: the newest says it is at rest.
    const double after_s = NsToS(since_up) - report.commands_s - kSettleS;
    if (next == recorded.commands.size() && after_s > 0.0 && (at_rest || after_s > kCatchUpS))
      break;
    if (realtime && MonotonicNs() - now > kLoseRealtimePeriods * kTickNs) realtime.reset();
  }
  link.Stop();
  report.gates_passed = lap.gates_passed();
  report.completed = lap.completed();
  report.lap_time_s = lap.lap_time_s();
  return report;
}

}  // namespace haptel::replay
