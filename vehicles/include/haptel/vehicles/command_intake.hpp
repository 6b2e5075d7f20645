#pragma once
/// @file How commands reach a vehicle node's control loop — the same for
/// every vehicle, whatever its command type: the DDS thread drops a
/// malformed command (counted), one from another writer than the
/// vehicle's owner's (counted, CommandOwner) and a stale one (counted,
/// CommandSequence) and hands the rest over through a seqlock; the control thread takes the
/// newest, feeds the watchdog with its arrival time and asks it whether the
/// vehicle is to be made safe. Allocation-free on both threads.
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstdio>

#include "haptel/core/clock.hpp"
#include "haptel/core/seqlock.hpp"
#include "haptel/link/writer_id.hpp"
#include "haptel/vehicles/command_watchdog.hpp"

namespace haptel::vehicles {

/// Which commands a vehicle takes: newer sequence numbers only, since
/// best-effort delivery may reorder — unless the sender restarted (its
/// sequence began again) and the last accepted command is older than the
/// watchdog timeout. Called from the DDS thread only.
class CommandSequence {
 public:
  explicit CommandSequence(double restart_after_s) : restart_after_ns_(SToNs(restart_after_s)) {}
  /// True (and remembered) when `seq` received at `now_ns` is to be applied.
  bool Accept(uint64_t seq, int64_t now_ns) {
    const bool restarted = now_ns - last_ns_ > restart_after_ns_;
    if (seq <= last_seq_ && !restarted) return false;
    last_seq_ = seq;
    last_ns_ = now_ns;
    return true;
  }
  /// Forgets the last command: the next one is taken whatever its number (a
  /// new sender, whose sequence starts afresh).
  void Reset() {
    last_seq_ = 0;
    last_ns_ = 0;
  }

 private:
  int64_t restart_after_ns_;
  uint64_t last_seq_ = 0;
  int64_t last_ns_ = 0;
};

/// Who sent a command: the writer DDS says it came from (what ownership is
/// bound to: nobody else's writer has its GUID), the operator session it
/// names (a random id, one per run: a label, read off the wire by anyone)
/// and its operator's name; `release` on an owner's last command frees the
/// vehicle at once.
struct CommandSender {
  link::WriterId writer;
  uint64_t session = 0;
  const char* name = "";
  bool release = false;
};

/// The writer a vehicle obeys, as its state reports it.
struct CommandOwnerInfo {
  link::WriterId writer;  ///< empty: nobody owns the vehicle
  uint64_t session = 0;   ///< the session its commands name (0: nobody owns the vehicle)
  char name[64] = "";
  int64_t since_wall_ns = 0;  ///< when it took the vehicle (CLOCK_REALTIME; 0: nobody)
};

/// One operator at a time drives a vehicle: one command writer (its DDS
/// GUID, CommandSender::writer), whatever session its commands name — a
/// stranger that copies the owner's session off the wire is refused like
/// anybody else. The first writer to send takes the vehicle and keeps it
/// while its commands keep coming; it is free again when that writer
/// releases it (its last command says so) or falls silent for
/// `free_after_s` — longer than any watchdog, so a link's hiccup does not
/// hand the vehicle to somebody else. Other writers' commands (and their
/// releases) are refused (counted); the state names the owner so their
/// operator can say who has it, and the owner's operator can tell it lost
/// control. Called from the DDS thread only; owner() from any thread.
class CommandOwner {
 public:
  static constexpr double kFreeAfter_s = 2.0;
  explicit CommandOwner(double free_after_s = kFreeAfter_s) : free_after_ns_(SToNs(free_after_s)) {}

