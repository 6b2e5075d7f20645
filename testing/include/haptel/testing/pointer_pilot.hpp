#pragma once
/// @file The pointer pilot: the automatic operator (mediator::AutoOperator)
/// sat at a desktop, driving a `haptel run --device <mouse> --operator person
/// --view window` through the real X pointer, its left button, its wheel and
/// the key hand's keys, as a person at the mouse would. For the end-to-end
/// tests and `haptel bench hands`; no product code links it.
///
/// It sees the vehicle as the run's operator does (its state topic, on the
/// run's DDS domain), decides as the automatic operator does (Observe each
/// state, Act → hand targets from the interface's own inverse map), and
/// expresses the targets through the mouse device's own map
/// (haptel/haptics/pointer.hpp): the pointer hand's target becomes a pixel
/// (PointerPixelFor) and a number of wheel notches; the key hand's target is
/// reached by holding W/S, A/D, Q/E while a model of the key hand
/// (StepKeyHand from the keys held) is short of it. The left button is held
/// while the hands grasp (at once for an interface with nothing to grasp:
/// there the button is what engages it).
#include <X11/keysym.h>

#include <array>
#include <atomic>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "haptel/config/device.hpp"
#include "haptel/haptics/pointer.hpp"
#include "haptel/interfaces/interface.hpp"
#include "haptel/mediator/auto_operator.hpp"
#include "haptel/testing/x_desktop.hpp"

namespace haptel::testing {

/// The keys of the key hand, in KeyHandKey order (+x, −x, +y, −y, +z, −z):
/// W/S forward and back, A/D left and right (the device's +y is its left),
/// Q/E up and down.
inline constexpr std::array<unsigned long, 6> kKeyHandKeysyms{XK_w, XK_s, XK_a, XK_d, XK_q, XK_e};

/// What the desktop is told in one step: where the pointer goes, the wheel's
/// notches so far, the button and the key hand's keys.
struct PointerGesture {
  std::array<int, 2> pixel{};  ///< from the window's top-left corner
  bool pointer_used = false;   ///< the interface uses the pointer hand
  int64_t wheel_notches = 0;
  bool button = false;
  std::array<bool, 6> keys{};  ///< KeyHandKey order
};

/// Turns hand targets into a PointerGesture, stepping its model of the key
/// hand (pure: no X; the pilot sends what it returns).
class PointerHands {
 public:
  explicit PointerHands(const MouseDeviceConfig& mouse);
  /// `targets`: the operator's hands now; `neutral`: the interface's at rest
  /// (its glove says whether there is anything to grasp); `dt_s` since the
  /// last step; the window's size.
  PointerGesture Step(const interfaces::HandTargets& targets,
                      const interfaces::HandTargets& neutral, double dt_s, int width_px,
                      int height_px);
  /// The model of the key hand: where the device puts it after the keys held.
  const haptics::Vec3d& key_hand() const { return key_hand_; }
  size_t pointer_index() const { return pointer_; }
  size_t key_index() const { return 1 - pointer_; }

 private:
  MouseDeviceConfig mouse_;
  size_t pointer_;
  haptics::Vec3d key_hand_;
  std::array<bool, 6> keys_{};
};

/// How a person brings the pointer hand, open, to a control before taking
/// hold of it (the cockpit's lever): drawn back out of whatever lies before
/// the hand's rest (the window's centre puts it behind the cockpit's wheel,
/// its fingers by the rim), across to the control's side, forward beside it,
/// then to its height (the scroll wheel), at a hand's pace and pausing at
/// each turn. A straight line catches the proxy hand on the rim from behind,
/// where it stays: the device's hand follows the pointer only through a soft
/// coupling (pseudo-haptics), which a contact holds back, and a hand hurried
/// round a corner lags behind the pointer and cuts it.
class PointerApproach {
 public:
  /// The path is walked at kSpeed_mps, pausing kSettle_s at each point.
  static constexpr double kSpeed_mps = 0.2;
  static constexpr double kSettle_s = 0.3;
  /// How far back the hand is drawn: the palm's half width (4 cm,
  /// config/physics.yaml) past the rim's tube (1.2 cm), and a margin.
  static constexpr double kBack_m = 0.06;

