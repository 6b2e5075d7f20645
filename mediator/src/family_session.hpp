#pragma once
// The part of a session that depends on the vehicle's family (VehicleFamily):
// its world and lap timer, the interfaces that make its commands, the
// operator who drives it, and what its view and progress lines add. The one
// session loop (session.cpp, for one vehicle or a fleet) is written over it
// and never asks which family it drives; the robot's part is in
// robot_session.cpp, the blimp's in blimp_session.cpp, and MakeFamilySession
// picks one. Internal to the mediator library.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "haptel/interfaces/input.hpp"
#include "haptel/mediator/engagement.hpp"
#include "haptel/mediator/fleet.hpp"
#include "haptel/mediator/haptic_side.hpp"
#include "haptel/mediator/interface_handover.hpp"
#include "haptel/mediator/prediction.hpp"
#include "haptel/mediator/run_counters.hpp"
#include "haptel/mediator/session.hpp"
#include "haptel/mediator/session_physics.hpp"
#include "haptel/mediator/session_view.hpp"
#include "haptel/mediator/vehicle_link.hpp"
#include "session_loop.hpp"

namespace haptel::mediator {

/// A predictor's per-state errors (m), against the vehicle's odometry, into
/// the record's prediction_error_odometry_m_p50 and _p95 (nearest rank);
/// left as they are (unknown) without any.
inline void RecordPredictionErrors(const std::vector<double>& errors_m, RunRecord& rec) {
  if (errors_m.empty()) return;
  const ErrorPercentiles e = PercentilesOf(errors_m);
  rec.prediction_error_odometry_m_p50 = e.p50;
  rec.prediction_error_odometry_m_p95 = e.p95;
}

/// In a fleet it is also one side of the person's interface handover
/// (interface_handover.hpp): its interface rendered while it fades out,
/// paused while another vehicle is driven, resumed when turned back to.
class FamilySession : public HandoverSide {
 public:
  ~FamilySession() override = default;

  /// The haptic side has started: start what runs on it (a physics world).
  virtual void Start(HapticSide& haptic) = 0;
  /// The set-up was interrupted before anything started: what was built is
  /// recorded in `result` and left to tear down on its own.
  virtual void AbandonSetup(SessionResult& result) = 0;

  /// The view's parts and options for this family (physics, controls,
  /// hands, where the screen hangs).
  virtual void ConfigureView(SessionView::Parts& parts, view::ViewOptions& options) const = 0;
  /// Whether a person's game controller is to be polled (without a view, a
  /// thread of its own does it).
  virtual bool UsesGamepad() const = 0;
  /// The physics world, while there is one (its loop is watched).
  virtual const SessionPhysics* physics() const { return nullptr; }

  /// Each tick, the states that arrived: the health hears of each, the lap,
  /// the trace and the operator see each pose.
  virtual void Drain(VehicleLink& link, VehicleHealth& health, HapticSide& haptic, RunTrace& trace,
                     int64_t t0_ns) = 0;
  /// Each tick the vehicle is the operator's: the person's requests, the
  /// operator's act, the interface's command (sent when due; a safe one
  /// while the vehicle is not up or the operator does not engage the
  /// interface: `engaged`, engagement.hpp). Ends the run when the person's
  /// controller went away.
  virtual std::optional<LoopEnd> Command(double t_s, int64_t now_ns,
                                         const interfaces::InputState& person, bool vehicle_up,
                                         bool engaged, HapticSide& haptic, VehicleLink& link) = 0;
  /// Between ticks, every millisecond while it says so (a single run in
  /// real time; the tick's Command decided `engaged` and the vehicle up):
  /// sends the interface's command at once when its motor levels changed
  /// since the last one sent, so that a person's input does not wait for
  /// the next tick (issue 36). Returns whether it wants to be asked again
  /// before the next tick (false: nothing to look at; the loop sleeps).
  virtual bool CommandBetweenTicks(double /*t_s*/, int64_t /*now_ns*/, HapticSide& /*haptic*/,
                                   VehicleLink& /*link*/) {
    return false;
  }
  /// What engagement asks of the interface driven now: the device's arms it
  /// uses, their neutral places, whether its last command is at rest.
  virtual InterfaceRest Rest() const = 0;
  /// The interfaces are switching (F1–F6) and ramp the force scale themselves.
  virtual bool SwitchingInterface() const { return false; }
  /// The lap's own end: completed (or crashed).
  virtual std::optional<LoopEnd> LapEnd() const = 0;
  /// The file of the track or course the spawned vehicle lives in.
  virtual const std::filesystem::path& world_file() const = 0;
  /// The lap cap of the track or course, s.
  virtual double lap_cap_s() const = 0;
  /// When the lap began (the start line crossed, the blimp lifted off), s
  /// since the session started; nullopt before. The lap clock counts from
  /// here; the time before it is the run's approach (RunRecord::approach_s).
  virtual std::optional<double> lap_start_s() const = 0;
  /// The view's overlay now; `touching`: the run's trace is in a contact.
  /// Builds it without allocating.
  virtual view::Overlay Overlay(double t_s, bool vehicle_up, bool touching) = 0;
  /// Where the head and the vehicle's camera look (a tracked screen), or none.
  virtual std::optional<view::Gaze> Gaze() const { return std::nullopt; }
  /// The predictive display's ghost and map poses now (with prediction on;
  /// none without it). Made each tick the view is fed.
  virtual std::optional<view::Prediction> Prediction(double /*t_s*/) { return std::nullopt; }
  /// The progress line(s) on stderr.
  virtual void LogProgress(double t_s, const VehicleLink& link, double distance_m) const = 0;
  /// How the end leaves the vehicle, for a lost vehicle's or device's line.
  virtual const char* MadeSafe() const = 0;

