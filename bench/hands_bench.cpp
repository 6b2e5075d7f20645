#include "hands_bench.hpp"

#include <X11/keysym.h>
#include <fastdds/rtps/common/SerializedPayload.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bare_loop.hpp"
#include "haptel/config/device.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/run.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/child_process.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/json.hpp"
#include "haptel/haptics/pointer.hpp"
#include "haptel/haptics/trace.hpp"
#include "haptel/mcap/reader.hpp"
#include "haptel/models/tread_drive.hpp"
#include "haptel/msg/haptelPubSubTypes.h"
#include "haptel/record/session_cdr.hpp"
#include "haptel/record/session_channels.hpp"
#include "haptel/session/sessionPubSubTypes.h"
#include "haptel/testing/hand_trace.hpp"
#include "haptel/testing/obstacle_track.hpp"
#include "haptel/testing/pointer_pilot.hpp"
#include "haptel/testing/run_watch.hpp"
#include "haptel/testing/x_desktop.hpp"
#include "haptel/testing/xvfb.hpp"
#include "plot.hpp"
#include "smoke.hpp"

namespace haptel::bench {
namespace {

using testing::HeardCommand;
using testing::PositionAt;
using testing::RunWatch;
using testing::WristsOf;
using testing::WristTrack;
using testing::XDesktop;
using testing::XWindowInfo;

/// The target for a pointer step to the command it changes.
constexpr double kInputToCommandP95Target_ms = 20.0;
/// The servo histogram's bin (LoopMeter): the resolution of every p99 here.
constexpr double kBin_us = 10.0;
/// The scripted path, pixels and seconds (the same for every interface).
constexpr int kStep_px = 100;
constexpr double kStepHold_s = 0.6;
constexpr int kPush_px = 60;
constexpr double kPushHold_s = 0.8;
/// The pointer hand has taken a step once it moved this far its way, m.
constexpr double kHandMoved_m = 0.0001;
/// A shake this long before the bench heard the contact is still its own:
/// the run may hear the bumper's state first.
constexpr int64_t kShakeEarly_ns = 20'000'000;
/// A contact of the vehicle holds the command this long: the cockpits'
/// throttle lock (config/interfaces/cockpit*.yaml, throttle_lock_s: 1 s);
/// the gesture's wall stands until 0.3 s after it.
constexpr int64_t kContactHold_ns = 1'000'000'000;
/// Bounds on waits (a hang, not a timing check).
constexpr double kStartBound_s = 90.0;
constexpr double kRunBound_s = 600.0;
constexpr const char* kVehicleName = "hands";
/// The bench's vehicle reports a state each of its simulation ticks (the
/// shipped 50 Hz would hide a command overtaken within 20 ms, and the
/// session sends up to its 100 Hz): every command sent is heard.
constexpr double kStateRate_hz = 200.0;

double Nan() { return std::nan(""); }
std::string Num(double v) { return std::isfinite(v) ? JsonNumber(v) : std::string("null"); }

/// A JSON array of `v`, in its order.
std::string Numbers(const std::vector<double>& v) {
  std::ostringstream out;
  out << "[";
  for (size_t i = 0; i < v.size(); ++i) out << (i ? "," : "") << Num(v[i]);
  out << "]";
  return out.str();
}

double Percentile(std::vector<double> v, double p) {
  if (v.empty()) return Nan();
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(std::min<double>(v.size() - 1, std::floor(p * v.size())))];
}

double Number(const std::string& json, const std::string& key) {
  const std::string v = JsonFieldOf(json, key);
  try {
    return v.empty() || v == "null" ? Nan() : std::stod(v);
  } catch (const std::exception&) {
    return Nan();
  }
}

/// A pointer position sent (CLOCK_MONOTONIC, ns; pixels in the window).
struct CursorAt {
  int64_t t_ns = 0;
  int x = 0, y = 0;
};

/// The run's vehicle (config/haptel.yaml's sim-robot.yaml) reporting at
/// kStateRate_hz, written to `dir`; the rest of its file as shipped.
std::filesystem::path WriteReportingVehicle(const std::filesystem::path& dir) {
  const std::filesystem::path shipped = ShippedFile("config/vehicles/sim-robot.yaml");
  std::ifstream in(shipped);
  if (!in) throw std::runtime_error("cannot read " + shipped.string());
  const auto file = dir / "hands-vehicle.yaml";
  std::ofstream out(file);
  bool rate = false;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("state_rate_hz:", 0) == 0) {
      line =
          "state_rate_hz: " + JsonNumber(kStateRate_hz) + "  # haptel bench hands: every command";
      rate = true;
    } else if (line.rfind("world:", 0) == 0) {
      // Relative to the shipped file's folder, not this one's.
      std::istringstream words(line.substr(6));
      std::string world;
      words >> world;
      line = "world: " + std::filesystem::absolute(shipped.parent_path() / world).string();
    }
    out << line << "\n";
  }
  if (!rate) throw std::runtime_error(shipped.string() + ": no state_rate_hz line to raise");
  if (!out) throw std::runtime_error("cannot write " + file.string());
  return file;
}

/// The run's link settings on the bench's domain.
LinkConfig LinkOn(int domain) {
  LinkConfig link = LoadRun(ShippedFile("config/haptel.yaml")).link;
  link.domain_id = domain;
  return link;
}

struct Options {
  std::vector<std::string> interfaces{"gesture", "gesture-shared", "cockpit", "cockpit-assisted"};
  std::filesystem::path device;
  std::filesystem::path vehicle;  ///< WriteReportingVehicle's
  int steps = 40;
  double nobody_s = 60.0;
  double contact_bound_s = 15.0;
  double bare_s = 2.0;
  double servo_rate_hz = 1000.0;  ///< the device's servo loop, for the bare loop
  int servo_priority = 80;
  int domain = 0;
  bool smoke = false;
};

