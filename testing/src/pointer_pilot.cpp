#include "haptel/testing/pointer_pilot.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <optional>

#include "haptel/config/run.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/interfaces/catalog.hpp"
#include "haptel/interfaces/cockpit.hpp"
#include "haptel/link/participant.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/mediator/auto_operator.hpp"

namespace haptel::testing {
namespace {

double GloveSum(const interfaces::HandTargets& targets) {
  double sum = 0.0;
  for (const auto& hand : targets) {
    if (!hand) continue;
    for (const double angle : hand->glove) sum += std::abs(angle);
  }
  return sum;
}

/// The pilot never runs the interface (the run does), so nothing reads its
/// controls: the cockpit's inverse map is a function of the intent alone.
class NoControls final : public interfaces::ControlsPort {
 public:
  interfaces::CockpitControls Controls() const override { return {}; }
  void Actuate(const interfaces::ControlActuation&) override {}
};

/// Held at neutral this long after the run's commands reach the vehicle.
constexpr double kTakeHold_s = 1.0;
/// Driving this long with the motors still: take hold again.
constexpr double kRetakeAfter_s = 3.0;
/// Having taken hold of controls, the pilot holds them at neutral for
/// kTakeHold_s and sways the wheel's hand along the rim, once over the hold,
/// to where the interface puts it for this turn each way (±12.6° of the
/// cockpits' wheel, full turn at 90°), as a person works a wheel the run
/// says is not yet at zero: a free wheel (the cockpit without return to
/// zero) nudged a few degrees as the hands closed on it stays there, past
/// the engagement's band (6.4° of wheel), and the run waited for zero until
/// the cap. Swayed, it passes zero and the run engages.
constexpr double kSwayTurn = 0.14;
/// The screen saying the run waits for the controls at neutral, the pilot
/// holds them there again, swaying wider each time (up to this many times
/// kSwayTurn): the wheel's grip may have slipped mid-turn, leaving the free
/// wheel further from zero than one sway reaches.
constexpr int kMaxSwayScale = 3;
/// A line read this long after a hold began is news (the console's line
/// lags the screen by up to its half-second push and the reading).
constexpr double kScreenLag_s = 1.5;

/// The run's line when it is held but waits for the controls (or the hand)
/// at neutral (mediator::Engagement::Line): "Not engaged - ... neutral ...".
bool SaysBackToNeutral(const std::string& line) {
  return line.rfind("Not engaged", 0) == 0 && line.find("neutral") != std::string::npos;
}

}  // namespace

PointerHands::PointerHands(const MouseDeviceConfig& mouse)
    : mouse_(mouse),
      pointer_(mouse.pointer_on_left ? size_t{0} : size_t{1}),
      key_hand_{mouse.key_hand_rest[0], mouse.key_hand_rest[1], mouse.key_hand_rest[2]} {}

PointerGesture PointerHands::Step(const interfaces::HandTargets& targets,
                                  const interfaces::HandTargets& neutral, double dt_s, int width_px,
                                  int height_px) {
  // The keys held since the last step moved the device's key hand.
  haptics::PointerState held;
  for (size_t k = 0; k < keys_.size(); ++k) held.key_hand[k] = keys_[k];
  key_hand_ = haptics::StepKeyHand(key_hand_, held, mouse_, dt_s);

  PointerGesture g;
  if (const auto& hand = targets[pointer_]) {
    g.pointer_used = true;
    const auto pixel = haptics::PointerPixelFor(hand->position, mouse_, width_px, height_px);
    // Kept inside the window: outside it, the hand is let go.
    g.pixel = {std::clamp(pixel[0], 0, width_px - 1), std::clamp(pixel[1], 0, height_px - 1)};
    if (mouse_.wheel_step > 0.0) {
      g.wheel_notches = std::lround((hand->position[2] - mouse_.centre[2]) / mouse_.wheel_step);
    }
  }
  // Nothing to grasp: the button engages the interface, held throughout.
  // Controls to grasp: held once the operator's fingers are half closed.
  const double closed = GloveSum(neutral);
  g.button = closed == 0.0 || GloveSum(targets) >= 0.5 * closed;

  // The key hand: a key held along each axis while the model is more than
  // one step short of the target (bang-bang, as a person taps keys).
  keys_ = {};
  if (const auto& hand = targets[key_index()]) {
    const double band = std::max(1e-3, mouse_.key_hand_speed * dt_s);
    for (size_t axis = 0; axis < 3; ++axis) {
      const double error = hand->position[axis] - key_hand_[axis];
      if (error > band) keys_[2 * axis] = true;
      if (error < -band) keys_[2 * axis + 1] = true;
    }
  }
  g.keys = keys_;
  return g;
}

PointerApproach::PointerApproach(const haptics::Vec3d& rest, const haptics::Vec3d& goal) {
  const double back = std::min(rest[0], goal[0]) - kBack_m;
  points_ = {rest, haptics::Vec3d{back, rest[1], rest[2]}, haptics::Vec3d{back, goal[1], rest[2]},
             haptics::Vec3d{goal[0], goal[1], rest[2]}, goal};
}

namespace {

double Distance(const haptics::Vec3d& a, const haptics::Vec3d& b) {
  return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
}

/// Each hand open above its control (its approach offset away): where the
/// operator's reach starts.
interfaces::HandTargets OpenAbove(const interfaces::HandTargets& at_controls) {
  interfaces::HandTargets open = at_controls;
  for (auto& hand : open) {
    if (!hand) continue;
    for (int k = 0; k < 3; ++k) hand->position[k] += hand->approach[k];
    hand->glove = {};
  }
  return open;
}

/// What one gesture changed on the desktop.
struct GestureSent {
  int moves = 0;
  int presses = 0;
  int notches = 0;
};

/// Puts on the desktop what `gesture` changes from `sent` (everything, the
/// `first` time): the pointer, the wheel's notches, the button, the keys.
GestureSent SendGesture(XDesktop& desktop, const XWindowInfo& window, const PointerGesture& gesture,
                        const PointerGesture& sent, bool first) {
  GestureSent out;
  if (gesture.pointer_used && (first || gesture.pixel != sent.pixel)) {
    desktop.MovePointer(window, gesture.pixel[0], gesture.pixel[1]);
    ++out.moves;
  }
  for (int64_t n = sent.wheel_notches; n != gesture.wheel_notches;
       n += n < gesture.wheel_notches ? 1 : -1) {
    desktop.WheelNotch(n < gesture.wheel_notches);
    ++out.notches;
  }
  if (first || gesture.button != sent.button) desktop.Button(1, gesture.button);
  for (size_t k = 0; k < gesture.keys.size(); ++k) {
    if (gesture.keys[k] == sent.keys[k]) continue;
    desktop.Key(kKeyHandKeysyms[k], gesture.keys[k]);
    out.presses += gesture.keys[k] ? 1 : 0;
  }
  return out;
}

}  // namespace

double PointerApproach::duration_s() const {
  double s = kSettle_s * static_cast<double>(points_.size());
  for (size_t k = 1; k < points_.size(); ++k)
    s += Distance(points_[k - 1], points_[k]) / kSpeed_mps;
  return s;
}

haptics::Vec3d PointerApproach::At(double s) const {
  // Each point: a pause, then the leg to the next.
  for (size_t k = 0; k + 1 < points_.size(); ++k) {
    s -= kSettle_s;
    if (s <= 0.0) return points_[k];
    const double leg_s = Distance(points_[k], points_[k + 1]) / kSpeed_mps;
    if (s < leg_s) {
      const double a = s / leg_s;
      haptics::Vec3d p;
      for (int i = 0; i < 3; ++i) p[i] = points_[k][i] + (points_[k + 1][i] - points_[k][i]) * a;
      return p;
    }
    s -= leg_s;
  }
  return points_.back();
}

struct PointerPilot::Parts {
  RunConfig run;
  VehicleConfig vehicle;
  std::unique_ptr<Track> track;
  DeviceConfig device;
  interfaces::InterfaceSpec spec;
  NoControls controls;
  std::unique_ptr<interfaces::MediatorInterface> interface;
  std::unique_ptr<mediator::AutoOperator> driver;
  std::unique_ptr<link::Participant> participant;
  std::unique_ptr<link::StateReader> states;
  std::mutex inbox_mutex;
  std::deque<mediator::Observation> inbox;
  bool commanded = false;  ///< a state says the run's commands reach the vehicle (inbox_mutex)
  int64_t moving_ns = 0;   ///< the last state whose obeyed command moved the motors (inbox_mutex)
  int64_t t0_ns = 0;
};

PointerPilot::PointerPilot(PilotSetup setup) : setup_(std::move(setup)), parts_(new Parts) {
  Parts& p = *parts_;
  p.run = LoadRun(setup_.run_file);
  p.vehicle = LoadVehicle(p.run.vehicle);
  p.track = std::make_unique<Track>(LoadTrack(setup_.track.empty() ? p.run.track : setup_.track));
  p.device = LoadDevice(setup_.device);
  p.spec = interfaces::LoadInterfaceSpec(p.run, setup_.interface);
  interfaces::InterfaceParts parts;
  parts.controls = &p.controls;
  parts.speed_levels = p.vehicle.drive.speed_levels;
  parts.vehicle = {.max_speed = p.vehicle.drive.max_speed,
                   .track_width = p.vehicle.drive.track_width,
                   .body_radius = p.vehicle.body.radius};
  p.interface = interfaces::MakeInterface(p.spec, parts);
  // Nothing to grasp: the pilot takes hold at the interface's neutral
  // itself (Run), the button held throughout. Controls to grasp: the
  // operator's own reach brings the open hands onto them (the mouse's hands
  // follow the pointer with the button up) and its grasp closes them (the
  // button goes down), as a person would.
  RestartOperator(p, std::nullopt);
}

void PointerPilot::RestartOperator(Parts& p, const std::optional<mediator::Observation>& seen) {
  OperatorConfig op = p.run.op;
  if (GloveSum(p.interface->HandTargetsFor({})) == 0.0) {
    op.grasp_reach_s = 0.0;
    op.grasp_close_s = 0.0;
  }
  // A fresh operator reaches and grasps again from its first Act.
  p.driver = std::make_unique<mediator::AutoOperator>(*p.track, op, p.vehicle.drive);
  if (seen) p.driver->Observe(*seen);
}

PointerPilot::~PointerPilot() { Stop(); }

void PointerPilot::Start() {
  Parts& p = *parts_;
  p.t0_ns = MonotonicNs();
  LinkConfig link = p.run.link;
  link.domain_id = setup_.domain;
  p.participant = std::make_unique<link::Participant>(link, "pointer-pilot");
  p.states = std::make_unique<link::StateReader>(
      *p.participant, link::TopicName(setup_.vehicle_name, "state"), link::Profile::kState,
      [&p](const msg::VehicleState& s) {
        if (!s.pose_valid()) return;
        const double t = 1e-9 * static_cast<double>(MonotonicNs() - p.t0_ns);
        std::lock_guard lock(p.inbox_mutex);
        p.commanded = p.commanded || s.last_command_sent_ns() > 0;
        if (s.motor_left_level() != 0 || s.motor_right_level() != 0) p.moving_ns = MonotonicNs();
        p.inbox.push_back({t, s.x(), s.y(), s.heading(), s.bumper_left(), s.bumper_right()});
      });
  thread_ = std::thread([this] { Run(); });
}

void PointerPilot::Stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
  if (parts_) parts_->states.reset();  // no callback after this
}