  enum class Verdict {
    kOwner,     ///< the owner's command (it kept or just took the vehicle)
    kNewOwner,  ///< the owner's command, and the owner changed with it
    kRefused,   ///< another writer owns the vehicle
  };
  Verdict Admit(const CommandSender& from, int64_t now_ns) {
    const bool free = !owned_ || now_ns - last_ns_ > free_after_ns_;
    if (!free && from.writer != writer_) {
      refused_.fetch_add(1, std::memory_order_relaxed);
      return Verdict::kRefused;
    }
    const bool changed = !owned_ || from.writer != writer_;
    writer_ = from.writer;
    last_ns_ = now_ns;
    heard_wall_ns_.store(WallNs(), std::memory_order_relaxed);
    owned_ = !from.release;
    held_until_ns_.store(owned_ ? now_ns + free_after_ns_ : 0, std::memory_order_relaxed);
    if (changed || from.release) {
      CommandOwnerInfo info;
      if (owned_) {
        info.writer = writer_;
        info.session = from.session;
        std::snprintf(info.name, sizeof info.name, "%s", from.name != nullptr ? from.name : "");
        info.since_wall_ns = WallNs();
      }
      info_.Store(info);
    }
    return changed ? Verdict::kNewOwner : Verdict::kOwner;
  }
  /// The owner as it took the vehicle, even after its lease ran out (see OwnerAt).
  CommandOwnerInfo owner() const { return info_.Load(); }
  /// The owner at `now_ns`: nobody once its lease ran out (released, or
  /// silent for free_after_s: its commands are its heartbeat), though no
  /// other writer has taken it yet. Any thread.
  CommandOwnerInfo OwnerAt(int64_t now_ns) const {
    if (now_ns > held_until_ns_.load(std::memory_order_relaxed)) return {};
    return info_.Load();
  }
  /// When the owner's last command came (CLOCK_REALTIME; 0: none yet). Any thread.
  int64_t heard_wall_ns() const { return heard_wall_ns_.load(std::memory_order_relaxed); }
  uint64_t refused() const { return refused_.load(); }
  /// Whether a writer of `writer`'s participant owns it at `now_ns`: it
  /// took it, has not released it and has not fallen silent. Any thread.
  bool HeldByParticipantOf(const link::WriterId& writer, int64_t now_ns) const {
    if (now_ns > held_until_ns_.load(std::memory_order_relaxed)) return false;
    const CommandOwnerInfo info = info_.Load();
    return !info.writer.empty() && info.writer.SameParticipant(writer);
  }

 private:
  int64_t free_after_ns_;
  bool owned_ = false;
  link::WriterId writer_;
  int64_t last_ns_ = 0;
  Seqlock<CommandOwnerInfo> info_;
  std::atomic<int64_t> held_until_ns_{0};  ///< the owner's lease ends (0: nobody owns it)
  std::atomic<int64_t> heard_wall_ns_{0};
  std::atomic<uint64_t> refused_{0};
};

/// Writers that may not drive however free the vehicle is: those of a
/// participant that holds one of its cameras (a camera station, issue 38:
/// the vehicle node asks each camera's intake, HeldByParticipantOf). With
/// DDS Security a station's identity may not even write a driving command;
/// without, this is what refuses it. Asked on the DDS thread; allocation-free.
class DrivingBar {
 public:
  virtual ~DrivingBar() = default;
  virtual bool Bars(const link::WriterId& writer, int64_t now_ns) const = 0;
};

/// A command as the control loop applies it, with what the state echoes.
template <typename Command>
struct ReceivedCommand {
  uint64_t seq = 0;  ///< 0: none yet
  int64_t sent_ns = 0;
  int64_t received_ns = 0;
  Command command{};
};

template <typename Command>
class CommandIntake {
 public:
  /// The watchdog's timeout, also the sequence's restart age (s, > 0).
  explicit CommandIntake(double watchdog_timeout_s)
      : sequence_(watchdog_timeout_s),
        watchdog_(watchdog_timeout_s),
        applied_version_(latest_.Version()) {}

