#pragma once
/// @file What a test or a benchmark hears of a robot run on its DDS domain,
/// beside the run: the commands it sends (when each arrived) and its
/// vehicle's bumpers (when the first contact came after Arm).
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "haptel/config/link.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/link/participant.hpp"
#include "haptel/link/topic.hpp"

namespace haptel::testing {

/// One command as it arrived (CLOCK_MONOTONIC, ns).
struct HeardCommand {
  int64_t t_ns = 0;
  double left = 0.0;
  double right = 0.0;
  bool moves() const { return left != 0.0 || right != 0.0; }
};

class RunWatch {
 public:
  /// Subscribes to `vehicle`'s command and state topics with `link`'s
  /// settings (the run's: its domain, transports, security).
  RunWatch(const LinkConfig& link, const std::string& vehicle)
      : participant_(link, "run-watch"),
        commands_(participant_, link::TopicName(vehicle, "command"), link::Profile::kCommand,
                  [this](const msg::TreadCommand& c) {
                    std::lock_guard lock(mutex_);
                    commands_seen_.push_back({MonotonicNs(), c.left(), c.right()});
                  }),
        states_(participant_, link::TopicName(vehicle, "state"), link::Profile::kState,
                [this](const msg::VehicleState& s) {
                  std::lock_guard lock(mutex_);
                  ++states_seen_;
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
  link::TreadCommandReader commands_;  // last: destroyed first, no callback after
  link::StateReader states_;
};

}  // namespace haptel::testing
