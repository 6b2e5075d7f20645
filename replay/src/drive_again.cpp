#include "haptel/replay/drive_again.hpp"

#include <fastdds/rtps/common/SerializedPayload.h>

#include <cstring>
#include <string>

#include "haptel/config/track.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/geometry2d.hpp"
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
constexpr double kSettleS = 1.0;        ///< after the last command
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
  int64_t up_ns = 0;  // when this vehicle first answered (0: not yet)
  size_t next = 0;    // the commands due so far
  size_t sent = 0;    // the commands due when one was last sent
  int64_t tick = t0;
  for (;;) {
    tick += kTickNs;
    SleepUntilNs(tick);
    const int64_t now = MonotonicNs();
    if (interrupted.load()) break;
    for (const auto& entry : channel.inbox().Drain()) {
      const msg::VehicleState& s = entry.state;
      if (up_ns == 0) up_ns = entry.received_ns;
      const double ts = NsToS(entry.received_ns - t0);
      if (s.pose_valid()) lap.Update(ts, Vec2(s.x(), s.y()));
      lap.UpdateContact(ts, s.bumper_left() || s.bumper_right());
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
    if (next == recorded.commands.size() && NsToS(since_up) > report.commands_s + kSettleS) break;
  }
  link.Stop();
  report.gates_passed = lap.gates_passed();
  report.completed = lap.completed();
  report.lap_time_s = lap.lap_time_s();
  return report;
}

}  // namespace haptel::replay