  /// From the pointer hand's `rest` to `goal` (the control's approach point).
  PointerApproach(const haptics::Vec3d& rest, const haptics::Vec3d& goal);
  /// The pointer hand's target `s` after setting off (`goal` from duration_s on).
  haptics::Vec3d At(double s) const;
  double duration_s() const;
  const std::array<haptics::Vec3d, 5>& points() const { return points_; }

 private:
  std::array<haptics::Vec3d, 5> points_;
};

/// Where a pilot drives.
struct PilotSetup {
  int domain = 0;            ///< the run's DDS domain
  std::string vehicle_name;  ///< the run's --vehicle-name
  std::filesystem::path run_file = "config/haptel.yaml";
  std::filesystem::path track;  ///< empty: the run file's
  std::filesystem::path device = "config/devices/mouse.yaml";
  std::string interface = "gesture";
  std::string window_title = "Haptel";
  double rate_hz = 50.0;  ///< steps per second (a mouse reports at 125 Hz and more)
};

/// What a pilot did, so far.
struct PilotCounts {
  int states = 0;         ///< vehicle states seen
  int steps = 0;          ///< steps acted (after the vehicle answered)
  int pointer_moves = 0;  ///< pointer motions sent
  int key_presses = 0;    ///< key-down events sent
  int wheel_notches = 0;  ///< wheel notches sent
  int contacts = 0;       ///< states with a bumper pressed, from none
  int regrasps = 0;       ///< controls let go and taken hold of again (the vehicle did not answer)
  int back_to_neutral = 0;  ///< held at neutral again, the screen saying the run waits for it
  bool window_found = false;
  std::string error;  ///< why the pilot stopped early (empty: it did not)
};

class PointerPilot {
 public:
  /// Loads the run, vehicle, track, device and interface files (ConfigError
  /// naming the file and key); starts nothing.
  explicit PointerPilot(PilotSetup setup);
  ~PointerPilot();
  PointerPilot(const PointerPilot&) = delete;
  PointerPilot& operator=(const PointerPilot&) = delete;

  /// Subscribes to the vehicle's state and starts driving on a thread of its
  /// own: waits for the window (its title), then acts at rate_hz once the
  /// vehicle answers.
  void Start();
  /// Stops driving and lets go: button and keys released, the pointer
  /// parked off the window (XDesktop::ParkPointer), so that the next
  /// window (a study's next trial) does not open with the hand following a
  /// pointer left over a control, straight into the cockpit's wheel.
  void Stop();
  PilotCounts counts() const;
  /// What the run's screen says to the person now (its one line, e.g. "Not
  /// engaged - bring the hand back to neutral (zero command) to drive"), as
  /// the person reads it: a study's console shows it to the experimenter
  /// (status.json's `live_message`, pushed twice a second). Any thread.
  void SeeScreenLine(const std::string& line);
  /// The interface's hands at rest (HandTargetsFor no intent): where a
  /// person takes hold (`haptel bench hands` takes hold of the cockpits there).
  interfaces::HandTargets Neutral() const;

 private:
  struct Parts;
  void Run();
  /// Waits until the window titled setup_.window_title is up (counts it
  /// found); none when stopped first.
  std::optional<XWindowInfo> AwaitWindow(XDesktop& desktop);
  /// The participant's screen line as last read, and when (ns, monotonic).
  std::pair<std::string, int64_t> ScreenLine() const;
  /// A fresh automatic operator (its reach and grasp start again), having
  /// seen `seen`.
  static void RestartOperator(Parts& p, const std::optional<mediator::Observation>& seen);
  PilotSetup setup_;
  std::unique_ptr<Parts> parts_;
  std::atomic<bool> stop_{false};
  mutable std::mutex counts_mutex_;
  PilotCounts counts_;
  std::string screen_line_;     ///< counts_mutex_
  int64_t screen_line_ns_ = 0;  ///< when it was read (counts_mutex_)
  std::thread thread_;
};

}  // namespace haptel::testing