struct Row {
  std::string interface;
  bool ran = false;
  std::string outcome;
  std::string error;
  int commands = 0;
  double max_forward = 0.0, max_turn = 0.0;
  std::vector<double> latencies_ms;
  /// Each step's pointer to the device's hand: the X server, SDL, the view's
  /// event pump and the servo tick; the rest of latencies_ms is the session.
  std::vector<double> to_hand_ms;
  /// Per step with both: its command's time less its hand's (the coupling,
  /// the proxy hand and the lever on the physics thread, the session tick),
  /// apart from the pointer's way into the device.
  std::vector<double> hand_to_command_ms;
  /// The stages after the hand, each step's from the pointer step (from the
  /// run's session file): the proxy hand first moving its way (the physics
  /// thread's, as the servo ticks saw it; none without a world), the first
  /// command sent that moved its way at all (the interface read at the
  /// session's tick or between ticks), and the first whose motor levels
  /// changed (latencies_ms: the control's travel to the first level).
  std::vector<double> to_proxy_ms, to_first_change_ms;
  /// The first command sent whose motor levels differ (the run's session
  /// file, quantised as the vehicle does): latencies_ms without the
  /// vehicle's process, which may read a command late.
  std::vector<double> to_levels_sent_ms;
  /// The gaps between the commands the run sent over the steps, ms: the
  /// session thread's own stalls (it sends one at least every 20 ms).
  std::vector<double> command_gaps_ms;
  int steps_unanswered = 0;
  /// Steps a contact of the vehicle held (left out of every stage above).
  int steps_after_contact = 0;
  double ratio_free = Nan(), ratio_across = Nan(), ratio_along = Nan();
  bool contact = false;
  double contact_to_shake_ms = Nan();
  int shakes = 0;  ///< shakes the device started (the trace's shake records), all sides
  double servo_p99_us = Nan(), bare_beside_p99_us = Nan(), bare_alone_p99_us = Nan();
  double pseudo_haptic_gain_mean = Nan();
  /// The run's physics thread (the proxy hands and the cockpit's controls):
  /// the steps it took per second (the world's 1000 Hz when it keeps real
  /// time) and its period's p99; NaN without a world (the gestures).
  double physics_rate_hz = Nan(), physics_period_p99_us = Nan();
  int nobody_moving_commands = -1;
  int nobody_commands = 0;
  double nobody_distance_m = Nan();
  Series hand{"", {}, {}};
  Series cursor{"", {}, {}};
};

/// The run's session file (its commands with their values, its servo ticks).
std::filesystem::path SessionFileOf(const std::filesystem::path& dir, const std::string& interface,
                                    const std::string& tag) {
  return dir / ("hands-" + interface + "-" + tag + ".mcap");
}

using record::DecodeCdr;

/// A command the run sent (its own stamp, CLOCK_MONOTONIC ns) and its values.
struct SentCommand {
  int64_t t_ns = 0;
  double forward = 0.0;  ///< (left + right) / 2
  double left = 0.0, right = 0.0;
};
/// The pointer hand's proxy as a servo tick saw it (CLOCK_MONOTONIC ns, m).
struct ProxyAt {
  int64_t t_ns = 0;
  double x = 0.0;
};
struct SessionFileStages {
  std::vector<SentCommand> commands;
  std::vector<ProxyAt> proxy;  ///< only the ticks with the proxy coupled
};

/// The commands sent and the pointer side's coupled proxy from `file`.
SessionFileStages ReadStages(const std::filesystem::path& file, haptics::Side pointer_side) {
  namespace channels = record::session;
  const mcap::Reader reader = mcap::Reader::Open(file);
  std::string command_topic;
  for (const auto& [id, channel] : reader.channels()) {
    const auto schema = reader.schemas().find(channel.schema_id);
    const auto direction = channel.metadata.find("direction");
    if (schema != reader.schemas().end() &&
        schema->second.name == std::string(channels::kDdsSchemaPrefix) + "TreadCommand" &&
        direction != channel.metadata.end() && direction->second == "sent")
      command_topic = channel.topic;
  }
  if (command_topic.empty()) throw std::runtime_error(file.string() + ": no commands sent");
  SessionFileStages out;
  reader.ForEachMessage(0, UINT64_MAX, {command_topic, std::string(channels::kServoTopic)},
                        [&](const mcap::MessageView& m) {
                          if (m.channel->topic == command_topic) {
                            msg::TreadCommand c;
                            if (DecodeCdr<msg::TreadCommandPubSubType>(m, c) && !c.release())
                              out.commands.push_back(
                                  {c.sent_ns(), 0.5 * (c.left() + c.right()), c.left(), c.right()});
                            return;
                          }
                          session::ServoTick tick;
                          if (DecodeCdr<session::ServoTickPubSubType>(m, tick) &&
                              tick.side() == static_cast<uint8_t>(haptics::Index(pointer_side)) &&
                              tick.coupling())
                            out.proxy.push_back({tick.t_ns(), tick.proxy_position()[0]});
                        });
  std::sort(out.commands.begin(), out.commands.end(),
            [](const SentCommand& a, const SentCommand& b) { return a.t_ns < b.t_ns; });
  return out;
}

std::vector<std::string> RunArgs(const Options& o, const std::string& interface,
                                 const std::filesystem::path& dir,
                                 const std::filesystem::path& track, const std::string& tag,
                                 double time_limit_s) {
  return {"run",
          "--operator",
          "person",
          "--device",
          o.device.string(),
          "--view",
          "window",
          "--interface",
          interface,
          "--track",
          track.string(),
          "--json",
          "--quiet",
          "--domain",
          std::to_string(o.domain),
          "--vehicle",
          o.vehicle.string(),
          "--vehicle-name",
          kVehicleName,
          "--database",
          (dir / "hands.db").string(),
          "--trace",
          (dir / ("hands-" + interface + "-" + tag + ".trace")).string(),
          "--vehicle-timeout",
          "5",
          "--time-limit",
          JsonNumber(time_limit_s),
          "--session",
          SessionFileOf(dir, interface, tag).string()};
}

