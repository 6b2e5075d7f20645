#pragma once
/// @file Who commands a vehicle when several sources could: inputs with
/// priorities and time-outs, and locks that hold the vehicle, after ROS's
/// twist_mux and what its users asked of it.
///
/// - An input is a source of commands (the operator's interface, a second
///   station, an autonomy stack). It is *live* while its newest command is
///   younger than its time-out. The selected input is the live one of the
///   highest priority (the first declared among equals).
/// - A lock holds the vehicle: while it is engaged, no input of its
///   priority or below is selected. It is engaged while its newest message
///   says so, or when it has a time-out and nothing has been heard within it
///   (a dead man's switch: a silent lock holds, as twist_mux's do).
/// - When a lock takes the vehicle from the input that had it, or no input
///   is live, the vehicle is to be sent zero at once rather than left to
///   its own watchdog (twist_mux PR #42, "Publish zero if locked").
/// - Which input is selected, or which lock holds, is a name anyone can
///   read (twist_mux publishes it on a topic; Haptel publishes it with the
///   vehicle's state and on the fleet's view).
///
/// Time is the caller's (seconds on one clock), so tests step it. Not
/// thread-safe; allocation-free after construction.
#include <cstddef>
#include <string>
#include <vector>

namespace haptel::mediator {

struct MuxInputSpec {
  std::string name;
  int priority = 0;        ///< 0..255, higher wins
  double timeout_s = 0.5;  ///< a command older than this is not live (> 0)
};

struct MuxLockSpec {
  std::string name;
  int priority = 0;  ///< holds inputs of this priority and below
  /// > 0: silence for this long engages the lock (a heartbeat); 0: only an
  /// explicit message engages or releases it.
  double timeout_s = 0.0;
};

class CommandMux {
 public:
  /// What the vehicle is to be sent now.
  struct Selection {
    int input = -1;  ///< the index of the input that drives it; -1: none
    int lock = -1;   ///< the engaged lock of the highest priority; -1: none
    /// Send zero (the vehicle's safe command): no input is selected, whether
    /// because a lock holds it or because none is live.
    bool zero = true;
    bool operator==(const Selection&) const = default;
  };

  /// Throws std::invalid_argument naming the entry for an empty or repeated
  /// name, a priority outside 0..255 or a time-out that is not > 0 (inputs)
  /// or >= 0 (locks).
  CommandMux(std::vector<MuxInputSpec> inputs, std::vector<MuxLockSpec> locks);

  /// A command arrived from input `index` at `t_s`.
  void OnInput(int index, double t_s);
  /// Lock `index` says `engaged` at `t_s` (a heartbeat of a timed lock too).
  void OnLock(int index, bool engaged, double t_s);

  /// The selection at `t_s`, and whether it changed since the last call
  /// (`changed`): a change to zero is to be sent at once.
  Selection Select(double t_s, bool* changed = nullptr);

  /// "keys", "lock:handover", or "none": the selection as a name.
  const std::string& SelectedName(const Selection& s) const;

  int input_index(const std::string& name) const;  ///< -1: no such input
  int lock_index(const std::string& name) const;   ///< -1: no such lock
  const std::vector<MuxInputSpec>& inputs() const { return inputs_; }
  const std::vector<MuxLockSpec>& locks() const { return locks_; }

 private:
  bool LockEngaged(size_t i, double t_s) const;

  std::vector<MuxInputSpec> inputs_;
  std::vector<MuxLockSpec> locks_;
  std::vector<double> input_seen_s_;     ///< newest command; -inf: never
  std::vector<double> lock_seen_s_;      ///< newest message; -inf: never
  std::vector<char> lock_engaged_;       ///< what the newest message said
  std::vector<std::string> lock_names_;  ///< "lock:<name>", made once
  Selection last_;
  bool selected_once_ = false;
  std::string none_ = "none";
};

}  // namespace haptel::mediator