  /// DDS thread: a command received at `now_ns` from `from`; `valid` is its
  /// range check. Returns whether it was taken.
  bool Offer(bool valid, const CommandSender& from, uint64_t seq, int64_t sent_ns,
             const Command& command, int64_t now_ns) {
    if (!valid) {
      malformed_.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    if (bar_ != nullptr && bar_->Bars(from.writer, now_ns)) {
      barred_.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    const CommandOwner::Verdict verdict = owner_.Admit(from, now_ns);
    if (verdict == CommandOwner::Verdict::kRefused) return false;
    // A new owner's sequence starts afresh, whatever the last one's reached.
    if (verdict == CommandOwner::Verdict::kNewOwner) sequence_.Reset();
    if (!sequence_.Accept(seq, now_ns)) {
      stale_.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    accepted_.fetch_add(1, std::memory_order_relaxed);
    latest_.Store({seq, sent_ns, now_ns, command});
    return true;
  }

  /// Control thread, once a tick: takes the newest command and checks the
  /// watchdog. True when expired (no command within the timeout, or none
  /// yet): the vehicle is to be made safe.
  bool Poll(int64_t now_ns) {
    const uint64_t version = latest_.Version();
    if (version != applied_version_) {
      applied_version_ = version;
      applied_ = latest_.Load();
      watchdog_.Feed(applied_.received_ns);
    }
    const bool expired = watchdog_.Check(now_ns);
    expired_.store(expired, std::memory_order_relaxed);
    trips_.store(watchdog_.trips(), std::memory_order_relaxed);
    return expired;
  }

  /// Control thread: the command taken by the last Poll.
  const ReceivedCommand<Command>& applied() const { return applied_; }
  /// Age of the applied command at `now_ns` (0 before the first).
  int64_t AppliedAgeNs(int64_t now_ns) const {
    return applied_.seq == 0 ? 0 : now_ns - applied_.received_ns;
  }

  // Any thread.
  uint64_t accepted() const { return accepted_.load(); }
  uint64_t malformed() const { return malformed_.load(); }
  uint64_t stale() const { return stale_.load(); }
  /// Commands from a writer that did not own the vehicle, or that may not
  /// drive it (SetBar): dropped.
  uint64_t refused() const { return owner_.refused() + barred_.load(); }
  /// Set-up, before the first Offer: writers `bar` bars are refused (it
  /// must outlive the intake; null: none).
  void SetBar(const DrivingBar* bar) { bar_ = bar; }
  /// The writer (and session) the vehicle obeys now.
  CommandOwnerInfo owner() const { return owner_.owner(); }
  /// See CommandOwner::OwnerAt and heard_wall_ns. Any thread.
  CommandOwnerInfo OwnerAt(int64_t now_ns) const { return owner_.OwnerAt(now_ns); }
  int64_t owner_heard_wall_ns() const { return owner_.heard_wall_ns(); }
  /// See CommandOwner::HeldByParticipantOf. Any thread.
  bool HeldByParticipantOf(const link::WriterId& writer, int64_t now_ns) const {
    return owner_.HeldByParticipantOf(writer, now_ns);
  }
  uint64_t watchdog_trips() const { return trips_.load(); }
  bool watchdog_expired() const { return expired_.load(); }

 private:
  const DrivingBar* bar_ = nullptr;
  CommandOwner owner_;        // DDS thread
  CommandSequence sequence_;  // DDS thread
  Seqlock<ReceivedCommand<Command>> latest_;
  CommandWatchdog watchdog_;  // control thread
  uint64_t
      applied_version_;  ///< the seqlock's version last taken (its initial value is no command)
  ReceivedCommand<Command> applied_;
  std::atomic<uint64_t> accepted_{0}, malformed_{0}, stale_{0}, trips_{0}, barred_{0};
  std::atomic<bool> expired_{true};
};

/// s: the longest control step: a thread this late was stopped (SIGSTOP, a
/// debugger), not slow, and the simulated world is taken as paused with it.
inline constexpr double kMaxControlStep_s = 1.0;

/// The control loop's step (s) at `now_ns`: the nominal period on the first
/// tick, then the time since the last, at most kMaxControlStep_s. A thread
/// starved on a loaded machine is late by tenths of a second: a simulated
/// vehicle steps through that time (in pieces of its own), as a real one
/// moves on meanwhile. (Capped at 50 ms, a blimp at 3 m/s lost 0.6 m
/// against its stamps in a 0.2-s stall, and the predictor's error against
/// the truth with it.)
inline double ControlStep(int64_t& last_tick_ns, int64_t now_ns, double rate_hz) {
  const double dt =
      last_tick_ns == 0 ? 1.0 / rate_hz : std::min(kMaxControlStep_s, NsToS(now_ns - last_tick_ns));
  last_tick_ns = now_ns;
  return dt;
}

}  // namespace haptel::vehicles
