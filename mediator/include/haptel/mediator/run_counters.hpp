#pragma once
/// @file Everything the session's parts count, gathered under fixed names,
/// and whether the servo and physics loops keep their rates.
///
/// The loops count instead of logging (DESIGN: status codes and counters in
/// loops); like MuJoCo's warning counters, every count reaches the user: the
/// progress line shows the non-zero ones, the JSON line and the database row
/// carry them all. The names and their meanings are listed in docs/results.md, "The
/// JSON line"; CollectCounters gives them in that order, zeros included
/// (a part the run does not have counts 0).
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "haptel/core/loop_meter.hpp"
#include "haptel/mediator/run_record.hpp"

namespace haptel::mediator {

class HapticSide;
class VehicleLink;
struct SessionPhysics;
class SessionView;

/// The counters of a session's parts, now (safe while they run). `physics`
/// and `view` may be null (the run has none).
std::vector<RunCounter> CollectCounters(const HapticSide& haptic, const SessionPhysics* physics,
                                        const VehicleLink& vehicle, const SessionView* view);

/// "name n, name n" of the counters that are not zero ("" when all are).
std::string NonZeroCounters(const std::vector<RunCounter>& counters);

/// A loop below this share of its target rate cannot keep its rate.
constexpr double kRateShortShare = 0.9;

/// Watches one loop's rate against its target, interval by interval (the
/// progress interval) and over the run, from the loop's own tick count.
class RateCheck {
 public:
  /// Intervals shorter than this are not judged (too few ticks to tell).
  static constexpr double kMinIntervalS = 0.5;

  /// `name` as the messages say it ("servo", "physics"); starts the first
  /// interval at `now_ns` with the loop's `ticks` so far.
  RateCheck(std::string name, double target_hz, uint64_t ticks, int64_t now_ns);

  /// Ends the interval at `now_ns`, when the loop had ticked `ticks` times in
  /// all, and starts the next. Returns "physics 306 Hz of 10000 Hz: cannot
  /// keep its rate" when the interval's rate was below kRateShortShare of the
  /// target, nothing otherwise (or when the interval was too short to judge).
  std::optional<std::string> EndInterval(uint64_t ticks, int64_t now_ns);
  /// Judges the run as a whole from the loop's own statistics (its rate from
  /// first to last tick); returns the message as EndInterval does.
  std::optional<std::string> EndRun(const LoopStats& run);

  /// Whether any interval, or the run, was short of the target.
  bool short_of_rate() const { return short_; }
  double target_hz() const { return target_hz_; }

 private:
  std::optional<std::string> Judge(double rate_hz);

  std::string name_;
  double target_hz_;
  uint64_t ticks_;
  int64_t start_ns_;
  bool short_ = false;
};

/// The session's watch over its parts' loops: their rates interval by
/// interval and over the run, and their counters. The parts must outlive it.
class LoopWatch {
 public:
  /// Starts the first interval at `now_ns`. `physics` and `view` may be null.
  LoopWatch(const HapticSide& haptic, const SessionPhysics* physics, const VehicleLink& vehicle,
            const SessionView* view, int64_t now_ns);

  /// A physics world built during the run (an interface that needs one was
  /// switched to): its loop is watched from `now_ns` on.
  void AddPhysics(const SessionPhysics* physics, int64_t now_ns);
  const SessionPhysics* physics() const { return physics_; }
  /// Ends an interval (a progress interval, or the run's last stretch) at
  /// `now_ns`: a line for each loop that fell short of its rate over it.
  std::vector<std::string> EndInterval(int64_t now_ns);
  /// Every counter now (CollectCounters).
  std::vector<RunCounter> Counters() const;
  /// Once the parts have stopped: judges each loop over the whole run, and
  /// fills `rec`'s target rates, physics rate, rate flags and counters.
  void Finish(RunRecord& rec);

 private:
  const HapticSide& haptic_;
  const SessionPhysics* physics_;
  const VehicleLink& vehicle_;
  const SessionView* view_;
  RateCheck servo_;
  std::optional<RateCheck> physics_rate_;
};

}  // namespace haptel::mediator
