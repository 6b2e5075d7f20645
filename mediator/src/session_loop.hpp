#pragma once
// What the session loop (RunSession) does whatever the vehicle's family:
// watch the vehicle's health, trace the run, pace the commands, stop at the
// limits, and put the link's figures in the record. Internal to the
// mediator library.
#include <cstdint>
#include <optional>
#include <string>

#include "haptel/mediator/haptic_side.hpp"
#include "haptel/mediator/run_record.hpp"
#include "haptel/mediator/session.hpp"
#include "haptel/mediator/vehicle_link.hpp"

namespace haptel::mediator {

/// Why a session loop ends.
struct LoopEnd {
  Outcome outcome = Outcome::kInterrupted;
  std::string message;
  double lost_detect_s = 0.0;  ///< vehicle or device lost: last sign of life -> detection
};

/// Ends `result` as `end` says; a lost vehicle or device is said at once
/// (the clean-up that follows may take a while), with how it was made safe.
void Finish(SessionResult& result, LoopEnd end, const char* made_safe);

/// The stops every loop checks first, each tick: an interruption, then the
/// haptic device (a lost arm means no forces, so no driving either; one
/// the person unplugged ends the run aborted).
std::optional<LoopEnd> CheckOperatorSide(const std::atomic<bool>& interrupted,
                                         const HapticSide& haptic, const std::string& device_name);

/// The vehicle's health as the loop sees it: its process, the faults its
/// states report, their silence, and, until it first answers, the start-up
/// timeout; and whether it is ours to drive: one vehicle under its name on
/// the domain, obeying this run's command writer.
class VehicleHealth {
 public:
  /// `session` and `writer`: this run's (VehicleLink::session() and
  /// command_writer()). `spawned_pid`: the vehicle process this run started
  /// (VehicleLink::pid(); 0: attached to one it did not start, whose states
  /// any process may send).
  VehicleHealth(const std::string& vehicle_name, int domain_id, uint64_t session,
                const link::WriterId& writer, double vehicle_timeout_s,
                double startup_timeout_s = kStartupTimeout_s, int64_t spawned_pid = 0);
  /// Whether a state has arrived yet.
  bool up() const { return up_; }
  /// Up, and its latest state named this run's writer as its owner, or none:
  /// what this session says of the vehicle is true (a fleet publishes who
  /// commands it only then, never while another operator holds it).
  bool ours() const { return up_ && refused_since_ns_ == 0; }
  /// Before the states are drained: the spawned process still runs, and no
  /// second vehicle answers under the same name (for kConflictAfter_s).
  std::optional<LoopEnd> CheckProcess(VehicleLink& vehicle, int64_t now_ns);
  /// For each state drained (received at `now_ns`); true for the first one
  /// (the vehicle just came up).
  /// Whether `s` comes from another process than the vehicle this run
  /// started (`spawned_pid`, on this host): another vehicle answering under
  /// the name. Such a state must not be used; the first one makes the next
  /// check a conflict, before the stranger has been driven as the run's
  /// vehicle. Never true for an attached vehicle (no process of the run's).
  template <typename State>
  bool FromAnotherProcess(const State& s) {
    if (spawned_pid_ == 0) return false;
    if (s.vehicle_pid() == spawned_pid_ && s.vehicle_host() == host_) return false;
    if (stranger_.empty()) {
      stranger_ = s.vehicle_pid() == 0 ? std::string("a process that does not say which")
                                       : "pid " + std::to_string(s.vehicle_pid()) + " on host '" +
                                             std::string(s.vehicle_host().c_str()) + "'";
    }
    return true;
  }
  /// The conflict a stranger's state made, once one came (CheckProcess and
  /// CheckStates return it before anything else).
  std::optional<LoopEnd> StrangerConflict() const;
  /// Control lost, once a state showed it (CheckStates returns it first
  /// after a conflict): the vehicle obeys another writer after this run's,
  /// or one naming this run's session.
  std::optional<LoopEnd> LostControl() const;
  template <typename State>
  bool OnState(const State& s, int64_t now_ns) {
    return OnState(s.fault(), s.fault_message(), s.owner_session(),
                   link::WriterId{s.owner_writer()}, s.owner().c_str(), now_ns);
  }
  bool OnState(bool fault, const std::string& fault_message, uint64_t owner_session,
               const link::WriterId& owner_writer, const char* owner, int64_t now_ns);
  /// After the states are drained: control lost (a state named another
  /// writer as the owner after one named this run's, or one naming this
  /// run's session: at once), a fault one of them reported, another writer
  /// owning the vehicle (for kRefusedAfter_s), their silence, or no answer
  /// yet `t_s` after the start.
  std::optional<LoopEnd> CheckStates(const VehicleLink& vehicle, int64_t now_ns, double t_s);