/// The pointer, moved and logged: where the cursor was sent, and when.
class Cursor {
 public:
  Cursor(XDesktop& desktop, const XWindowInfo& window) : desktop_(desktop), window_(window) {}
  int64_t MoveTo(int x, int y) {
    const int64_t t = MonotonicNs();
    desktop_.MovePointer(window_, x, y);
    log_.push_back({t, x, y});
    return t;
  }
  /// Glides to (x, y) over `seconds` in 10 ms steps (a hand's move, not a jump).
  void GlideTo(int x, int y, double seconds) {
    const CursorAt from = log_.empty() ? CursorAt{} : log_.back();
    const int n = std::max(1, static_cast<int>(seconds / 0.01));
    for (int i = 1; i <= n; ++i) {
      const double f = static_cast<double>(i) / n;
      MoveTo(from.x + static_cast<int>(std::lround((x - from.x) * f)),
             from.y + static_cast<int>(std::lround((y - from.y) * f)));
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  const std::vector<CursorAt>& log() const { return log_; }
  const XWindowInfo& window() const { return window_; }

 private:
  XDesktop& desktop_;
  XWindowInfo window_;
  std::vector<CursorAt> log_;
};

void Sleep(double s) { std::this_thread::sleep_for(std::chrono::duration<double>(s)); }

/// How long (ms) after `from` the first of `samples` (in time order) within
/// (from, to] had a value that `changed(value, before)` from the last one's
/// at or before `from`; none when none did (or none came before `from`).
template <class Sample, class ValueOf, class Changed>
std::optional<double> FirstChangeMs(const std::vector<Sample>& samples, int64_t from, int64_t to,
                                    ValueOf value_of, Changed changed) {
  std::optional<decltype(value_of(samples.front()))> before;
  for (const Sample& sample : samples) {
    if (sample.t_ns <= from) {
      before = value_of(sample);
      continue;
    }
    if (sample.t_ns > to || !before) break;
    if (changed(value_of(sample), *before)) return 1e-6 * static_cast<double>(sample.t_ns - from);
  }
  return std::nullopt;
}

/// Where the path takes hold. Nothing to grasp (the gestures): the button
/// at the window's centre. Controls (the cockpits): the pointer hand brought
/// round to its control open, as the pointer pilot brings it
/// (PointerApproach), then onto its grip, then the button; the path's steps
/// are then taken from the grip (the lever pushed and pulled).
struct Hold {
  std::optional<testing::PointerApproach> approach;
  haptics::Vec3d grip{};
};

Hold HoldFor(const Options& o, const std::string& interface, const std::filesystem::path& track,
             const MouseDeviceConfig& mouse) {
  testing::PilotSetup setup;
  setup.run_file = ShippedFile("config/haptel.yaml");
  setup.device = o.device;
  setup.track = track;
  setup.interface = interface;
  const interfaces::HandTargets neutral = testing::PointerPilot(setup).Neutral();
  const auto& hand = neutral[mouse.pointer_on_left ? 0 : 1];
  Hold hold;
  if (!hand || std::all_of(hand->glove.begin(), hand->glove.end(),
                           [](double angle) { return angle == 0.0; })) {
    return hold;
  }
  haptics::Vec3d open = hand->position;
  for (int k = 0; k < 3; ++k) open[k] += hand->approach[k];
  hold.approach.emplace(haptics::Vec3d{mouse.centre[0], mouse.centre[1], mouse.centre[2]}, open);
  hold.grip = hand->position;
  return hold;
}

/// The engaged run: the scripted path with the button held. Fills the row's
/// commands, latencies, ratios and contact figures.
void Engaged(const Options& o, const std::filesystem::path& dir, const std::filesystem::path& track,
             const MouseDeviceConfig& mouse, const Hold& hold, Row& row) {
  // The script's length and a margin: the run ends by Escape, or by this limit.
  const double limit_s = o.steps * kStepHold_s + o.contact_bound_s + 20.0;
  const auto args = RunArgs(o, row.interface, dir, track, "engaged", limit_s);
  RunWatch listener(LinkOn(o.domain), kVehicleName);
  std::string json, err;
  std::vector<int64_t> step_ns;
  int64_t across_from = 0, across_to = 0, along_from = 0, along_to = 0, still_from = 0;
  std::vector<CursorAt> cursor_log;
  const BareLoop beside = MeasureBareLoopWhile(o.servo_rate_hz, o.servo_priority, [&] {
    ChildProcess run((ProgramDirectory() / "haptel").string(), args, ChildProcess::Options{true});
    try {
      XDesktop desktop;
      std::optional<XWindowInfo> window;
      const int64_t deadline = MonotonicNs() + static_cast<int64_t>(kStartBound_s * 1e9);
      while (!(window = desktop.FindWindow("Haptel")) || listener.states() == 0) {
        if (MonotonicNs() > deadline || !run.Alive())
          throw std::runtime_error("the run's window or vehicle did not come up");
        run.Pump();
        Sleep(0.05);
      }
      desktop.Focus(*window);
      Cursor cursor(desktop, *window);
      int cx = window->width_px / 2, cy = window->height_px / 2;
      cursor.MoveTo(cx, cy);
      Sleep(0.3);
      if (hold.approach) {
        int64_t notches = 0;
        const auto to = [&](const haptics::Vec3d& target) {
          const std::array<int, 2> px =
              haptics::PointerPixelFor(target, mouse, window->width_px, window->height_px);
          cursor.MoveTo(px[0], px[1]);
          const int64_t want = mouse.wheel_step > 0.0
                                   ? std::lround((target[2] - mouse.centre[2]) / mouse.wheel_step)
                                   : 0;
          for (; notches != want; notches += notches < want ? 1 : -1)
            desktop.WheelNotch(notches < want);
          return px;
        };
        const double approach_s = hold.approach->duration_s();
        for (double s = 0.0; s < approach_s; s += 0.01) {
          to(hold.approach->At(s));
          Sleep(0.01);
        }
        // Onto the grip in half a second, as the operator's reach goes.
        const haptics::Vec3d open = hold.approach->At(approach_s);
        for (int i = 1; i <= 50; ++i) {
          haptics::Vec3d p;
          for (int k = 0; k < 3; ++k) p[k] = open[k] + (hold.grip[k] - open[k]) * i / 50.0;
          const std::array<int, 2> px = to(p);
          cx = px[0];
          cy = px[1];
          Sleep(0.01);
        }
        Sleep(0.3);
      }
      desktop.Button(1, true);
      Sleep(0.5);
      // Steps up and down (forward and back), the same for every interface.
      for (int i = 0; i < o.steps; ++i) {
        step_ns.push_back(cursor.MoveTo(cx, cy + (i % 2 == 0 ? -kStep_px : kStep_px)));
        Sleep(kStepHold_s);
        run.Pump();
      }
      step_ns.push_back(MonotonicNs());  // the last step's end
      // Forward until the bumper touches, then still.
      listener.Arm();
      cursor.MoveTo(cx, cy - kStep_px);
      const int64_t contact_deadline =
          MonotonicNs() + static_cast<int64_t>(o.contact_bound_s * 1e9);
      while (listener.contact_ns() == 0 && MonotonicNs() < contact_deadline) {
        run.Pump();
        Sleep(0.02);
      }
      still_from = MonotonicNs();
      Sleep(1.0);
      // Across the wall (further forward), then along it (right).
      across_from = MonotonicNs();
      cursor.GlideTo(cx, cy - kStep_px - kPush_px, 0.3);
      Sleep(kPushHold_s);
      across_to = MonotonicNs();
      along_from = across_to;
      cursor.GlideTo(cx + kPush_px, cy - kStep_px - kPush_px, 0.3);
      Sleep(kPushHold_s);
      along_to = MonotonicNs();
      desktop.Button(1, false);
      desktop.Key(XK_Escape, true);
      desktop.Key(XK_Escape, false);
      cursor_log = cursor.log();
    } catch (const std::exception& e) {
      row.error = e.what();
      run.Terminate();
    }
    run.Wait(kRunBound_s);
    json = run.LastLine();
    err = run.err();
  });
  std::ofstream(dir / ("hands-" + row.interface + "-engaged.log")) << err;
  row.bare_beside_p99_us = beside.stats.period_p99_us;
  if (json.empty() || json.front() != '{') {
    if (row.error.empty()) row.error = "the engaged run gave no result";
    return;
  }
  row.ran = row.error.empty();
  row.outcome = JsonFieldOf(json, "outcome");
  row.servo_p99_us = Number(json, "servo_period_p99_us");
  row.pseudo_haptic_gain_mean = Number(json, "pseudo_haptic_gain_mean");
  row.physics_rate_hz = Number(json, "physics_rate_hz");
  row.physics_period_p99_us = Number(json, "physics_period_p99_us");

  // Commands: how many, their largest forward and turn, and each step's answer.
  const std::vector<HeardCommand> commands = listener.commands();
  row.commands = static_cast<int>(commands.size());
  for (const HeardCommand& c : commands) {
    row.max_forward = std::max(row.max_forward, std::abs(0.5 * (c.left + c.right)));
    row.max_turn = std::max(row.max_turn, std::abs(0.5 * (c.right - c.left)));
  }
  // The hands, from the run's device trace.
  std::vector<haptics::TraceRecord> trace;
  try {
    trace = haptics::ReadTrace(dir / ("hands-" + row.interface + "-engaged.trace"));
  } catch (const std::exception& e) {
    row.error = e.what();
    return;
  }
  // A step the vehicle's contact holds (its shake, the trace's shake record,
  // within kContactHold_ns before the step or during it) is no measure of
  // the chain: the cockpits lock the lever at zero for a second.
  std::vector<bool> held(step_ns.size(), false);
  for (const haptics::TraceRecord& r : trace) {
    if (r.kind != haptics::TraceRecord::kShake) continue;
    for (size_t i = 0; i + 1 < step_ns.size(); ++i)
      held[i] = held[i] || (r.t_ns >= step_ns[i] - kContactHold_ns && r.t_ns < step_ns[i + 1]);
  }
  std::vector<double> step_command_ms(step_ns.size(), Nan());  // per step, NaN: unanswered
  for (size_t i = 0; i + 1 < step_ns.size(); ++i) {
    if (held[i]) {
      ++row.steps_after_contact;
      continue;
    }
    const int64_t sent = step_ns[i];
    HeardCommand before{};
    for (const HeardCommand& c : commands) {
      if (c.t_ns < sent) before = c;
    }
    bool answered = false;
    for (const HeardCommand& c : commands) {
      if (c.t_ns < sent || c.t_ns > step_ns[i + 1]) continue;
      if (c.left != before.left || c.right != before.right) {
        row.latencies_ms.push_back(1e-6 * static_cast<double>(c.t_ns - sent));
        step_command_ms[i] = row.latencies_ms.back();
        answered = true;
        break;
      }
    }
    row.steps_unanswered += answered ? 0 : 1;
  }

  using haptics::Side;
  const WristTrack hand = WristsOf(trace, mouse.pointer_on_left ? Side::kLeft : Side::kRight);
  const double m = mouse.metres_per_pixel;
  // Each step's pointer to the hand: the first tick the hand moved its way.
  for (size_t i = 0; i + 1 < step_ns.size(); ++i) {
    if (held[i]) continue;
    const double way = i % 2 == 0 ? 1.0 : -1.0;  // up the window: forward, +x
    const double from = PositionAt(hand, step_ns[i])[0];
    for (const auto& [t, p] : hand) {
      if (t <= step_ns[i] || t > step_ns[i + 1]) continue;
      if (way * (p[0] - from) >= kHandMoved_m) {
        row.to_hand_ms.push_back(1e-6 * static_cast<double>(t - step_ns[i]));
        if (std::isfinite(step_command_ms[i]))
          row.hand_to_command_ms.push_back(step_command_ms[i] - row.to_hand_ms.back());
        break;
      }
    }
  }
  // The stages after the hand, from the run's session file.
  try {
    const int speed_levels = LoadVehicle(o.vehicle).drive.speed_levels;
    const SessionFileStages stages = ReadStages(SessionFileOf(dir, row.interface, "engaged"),
                                                mouse.pointer_on_left ? Side::kLeft : Side::kRight);
    for (size_t k = 1; k < stages.commands.size(); ++k) {
      const int64_t t = stages.commands[k].t_ns;
      if (!step_ns.empty() && t > step_ns.front() && t <= step_ns.back())
        row.command_gaps_ms.push_back(1e-6 * static_cast<double>(t - stages.commands[k - 1].t_ns));
    }
    for (size_t i = 0; i + 1 < step_ns.size(); ++i) {
      if (held[i]) continue;
      const double way = i % 2 == 0 ? 1.0 : -1.0;
      const int64_t from = step_ns[i], to = step_ns[i + 1];
      const auto moved = [&](double now, double before) {
        return way * (now - before) >= kHandMoved_m;
      };
      const auto forward_more = [&](double now, double before) {
        return way * (now - before) > 0.0;
      };
      if (auto ms = FirstChangeMs(
              stages.proxy, from, to, [](const ProxyAt& p) { return p.x; }, moved))
        row.to_proxy_ms.push_back(*ms);
      if (auto ms = FirstChangeMs(
              stages.commands, from, to, [](const SentCommand& c) { return c.forward; },
              forward_more))
        row.to_first_change_ms.push_back(*ms);
      // The first sent whose levels (as the vehicle quantises them) differ:
      // the operator's side alone, without the vehicle's reading of it.
      const auto levels = [&](const SentCommand& c) {
        return std::array<int, 2>{models::QuantiseCommand(c.left, speed_levels),
                                  models::QuantiseCommand(c.right, speed_levels)};
      };
      if (auto ms = FirstChangeMs(stages.commands, from, to, levels, std::not_equal_to<>()))
        row.to_levels_sent_ms.push_back(*ms);
    }
  } catch (const std::exception& e) {
    row.error = e.what();
  }
  // The hand's forward offset over the cursor's, step by step: each step's
  // settled hand (just before the next step) against the one before.
  std::vector<double> free;
  for (size_t i = 1; i + 1 < step_ns.size(); ++i) {
    const int64_t settled = step_ns[i + 1] - 20'000'000, before = step_ns[i] - 20'000'000;
    const double cursor_m = 2.0 * kStep_px * m;
    free.push_back(std::abs(PositionAt(hand, settled)[0] - PositionAt(hand, before)[0]) / cursor_m);
  }
  row.ratio_free = Percentile(free, 0.5);
  row.ratio_across =
      std::abs(PositionAt(hand, across_to)[0] - PositionAt(hand, across_from)[0]) / (kPush_px * m);
  row.ratio_along =
      std::abs(PositionAt(hand, along_to)[1] - PositionAt(hand, along_from)[1]) / (kPush_px * m);
  const int64_t contact = listener.contact_ns();
  row.contact = contact != 0;
  // The contact's shake: the device's first after the contact, either hand
  // (its trace records each start, Device::PseudoHaptics).
  for (const haptics::TraceRecord& r : trace) {
    if (r.kind != haptics::TraceRecord::kShake) continue;
    ++row.shakes;
    if (!row.contact || std::isfinite(row.contact_to_shake_ms)) continue;
    if (r.t_ns >= contact - kShakeEarly_ns && r.t_ns <= still_from + 1'000'000'000)
      row.contact_to_shake_ms = 1e-6 * static_cast<double>(r.t_ns - contact);
  }
  // The plot: the pointer hand's forward offset and the cursor's, mm, over the path.
  if (!hand.empty() && !cursor_log.empty()) {
    const int64_t t0 = cursor_log.front().t_ns;
    const int cy = cursor_log.front().y;
    row.hand.name = row.interface + ": hand";
    for (const auto& [t, p] : hand) {
      if (t < t0 || t > along_to) continue;
      row.hand.x.push_back(1e-9 * static_cast<double>(t - t0));
      row.hand.y.push_back(1e3 * (p[0] - mouse.centre[0]));
    }
    row.cursor.name = row.interface + ": cursor";
    for (const CursorAt& c : cursor_log) {
      row.cursor.x.push_back(1e-9 * static_cast<double>(c.t_ns - t0));
      row.cursor.y.push_back(1e3 * (cy - c.y) * m);
    }
  }
}

/// The same path with nobody engaged (no button), for `nobody_s`: the
/// commands that would move the vehicle.
void Nobody(const Options& o, const std::filesystem::path& dir, const std::filesystem::path& track,
            Row& row) {
  RunWatch listener(LinkOn(o.domain), kVehicleName);
  ChildProcess run((ProgramDirectory() / "haptel").string(),
                   RunArgs(o, row.interface, dir, track, "nobody", o.nobody_s),
                   ChildProcess::Options{true});
  try {
    XDesktop desktop;
    std::optional<XWindowInfo> window;
    const int64_t deadline = MonotonicNs() + static_cast<int64_t>(kStartBound_s * 1e9);
    while (!(window = desktop.FindWindow("Haptel"))) {
      if (MonotonicNs() > deadline || !run.Alive())
        throw std::runtime_error("the run's window did not come up");
      run.Pump();
      Sleep(0.05);
    }
    Cursor cursor(desktop, *window);
    const int cx = window->width_px / 2, cy = window->height_px / 2;
    for (int i = 0; run.Alive(); ++i) {
      cursor.MoveTo(cx + (i % 3 - 1) * kPush_px, cy + (i % 2 == 0 ? -kStep_px : kStep_px));
      Sleep(kStepHold_s);
      run.Pump();
    }
  } catch (const std::exception& e) {
    row.error += (row.error.empty() ? "" : "; ") + std::string(e.what());
    run.Terminate();
  }
  run.Wait(kRunBound_s);
  const std::string json = run.LastLine();
  std::ofstream(dir / ("hands-" + row.interface + "-nobody.log")) << run.err();
  if (json.empty() || json.front() != '{') {
    row.error +=
        (row.error.empty() ? "" : "; ") + std::string("the run with nobody gave no result");
    row.ran = false;
    return;
  }
  row.nobody_distance_m = Number(json, "distance_m");
  row.nobody_moving_commands = 0;
  const auto commands = listener.commands();
  row.nobody_commands = static_cast<int>(commands.size());
  for (const HeardCommand& c : commands) row.nobody_moving_commands += c.moves() ? 1 : 0;
}

}  // namespace

int BenchHandsMain(int argc, const char* const* argv) {
  bool json = false;
  Options o;
  DeviceConfig device;
  o.domain = 150 + static_cast<int>(getpid() % 30);
  try {
    const Args args(argc, argv, {"interfaces", "device", "steps", "nobody-s", "domain"},
                    {"json", kSmokeFlag});
    json = args.Flag("json");
    o.smoke = args.Flag(kSmokeFlag);
    if (o.smoke) {
      o.interfaces = {"gesture"};
      o.steps = 4;
      // The run's time limit counts from its start: on a loaded machine
      // the vehicle's start-up took all of 3 s, and nobody's run heard no
      // command at all (the suite's smoke then failed on nothing heard).
      o.nobody_s = 8.0;
      o.contact_bound_s = 5.0;
      o.bare_s = 0.5;
    }
    if (auto list = args.Value("interfaces")) o.interfaces = SplitList(*list);
    if (o.interfaces.empty()) throw UsageError("option --interfaces: expected interface names");
    o.device = args.Value("device").value_or(ShippedFile("config/devices/mouse.yaml").string());
    device = LoadDevice(o.device);
    if (device.driver != "mouse") {
      throw UsageError("option --device: " + o.device.string() + " is a '" + device.driver +
                       "' device; expected the mouse device (config/devices/mouse.yaml)");
    }
    o.servo_rate_hz = device.servo.rate_hz;
    o.servo_priority = device.servo.realtime_priority;
    o.steps = args.Int("steps", 2, 1000).value_or(o.steps);
    o.nobody_s = args.Number("nobody-s", 1.0, 3600.0).value_or(o.nobody_s);
    o.domain = args.Int("domain", 0, 232).value_or(o.domain);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel bench hands: %s\n", e.what());
    return 2;
  }
  const auto dir = OutputDir(o.smoke);
  PrintSmokeNote("hands", o.smoke, "gesture only, %d steps, %.0f s with nobody engaged", o.steps,
                 o.nobody_s);
  std::unique_ptr<testing::Xvfb> x;
  try {
    x = std::make_unique<testing::Xvfb>();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel bench hands: %s\n", e.what());
    return 1;
  }
  const std::filesystem::path track =
      testing::WriteObstacleAheadTrack(ShippedFile("config/tracks/test-short.yaml"), dir);
  o.vehicle = WriteReportingVehicle(dir);
  std::printf(
      "haptel bench hands: %s through the real window on Xvfb %s, the short track with an "
      "obstacle ahead\n\n",
      o.device.c_str(), x->display().c_str());
  std::printf(
      "  interface          outcome   cmds  fwd max turn max  in->cmd p50/p95 ms  in->hand "
      "p50/p95  ratio free/across/along  contact->shake ms  servo p99 us  bare beside/alone  "
      "nobody: moving/cmds  m\n");
  std::vector<Row> rows;
  for (const std::string& interface : o.interfaces) {
    Row row;
    row.interface = interface;
    row.bare_alone_p99_us =
        MeasureBareLoop(device.servo.rate_hz, device.servo.realtime_priority, o.bare_s)
            .stats.period_p99_us;
    try {
      Engaged(o, dir, track, device.mouse, HoldFor(o, interface, track, device.mouse), row);
    } catch (const std::exception& e) {
      row.error = e.what();  // the interface's files: nothing to take hold of
    }
    Nobody(o, dir, track, row);
    if (!row.error.empty()) {
      std::fprintf(stderr, "haptel bench hands: %s: %s (the run's output: %s)\n", interface.c_str(),
                   row.error.c_str(), (dir / ("hands-" + interface + "-engaged.log")).c_str());
    }
    std::printf(
        "  %-17s  %-8s  %4d  %7.2f  %8.2f  %7.1f / %7.1f    %5.1f / %5.1f   %5.2f / %5.2f / %5.2f  "
        "%17.1f  %12.0f  %6.0f / %5.0f  %7d / %5d  %5.3f\n",
        interface.c_str(), row.ran ? row.outcome.c_str() : "failed", row.commands, row.max_forward,
        row.max_turn, Percentile(row.latencies_ms, 0.5), Percentile(row.latencies_ms, 0.95),
        Percentile(row.to_hand_ms, 0.5), Percentile(row.to_hand_ms, 0.95), row.ratio_free,
        row.ratio_across, row.ratio_along, row.contact_to_shake_ms, row.servo_p99_us,
        row.bare_beside_p99_us, row.bare_alone_p99_us, row.nobody_moving_commands,
        row.nobody_commands, row.nobody_distance_m);
    // The lever's chain runs on the physics thread: behind real time, the
    // lever follows the hand late.
    std::printf("  %-17s  hand->cmd p50/p95 %.1f / %.1f ms", "",
                Percentile(row.hand_to_command_ms, 0.5), Percentile(row.hand_to_command_ms, 0.95));
    if (row.physics_rate_hz > 0.0) {
      std::printf(", physics thread %.0f steps/s (p99 period %.0f us)", row.physics_rate_hz,
                  row.physics_period_p99_us);
    }
    std::printf("\n");
    std::printf(
        "  %-17s  stages from the step, p50/p95 ms: hand %.1f / %.1f, proxy %.1f / %.1f, first "
        "change of command %.1f / %.1f, first change of levels sent %.1f / %.1f, obeyed %.1f / "
        "%.1f\n",
        "", Percentile(row.to_hand_ms, 0.5), Percentile(row.to_hand_ms, 0.95),
        Percentile(row.to_proxy_ms, 0.5), Percentile(row.to_proxy_ms, 0.95),
        Percentile(row.to_first_change_ms, 0.5), Percentile(row.to_first_change_ms, 0.95),
        Percentile(row.to_levels_sent_ms, 0.5), Percentile(row.to_levels_sent_ms, 0.95),
        Percentile(row.latencies_ms, 0.5), Percentile(row.latencies_ms, 0.95));
    if (!row.command_gaps_ms.empty()) {
      std::printf(
          "  %-17s  the session's commands over the steps: gap p99 %.1f ms, largest %.1f ms\n", "",
          Percentile(row.command_gaps_ms, 0.99),
          *std::max_element(row.command_gaps_ms.begin(), row.command_gaps_ms.end()));
    }
    if (row.steps_after_contact > 0) {
      std::printf("  %-17s  %d step(s) left out: a contact of the vehicle held the command\n", "",
                  row.steps_after_contact);
    }
    std::fflush(stdout);
    rows.push_back(std::move(row));
  }

  bool latency_met = true, nobody_met = true, servo_unchanged = true;
  for (const Row& r : rows) {
    latency_met = latency_met && !r.latencies_ms.empty() &&
                  Percentile(r.latencies_ms, 0.95) <= kInputToCommandP95Target_ms;
    nobody_met = nobody_met && r.nobody_moving_commands == 0;
    servo_unchanged =
        servo_unchanged &&
        r.servo_p99_us <= std::max(r.bare_beside_p99_us, r.bare_alone_p99_us) + kBin_us;
  }
  std::printf(
      "\n  in->cmd: a pointer step sent through XTest to the send time of the first command "
      "after it whose motor\n"
      "  levels differ (as the vehicle's states report it, at 200 Hz: every command heard); "
      "stages: the step to\n"
      "  the hand, to the proxy hand (the physics world's, as the servo ticks saw it), to the "
      "first command sent\n"
      "  that moved its way at all (the run's session file), to the first sent that changed "
      "the levels (the\n"
      "  session file's, quantised as the vehicle does), to the first obeyed that did "
      "(in->cmd: with the vehicle's\n"
      "  process, which may read a command late);\n"
      "  a step a contact of the vehicle held (the cockpits lock the lever at zero for 1 s) is "
      "left out and counted;\n"
      "  in->hand: the step to the device's hand first moving its way (X, SDL, the "
      "view's\n"
      "  event pump, a servo tick); ratio: the pointer hand's displacement over the cursor's (1: "
      "it "
      "follows;\n"
      "  below: bent by a force), free (the steps), across the wall (pushed on towards the "
      "obstacle) and\n"
      "  along it; contact->shake: the bumper's state to the device's shake starting (its trace's "
      "shake\n"
      "  record), with the pointer still; servo p99: the\n"
      "  run's, against an empty loop at its rate beside the run and alone; nobody: the same path "
      "with no\n"
      "  button, commands that would move the vehicle, and the metres it went.\n\n");
  std::printf("  target: input-to-command p95 <= %.0f ms: %s\n", kInputToCommandP95Target_ms,
              latency_met ? "met" : "MISSED");
  std::printf("  target: nobody engaged, 0 commands that move the vehicle: %s\n",
              nobody_met ? "met" : "MISSED");
  std::printf("  target: servo p99 unchanged (<= the bare loop's + one %.0f us bin): %s\n", kBin_us,
              servo_unchanged ? "met" : "MISSED");

  {
    std::ofstream csv(dir / "hands.csv");
    csv << "interface,outcome,commands,max_forward,max_turn,input_to_command_ms_p50,"
           "input_to_command_ms_p95,input_to_hand_ms_p50,input_to_hand_ms_p95,steps_unanswered,"
           "ratio_free,ratio_across_wall,ratio_along_wall,contact,contact_to_shake_ms,shakes,"
           "pseudo_haptic_gain_mean,servo_p99_us,"
           "bare_beside_p99_us,bare_alone_p99_us,nobody_moving_commands,nobody_commands,"
           "nobody_distance_m\n";
    for (const Row& r : rows) {
      csv << r.interface << "," << r.outcome << "," << r.commands << "," << r.max_forward << ","
          << r.max_turn << "," << Percentile(r.latencies_ms, 0.5) << ","
          << Percentile(r.latencies_ms, 0.95) << "," << Percentile(r.to_hand_ms, 0.5) << ","
          << Percentile(r.to_hand_ms, 0.95) << "," << r.steps_unanswered << "," << r.ratio_free
          << "," << r.ratio_across << "," << r.ratio_along << "," << r.contact << ","
          << r.contact_to_shake_ms << "," << r.shakes << "," << r.pseudo_haptic_gain_mean << ","
          << r.servo_p99_us << "," << r.bare_beside_p99_us << "," << r.bare_alone_p99_us << ","
          << r.nobody_moving_commands << "," << r.nobody_commands << "," << r.nobody_distance_m
          << "\n";
    }
  }
  std::vector<Series> series;
  for (const Row& r : rows) {
    if (r.hand.x.empty()) continue;
    if (series.empty()) series.push_back(r.cursor);
    series.push_back(r.hand);
  }
  if (!series.empty()) {
    PlotLines(dir / "hands.png", series,
              {"The pointer hand's forward offset against the cursor's (the same path)", "s",
               "mm forward of the centre"});
  }
  std::printf("\n  wrote %s, %s\n", (dir / "hands.csv").c_str(), (dir / "hands.png").c_str());

  const bool all_ran = std::all_of(rows.begin(), rows.end(), [](const Row& r) { return r.ran; });
  if (json) {
    std::ostringstream out;
    out << "{\"interfaces\":[";
    for (size_t i = 0; i < rows.size(); ++i) {
      const Row& r = rows[i];
      out << (i ? "," : "") << "{\"interface\":" << JsonString(r.interface)
          << ",\"ran\":" << (r.ran ? "true" : "false") << ",\"outcome\":" << JsonString(r.outcome)
          << ",\"error\":" << JsonString(r.error) << ",\"commands\":" << r.commands
          << ",\"max_forward\":" << Num(r.max_forward) << ",\"max_turn\":" << Num(r.max_turn)
          << ",\"input_to_command_ms_p50\":" << Num(Percentile(r.latencies_ms, 0.5))
          << ",\"input_to_command_ms_p95\":" << Num(Percentile(r.latencies_ms, 0.95))
          << ",\"input_to_hand_ms_p50\":" << Num(Percentile(r.to_hand_ms, 0.5))
          << ",\"input_to_hand_ms_p95\":" << Num(Percentile(r.to_hand_ms, 0.95))
          << ",\"hand_to_command_ms_p50\":" << Num(Percentile(r.hand_to_command_ms, 0.5))
          << ",\"hand_to_command_ms_p95\":" << Num(Percentile(r.hand_to_command_ms, 0.95))
          << ",\"input_to_proxy_ms_p50\":" << Num(Percentile(r.to_proxy_ms, 0.5))
          << ",\"input_to_proxy_ms_p95\":" << Num(Percentile(r.to_proxy_ms, 0.95))
          << ",\"input_to_first_change_ms_p50\":" << Num(Percentile(r.to_first_change_ms, 0.5))
          << ",\"input_to_first_change_ms_p95\":" << Num(Percentile(r.to_first_change_ms, 0.95))
          << ",\"input_to_first_change_ms\":" << Numbers(r.to_first_change_ms)
          << ",\"input_to_levels_sent_ms_p50\":" << Num(Percentile(r.to_levels_sent_ms, 0.5))
          << ",\"input_to_levels_sent_ms_p95\":" << Num(Percentile(r.to_levels_sent_ms, 0.95))
          << ",\"command_gap_ms_p99\":" << Num(Percentile(r.command_gaps_ms, 0.99))
          << ",\"command_gap_ms_max\":"
          << Num(r.command_gaps_ms.empty()
                     ? Nan()
                     : *std::max_element(r.command_gaps_ms.begin(), r.command_gaps_ms.end()))
          << ",\"physics_rate_hz\":" << Num(r.physics_rate_hz)
          << ",\"physics_period_p99_us\":" << Num(r.physics_period_p99_us)
          << ",\"input_to_command_ms\":" << Numbers(r.latencies_ms)
          << ",\"input_to_hand_ms\":" << Numbers(r.to_hand_ms) << ",\"steps\":"
          << r.latencies_ms.size() + static_cast<size_t>(r.steps_unanswered + r.steps_after_contact)
          << ",\"steps_unanswered\":" << r.steps_unanswered
          << ",\"steps_after_contact\":" << r.steps_after_contact
          << ",\"ratio_free\":" << Num(r.ratio_free)
          << ",\"ratio_across_wall\":" << Num(r.ratio_across)
          << ",\"ratio_along_wall\":" << Num(r.ratio_along)
          << ",\"contact\":" << (r.contact ? "true" : "false")
          << ",\"contact_to_shake_ms\":" << Num(r.contact_to_shake_ms) << ",\"shakes\":" << r.shakes
          << ",\"pseudo_haptic_gain_mean\":" << Num(r.pseudo_haptic_gain_mean)
          << ",\"servo_p99_us\":" << Num(r.servo_p99_us)
          << ",\"bare_beside_p99_us\":" << Num(r.bare_beside_p99_us)
          << ",\"bare_alone_p99_us\":" << Num(r.bare_alone_p99_us)
          << ",\"nobody_s\":" << Num(o.nobody_s)
          << ",\"nobody_moving_commands\":" << r.nobody_moving_commands
          << ",\"nobody_commands\":" << r.nobody_commands
          << ",\"nobody_distance_m\":" << Num(r.nobody_distance_m) << "}";
    }
    out << "],\"input_to_command_target_met\":" << (latency_met ? "true" : "false")
        << ",\"nobody_target_met\":" << (nobody_met ? "true" : "false")
        << ",\"servo_unchanged\":" << (servo_unchanged ? "true" : "false") << "}";
    std::printf("%s\n", JsonLine(out.str(), o.smoke).c_str());
  }
  return all_ran ? 0 : 1;
}

}  // namespace haptel::bench
