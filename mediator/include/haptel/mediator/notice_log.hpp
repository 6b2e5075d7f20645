#pragma once
/// @file An interface's notice (Interface::Notice: what stops the person
/// driving, e.g. no game controller) said once in the run's log.
#include <cstring>

namespace haptel::mediator {

/// Says a notice once it has stood for kSettle_s, and again only after it
/// went away or changed: a game controller is opened in the view's first
/// events, so a notice gone within a second was never the person's problem.
/// Session thread; allocates nothing.
class NoticeLog {
 public:
  static constexpr double kSettle_s = 1.0;

  /// The line to log now (the notice itself), or null.
  const char* Update(double t_s, const char* notice) {
    const bool same = notice == current_ || (notice != nullptr && current_ != nullptr &&
                                             std::strcmp(notice, current_) == 0);
    if (!same) {
      current_ = notice;
      since_s_ = t_s;
      said_ = false;
    }
    if (current_ == nullptr || said_ || t_s - since_s_ < kSettle_s) return nullptr;
    said_ = true;
    return current_;
  }

 private:
  const char* current_ = nullptr;
  double since_s_ = 0.0;
  bool said_ = false;
};

}  // namespace haptel::mediator