  /// The loop has ended: forces out of the HAL from anything still running.
  virtual void RequestStop() {}
  /// Stops what the part runs and puts its figures (lap, splits, interface
  /// switches, physics, the operator's) into `result`.
  virtual void Finish(SessionResult& result, bool progress) = 0;
};

/// The robot's part: the grand-prix track, the switchable interfaces (and
/// a physics world when their controls or the scene need one), the
/// automatic driver or a person. Throws ConfigError for parts that cannot be
/// set up. Its record fields (track, gates, interface) are set in `rec`.
std::unique_ptr<FamilySession> MakeRobotSession(const SessionSetup& setup, HapticSide& haptic,
                                                interfaces::InputBox& input,
                                                const std::atomic<bool>& interrupted,
                                                RunRecord& rec);
/// The blimp's part: its course, the gesture cockpit (or a person's keys or
/// game controller), the automatic pilot or a person.
std::unique_ptr<FamilySession> MakeBlimpSession(const SessionSetup& setup, HapticSide& haptic,
                                                interfaces::InputBox& input, RunRecord& rec);
/// The part of `setup.vehicle`'s family (the robot's or the blimp's above):
/// the one place a session tells the families apart.
inline std::unique_ptr<FamilySession> MakeFamilySession(const SessionSetup& setup,
                                                        HapticSide& haptic,
                                                        interfaces::InputBox& input,
                                                        const std::atomic<bool>& interrupted,
                                                        RunRecord& rec) {
  switch (setup.vehicle.family()) {
    case VehicleFamily::kRobot:
      return MakeRobotSession(setup, haptic, input, interrupted, rec);
    case VehicleFamily::kBlimp:
      return MakeBlimpSession(setup, haptic, input, rec);
  }
  throw std::logic_error("vehicle family without a session part");
}

/// One vehicle of a session (a single run's, or one of a fleet's) and what
/// the loop keeps for it: its family's part, its link, health, trace and
/// loop watch, and its result. Built in that order by the loop's set-up.
struct VehicleRun {
  explicit VehicleRun(const SessionSetup& s) : setup(s) {}

  const SessionSetup& setup;
  FleetVehicleResult out;  ///< its outcome and record; a fleet's turn figures
  std::unique_ptr<FamilySession> family;
  std::unique_ptr<VehicleLink> link;
  std::unique_ptr<VehicleHealth> health;
  std::unique_ptr<RunTrace> trace;
  std::unique_ptr<LoopWatch> watch;
  bool done = false;      ///< its course is over (completed, lost, crashed, capped)
  bool lost = false;      ///< nothing more to hold: its process or its states are gone
  view::Overlay overlay;  ///< its view's overlay, made each tick the view is fed
};

}  // namespace haptel::mediator