  /// A second vehicle must answer this long before it is a conflict
  /// (discovery is not atomic), and another owner hold the vehicle this
  /// long before this run is refused (a previous run's release may still be
  /// on its way). Both well within a second.
  static constexpr double kConflictAfter_s = 0.3;
  /// A vehicle must answer this long after the start, unless told otherwise.
  static constexpr double kStartupTimeout_s = 15.0;
  static constexpr double kRefusedAfter_s = 0.5;

 private:
  std::string name_;
  int domain_id_;
  uint64_t session_;
  link::WriterId writer_;
  double timeout_s_;
  double startup_timeout_s_;
  bool up_ = false;
  std::string fault_;              ///< the first fault reported since the last check
  int64_t conflict_since_ns_ = 0;  ///< 0: one vehicle (or none) answers
  int64_t refused_since_ns_ = 0;   ///< 0: the vehicle is ours or free
  std::string owner_;              ///< who holds it, while refused_since_ns_ is set
  bool had_control_ = false;       ///< a state named this run's writer as the owner
  std::string lost_control_;       ///< why this run lost control ("": it did not)
  int64_t spawned_pid_;            ///< 0: attached
  std::string host_;               ///< this host's name (HostName)
  std::string stranger_;           ///< another process's state came: which ("": none)
};

/// The run's trace in the record: distance flown or driven, the path every
/// 50 ms, and where each contact began.
class RunTrace {
 public:
  explicit RunTrace(RunRecord& record) : record_(record) {}
  /// A pose at `t_s` (z: 0 for a ground vehicle); `touching`: in contact.
  /// `driven_m`: how far the vehicle moved since the previous pose as it
  /// measured it (a robot's odometry: a localised pose's corrections are
  /// not driving); negative: the distance between the poses.
  void Add(double t_s, double x, double y, double z, double speed, bool touching,
           double driven_m = -1.0);
  bool touching() const { return touching_; }

 private:
  RunRecord& record_;
  bool have_position_ = false;
  double last_x_ = 0.0, last_y_ = 0.0, last_z_ = 0.0;
  double last_path_t_ = -1.0;
  bool touching_ = false;
};

/// True when a command is due at `now_ns`: at once when it `changed` from
/// the last one sent (a person's input does not wait for the next period),
/// else once per `period_ns` (the vehicle's watchdog hears the link alive);
/// a late loop sends one, it does not catch up. Called once a session tick,
/// so the link carries at most the session's rate (session_rate_hz).
bool CommandDue(int64_t& next_ns, int64_t now_ns, int64_t period_ns, bool changed = false);

/// Between the session's ticks (FamilySession::CommandBetweenTicks): whether
/// `now` sets other motor levels than `sent` once the robot quantises both to
/// its `speed_levels` per direction (models::QuantiseCommand). Only such a
/// change goes out before the tick: one within a level moves nothing, and
/// the link keeps to about the session's rate.
bool LevelsChange(const TreadCommand& sent, const TreadCommand& now, int speed_levels);

/// The session's own limits at `t_s` (s since the session started): the time
/// limit on the session's clock (0: none); then the lap limit (a study's cap;
/// 0: none) and the track's lap cap, both on the lap's clock — from
/// `lap_start_s`, when the start line was crossed — so that every interface
/// gets the same lap time whatever its approach and grasp took. Before the
/// line (nullopt) the approach counts against them instead, so a vehicle
/// that never reaches the line still ends.
std::optional<LoopEnd> CheckLimits(double t_s, std::optional<double> lap_start_s,
                                   double time_limit_s, double lap_limit_s, double lap_cap_s);

/// The figures of the servo loop and the link into the record (after both stopped).
void RecordLinkFigures(const HapticSide& haptic, const VehicleLink& vehicle, SessionResult& result);

}  // namespace haptel::mediator
