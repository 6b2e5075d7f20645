#pragma once
/// @file The vehicle node's command watchdog.
#include <cstdint>

namespace haptel::vehicles {

/// Stops the motors when no fresh command arrived within the timeout.
/// Time comes in as an argument, so tests drive it with any clock.
class CommandWatchdog {
 public:
  explicit CommandWatchdog(double timeout_s);
  /// A fresh command arrived at `now_ns`.
  void Feed(int64_t now_ns);
  /// True when the last command is older than the timeout, or none came yet.
  bool Expired(int64_t now_ns) const;
  /// Number of times the watchdog went from fed to expired.
  uint64_t trips() const { return trips_; }
  /// Call once per control cycle: returns Expired() and counts new trips.
  bool Check(int64_t now_ns);

 private:
  int64_t timeout_ns_;
  int64_t last_feed_ns_ = 0;
  bool fed_ = false;
  bool was_expired_ = true;
  uint64_t trips_ = 0;
};

}  // namespace haptel::vehicles