interfaces::HandTargets PointerPilot::Neutral() const {
  return parts_->interface->HandTargetsFor({});
}

void PointerPilot::SeeScreenLine(const std::string& line) {
  std::lock_guard lock(counts_mutex_);
  screen_line_ = line;
  screen_line_ns_ = MonotonicNs();
}

PilotCounts PointerPilot::counts() const {
  std::lock_guard lock(counts_mutex_);
  return counts_;
}

std::pair<std::string, int64_t> PointerPilot::ScreenLine() const {
  std::lock_guard lock(counts_mutex_);
  return {screen_line_, screen_line_ns_};
}

std::optional<XWindowInfo> PointerPilot::AwaitWindow(XDesktop& desktop) {
  std::optional<XWindowInfo> window;
  while (!stop_ && !(window = desktop.FindWindow(setup_.window_title))) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  if (window) {
    std::lock_guard lock(counts_mutex_);
    counts_.window_found = true;
  }
  return window;
}

void PointerPilot::Run() {
  Parts& p = *parts_;
  try {
    XDesktop desktop;
    std::optional<XWindowInfo> window = AwaitWindow(desktop);
    if (!window) return;
    desktop.Focus(*window);
    PointerHands hands(p.device.mouse);
    const interfaces::HandTargets neutral = p.interface->HandTargetsFor({});
    // Controls to grasp: the operator's reach and grasp take hold (no hold at neutral).
    const bool grasps = GloveSum(neutral) > 0.0;
    const interfaces::HandTargets open_at_approach = OpenAbove(neutral);
    std::optional<PointerApproach> approach;
    if (const auto& goal = open_at_approach[hands.pointer_index()]; grasps && goal) {
      const auto& c = p.device.mouse.centre;
      approach.emplace(haptics::Vec3d{c[0], c[1], c[2]}, goal->position);
    }
    double approach_start_s = -1.0;
    std::optional<haptics::Vec3d> pointer_target;  ///< where the pointer hand was sent last
    std::optional<mediator::Observation> seen_last;
    PointerGesture sent;
    bool first = true;
    bool touching = false;
    const auto period = std::chrono::nanoseconds(static_cast<int64_t>(1e9 / setup_.rate_hz));
    auto next = std::chrono::steady_clock::now();
    double last_t = -1.0;
    double hold_until_s = -1.0;
    int sway_scale = 1;
    int64_t next_refresh_ns = 0;
    while (!stop_) {
      next += period;
      std::this_thread::sleep_until(next);
      std::deque<mediator::Observation> seen;
      bool commanded = false;
      int64_t moving_ns = 0;
      {
        std::lock_guard lock(p.inbox_mutex);
        seen.swap(p.inbox);
        commanded = p.commanded;
        moving_ns = p.moving_ns;
      }
      int contacts = 0;
      if (!seen.empty()) seen_last = seen.back();
      for (const auto& o : seen) {
        p.driver->Observe(o);
        const bool now_touching = o.bumper_left || o.bumper_right;
        contacts += now_touching && !touching ? 1 : 0;
        touching = now_touching;
      }
      {
        std::lock_guard lock(counts_mutex_);
        counts_.states += static_cast<int>(seen.size());
        counts_.contacts += contacts;
        if (counts_.states == 0) continue;  // the vehicle has not answered yet
      }
      const int64_t now_ns = MonotonicNs();
      if (now_ns >= next_refresh_ns) {  // the window may be resized
        window = desktop.Refresh(*window);
        next_refresh_ns = now_ns + 1'000'000'000;
      }
      const double t = 1e-9 * static_cast<double>(now_ns - p.t0_ns);
      const double dt = last_t < 0.0 ? 0.0 : t - last_t;
      last_t = t;
      // A person takes hold first, at neutral, and drives once the run
      // engages (its commands reach the vehicle, and a moment after): an
      // interface engages only from rest (mediator/engagement.hpp). With
      // controls to grasp, the operator's reach and grasp are that hold.
      if (commanded && hold_until_s < 0.0 && !grasps) hold_until_s = t + kTakeHold_s;
      if (grasps && hold_until_s < 0.0 && p.driver->grasped(t)) hold_until_s = t + kTakeHold_s;
      // Driving, yet the motors have not moved for a while: the run did not
      // engage (it took hold later than the pilot thought, or it let go
      // mid-lap and waits for the command at rest: a lever held forward
      // never is). A person told so on screen goes back to neutral (the
      // controls at zero, still held) and takes hold again.
      // With controls to grasp, the hand may not hold them at all (it closed
      // beside the lever, or was caught on the wheel's rim on its way): a
      // person sees the lever stay put, lets go and takes hold again, from
      // the approach (PointerApproach from where the hand is).
      const double still_s = 1e-9 * static_cast<double>(now_ns - std::max(moving_ns, p.t0_ns));
      if (hold_until_s >= 0.0 && t >= hold_until_s + kRetakeAfter_s && still_s > kRetakeAfter_s) {
        if (grasps && pointer_target) {
          approach.emplace(*pointer_target, open_at_approach[hands.pointer_index()]->position);
          approach_start_s = t;
          hold_until_s = -1.0;
          RestartOperator(p, seen_last);
          std::lock_guard lock(counts_mutex_);
          ++counts_.regrasps;
        } else {
          hold_until_s = t + kTakeHold_s;
        }
      }
      // The screen says the run waits for the controls at neutral (a hand
      // that slipped, a wheel left off zero): a person holds them there
      // again, turning the wheel through zero, and drives on once engaged.
      const auto [screen_line, screen_line_ns] = ScreenLine();
      const double line_t = 1e-9 * static_cast<double>(screen_line_ns - p.t0_ns);
      if (hold_until_s >= 0.0 && t >= hold_until_s && SaysBackToNeutral(screen_line) &&
          line_t > hold_until_s - kTakeHold_s + kScreenLag_s) {
        hold_until_s = t + kTakeHold_s;
        sway_scale = std::min(sway_scale + 1, kMaxSwayScale);
        std::lock_guard lock(counts_mutex_);
        ++counts_.back_to_neutral;
      }
      const bool holding = hold_until_s < 0.0 ? !grasps : t < hold_until_s;
      // Controls to grasp: the open pointer hand goes round to its control
      // first (PointerApproach); the operator's reach and grasp start there.
      if (grasps && approach_start_s < 0.0) approach_start_s = t;
      interfaces::HandTargets targets;
      if (approach && t - approach_start_s < approach->duration_s()) {
        targets[hands.pointer_index()] = open_at_approach[hands.pointer_index()];
        targets[hands.pointer_index()]->position = approach->At(t - approach_start_s);
      } else {
        targets = holding ? neutral : p.driver->Act(t, *p.interface);
        auto& wheel_hand = targets[hands.key_index()];
        if (holding && grasps && wheel_hand) {
          const double phase = (t - (hold_until_s - kTakeHold_s)) / kTakeHold_s;
          const double turn = sway_scale * kSwayTurn * std::sin(2.0 * M_PI * phase);
          const interfaces::HandTargets swayed = p.interface->HandTargetsFor({0.0, turn});
          if (const auto& along = swayed[hands.key_index()]) wheel_hand->position = along->position;
        }
      }
      if (const auto& hand = targets[hands.pointer_index()]) pointer_target = hand->position;
      const PointerGesture g =
          hands.Step(targets, neutral, dt, window->width_px, window->height_px);
      const GestureSent changed = SendGesture(desktop, *window, g, sent, first);
      sent = g;
      first = false;
      std::lock_guard lock(counts_mutex_);
      ++counts_.steps;
      counts_.pointer_moves += changed.moves;
      counts_.key_presses += changed.presses;
      counts_.wheel_notches += changed.notches;
    }
    // Let go, and take the pointer off the window (for the next one).
    if (sent.button) desktop.Button(1, false);
    for (size_t k = 0; k < sent.keys.size(); ++k) {
      if (sent.keys[k]) desktop.Key(kKeyHandKeysyms[k], false);
    }
    desktop.ParkPointer();
  } catch (const std::exception& e) {
    std::lock_guard lock(counts_mutex_);
    counts_.error = e.what();
  }
}

}  // namespace haptel::testing
