#pragma once
/// @file What a test or a benchmark hears of a robot run on its DDS domain,
/// beside the run, from its vehicle's states alone: the commands the
/// vehicle obeyed (each state names the last one: when the run sent it, and
/// the motor levels it set) and its bumpers (when the first contact came
/// after Arm). Not from the command topic: a second reader there is a second
/// vehicle to the run, which ends it as a conflict.
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "haptel/config/link.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/link/participant.hpp"
#include "haptel/link/topic.hpp"

namespace haptel::testing {

/// One command the vehicle obeyed: when the run sent it (CLOCK_MONOTONIC,
/// ns, the run's clock and this one's on one machine) and the motor levels
/// it set (signed; 0 stopped).
struct HeardCommand {
  int64_t t_ns = 0;
  double left = 0.0;
  double right = 0.0;
  bool moves() const { return left != 0.0 || right != 0.0; }
};

class RunWatch {
 public:
  /// Subscribes to `vehicle`'s state topic with `link`'s settings (the
  /// run's: its domain, transports, security).
  RunWatch(const LinkConfig& link, const std::string& vehicle)
      : participant_(link, "run-watch"),
        states_(participant_, link::TopicName(vehicle, "state"), link::Profile::kState,
                [this](const msg::VehicleState& s) {
                  std::lock_guard lock(mutex_);
                  ++states_seen_;
                  const int64_t sent = s.last_command_sent_ns();
                  if (sent > 0 && (commands_seen_.empty() || commands_seen_.back().t_ns != sent)) {
                    commands_seen_.push_back({sent, static_cast<double>(s.motor_left_level()),
                                              static_cast<double>(s.motor_right_level())});
                  }
                  if (armed_ && contact_ns_ == 0 && (s.bumper_left() || s.bumper_right()))
                    contact_ns_ = MonotonicNs();
                }) {}

  /// States heard so far (the vehicle answers once there is one).
  int states() {
    std::lock_guard lock(mutex_);
    return states_seen_;
  }
  /// From now on, the first state with a bumper pressed is the contact.
  void Arm() {
    std::lock_guard lock(mutex_);
    armed_ = true;
  }
  /// When the first contact after Arm arrived; 0: none yet.
  int64_t contact_ns() {
    std::lock_guard lock(mutex_);
    return contact_ns_;
  }
  std::vector<HeardCommand> commands() {
    std::lock_guard lock(mutex_);
    return commands_seen_;
  }

 private:
  link::Participant participant_;
  std::mutex mutex_;
  std::vector<HeardCommand> commands_seen_;
  int states_seen_ = 0;
  bool armed_ = false;
  int64_t contact_ns_ = 0;
  link::StateReader states_;  // last: destroyed first, no callback after
};

}  // namespace haptel::testing
