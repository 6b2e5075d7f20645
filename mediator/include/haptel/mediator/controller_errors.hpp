#pragma once
/// @file The blimp's servo controller's error register as the operator
/// sees it: each state carries the register as the vehicle's last error
/// poll read it (BlimpState.controller_errors, the Maestro's bits; the
/// device clears it on reading, so a bit shows once per error). The watch
/// keeps what every state carried, for the progress line (what came since
/// the last line) and the run's summary and JSON line (all of it).
///
/// Judging the controller is the vehicle's work (it knows the port and
/// every poll, servo_output.hpp): an untrusted controller comes as the
/// state's fault, which ends the run as vehicle lost.
#include <cstdint>
#include <string>
#include <vector>

namespace haptel::mediator {

class ControllerErrorWatch {
 public:
  /// For each state drained (`controller_errors`: its register).
  void Observe(uint16_t controller_errors) {
    since_line_ = static_cast<uint16_t>(since_line_ | controller_errors);
    seen_ = static_cast<uint16_t>(seen_ | controller_errors);
  }
  template <typename State>
  void ObserveState(const State& s) {
    Observe(s.controller_errors());
  }
  /// The progress line's part: "  controller errors: CRC error (register
  /// 0x0008)" for what came since the last call; "" when nothing did.
  std::string TakeProgressText();
  /// Every bit the run's states carried.
  uint16_t seen() const { return seen_; }

 private:
  uint16_t since_line_ = 0;
  uint16_t seen_ = 0;
};

/// The summary's line for a Maestro's errors over the run:
/// "servo controller errors: CRC error, serial timeout (register 0x0028)",
/// or "servo controller errors: none".
std::string ControllerErrorsLine(uint16_t errors);
/// Each set bit's name, highest bit first (none: empty): the JSON line's
/// `controller_error_names`.
std::vector<std::string> ControllerErrorNames(uint16_t errors);

}  // namespace haptel::mediator
