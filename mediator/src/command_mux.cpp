#include "haptel/mediator/command_mux.hpp"

#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>

namespace haptel::mediator {

namespace {

constexpr double kNever = -std::numeric_limits<double>::infinity();

void Check(const std::string& kind, size_t i, const std::string& name, int priority,
           bool timeout_ok, std::set<std::string>& names) {
  const std::string which = kind + "[" + std::to_string(i) + "]";
  if (name.empty()) throw std::invalid_argument("command mux: " + which + ".name: expected a name");
  if (!names.insert(kind + ":" + name).second)
    throw std::invalid_argument("command mux: " + which + ".name: '" + name + "' is named twice");
  if (priority < 0 || priority > 255)
    throw std::invalid_argument("command mux: " + which + ".priority: expected 0..255, got " +
                                std::to_string(priority));
  if (!timeout_ok)
    throw std::invalid_argument(
        "command mux: " + which + ".timeout_s: expected " +
        (kind == "inputs" ? "a time-out above 0 s" : "0 (none) or a time-out above 0 s"));
}

}  // namespace

CommandMux::CommandMux(std::vector<MuxInputSpec> inputs, std::vector<MuxLockSpec> locks)
    : inputs_(std::move(inputs)), locks_(std::move(locks)) {
  std::set<std::string> names;
  for (size_t i = 0; i < inputs_.size(); ++i) {
    const MuxInputSpec& in = inputs_[i];
    Check("inputs", i, in.name, in.priority, std::isfinite(in.timeout_s) && in.timeout_s > 0,
          names);
  }
  for (size_t i = 0; i < locks_.size(); ++i) {
    const MuxLockSpec& l = locks_[i];
    Check("locks", i, l.name, l.priority, std::isfinite(l.timeout_s) && l.timeout_s >= 0, names);
    lock_names_.push_back("lock:" + l.name);
  }
  input_seen_s_.assign(inputs_.size(), kNever);
  lock_seen_s_.assign(locks_.size(), kNever);
  lock_engaged_.assign(locks_.size(), 0);
}

void CommandMux::OnInput(int index, double t_s) {
  if (index < 0 || static_cast<size_t>(index) >= inputs_.size()) return;
  input_seen_s_[static_cast<size_t>(index)] = t_s;
}

void CommandMux::OnLock(int index, bool engaged, double t_s) {
  if (index < 0 || static_cast<size_t>(index) >= locks_.size()) return;
  lock_seen_s_[static_cast<size_t>(index)] = t_s;
  lock_engaged_[static_cast<size_t>(index)] = engaged ? 1 : 0;
}

bool CommandMux::LockEngaged(size_t i, double t_s) const {
  if (lock_engaged_[i]) return true;
  // A heartbeat lock engages when its heartbeat stops (or never started).
  return locks_[i].timeout_s > 0 && t_s - lock_seen_s_[i] > locks_[i].timeout_s;
}

CommandMux::Selection CommandMux::Select(double t_s, bool* changed) {
  Selection s;
  int held_below = -1;  // inputs of this priority and below are held
  for (size_t i = 0; i < locks_.size(); ++i) {
    if (!LockEngaged(i, t_s)) continue;
    if (locks_[i].priority > held_below) {
      held_below = locks_[i].priority;
      s.lock = static_cast<int>(i);
    }
  }
  int best = -1;
  for (size_t i = 0; i < inputs_.size(); ++i) {
    const bool live = t_s - input_seen_s_[i] <= inputs_[i].timeout_s;
    if (!live || inputs_[i].priority <= held_below) continue;
    if (best < 0 || inputs_[i].priority > inputs_[static_cast<size_t>(best)].priority)
      best = static_cast<int>(i);
  }
  s.input = best;
  s.zero = best < 0;
  if (changed) *changed = !selected_once_ || !(s == last_);
  last_ = s;
  selected_once_ = true;
  return s;
}

const std::string& CommandMux::SelectedName(const Selection& s) const {
  if (s.input >= 0) return inputs_[static_cast<size_t>(s.input)].name;
  if (s.lock >= 0) return lock_names_[static_cast<size_t>(s.lock)];
  return none_;
}

int CommandMux::input_index(const std::string& name) const {
  for (size_t i = 0; i < inputs_.size(); ++i) {
    if (inputs_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

int CommandMux::lock_index(const std::string& name) const {
  for (size_t i = 0; i < locks_.size(); ++i) {
    if (locks_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace haptel::mediator
