#pragma once
/// @file The automatic blimp pilot: a simulated person who flies the course
/// from what the link reports, as the thesis's pilot did (ch. 8.2).
///
/// It sees the blimp after a reaction delay and flies in phases: on the pad
/// it reads the wind's speed (the airspeed at rest); in a fresh wind it
/// rises straight over the pad and drifts with the air until its wind
/// estimate is steady, turns its nose into the wind (tail rotor) and leaves
/// into it until the rudder bites — an airship is launched into the wind,
/// and nothing is flown towards while the wind is unknown; in a light one
/// it climbs out as an aeroplane does (the helix plane tilted up, thrust
/// forwards for the cruise's airspeed: climbing out slowly, the hull went
/// where the wind took it). Then the gates in order —
/// each approached along its direction of travel by pursuing a point on
/// the gate's approach line some metres ahead (a point before the gate
/// first, then through it), at the gate's height or at a safety height
/// above any building near the way to it — then the landing: power cut back
/// to coast down to a slow approach, gliding down to a metre above the
/// ground; over the circle and slow, facing into the wind it estimates, it
/// sinks onto the ground (thrust forwards to hold its place, down to sink).
/// (The wind: from what the blimp reports, its ground velocity against its
/// airspeed along the heading, held while slower than the rudder bites (the
/// sideslip would be read as wind); with a predictive display, from the
/// states as reported, not the predicted blimp it flies by, and so is the
/// pad's reading.) Landing against a head wind, it comes no slower than
/// the rudder bites through the air until near the circle.
/// In a wind the rudder bites in (at least tail_rotor_speed) the whole
/// approach heads along the wind triangle's air velocity (the ground
/// velocity wanted less the wind): nose into the wind, crabbed across it,
/// the circle reached from downwind, the height held by thrust;
/// on touchdown the helix plane goes down and a little power holds the
/// gondola on the ground.
///
/// Its hands: a forward force (airspeed, or ground speed when landing) and
/// a vertical force (climb rate towards the target height) become the power
/// and the helix plane's tilt; the elevator holds a small pitch towards the
/// climb. It steers its heading — turned into a cross wind by the wind
/// triangle, from the wind it estimates — with the rudder, which bites above
/// about 8 km/h; slow and off course, it lets go of the power and turns on
/// the tail rotor (the thesis's quick turnabout: the gesture cockpit drives
/// the tail rotor only at zero power, and so does the pilot). Landing, the
/// power is also the only way up or down: near enough its height and
/// steady, it gives no vertical thrust (the hull floats), so the power
/// stays off and the tail rotor can steer; a turnabout waits for the height
/// to settle and ends when it drifts off. The pilot camera looks at the next gate (then
/// at the landing circle): pan its bearing off the heading, tilt its
/// elevation off the hull's pitch, each within the head's range.
#include <array>
#include <vector>

#include "haptel/config/airship.hpp"
#include "haptel/config/blimp_course.hpp"
#include "haptel/config/blimp_course_geometry.hpp"
#include "haptel/core/blimp_command.hpp"
#include "haptel/mediator/blimp/observation.hpp"

namespace haptel::mediator {

struct BlimpPilotConfig {
  double cruise_airspeed = 6.0;    ///< m/s
  double reaction_delay_s = 0.15;  ///< the pilot acts on what it saw this long ago
  // Guidance.
  double lookahead = 18.0;      ///< m: the pursued point, ahead along the approach line
  double exit_distance = 12.0;  ///< m beyond a gate: the furthest point pursued through it
  double turn_back_distance =
      25.0;  ///< m before a gate: where to go when past its plane without passing it
  /// Off the approach line by more than half the gate's width, the pursued
  /// point stays this many metres before the gate per metre off the line.
  double approach_slope = 1.0;
  double building_clearance = 4.5;  ///< m from a roof up to the centre of gravity
  double building_margin = 6.0;     ///< m: buildings this close to the way ahead are climbed over
  /// s: buildings this close to where the blimp drifts (its ground velocity
  /// for this long) are climbed over too: slow, a cross wind carries it off
  /// its way faster than it turns, onto what was beside it (lab's 1 m/s
  /// wind, the hop's shed). Long enough to climb over a roof at max_climb.
  double drift_lookahead_s = 8.0;
  double takeoff_height = 2.5;  ///< m above the start before heading off at speed
  // The take-off, as an airship is launched: the wind is found first.
  /// s on the pad reading the airspeed, which at rest is the wind's speed
  /// (less, once the wind drags the hull along: then it goes at once).
  double pad_watch_s = 1.0;
  /// m/s: a wind read on the pad at least this fast is watched from over
  /// the pad before leaving: the hull rises straight up (no forward thrust;
  /// the power waits for the helix plane to tilt up, the hull kept level) to
  /// half a metre over takeoff_height — higher where its drift would take it
  /// onto a building — and drifts with the air, its nose turned into the
  /// wind as the drift shows it, until its estimate is steady: at least
  /// wind_watch_min_s clear of the pad, and the drift's measured wind within
  /// wind_steady_mps of the estimate for wind_steady_s (at most
  /// wind_watch_max_s). Then it leaves into the wind until the rudder bites.
  /// A lighter wind is learnt on the way (the take-off at the cruise's
  /// airspeed). Climbing out at once in harsh's 3.5 m/s, the hull was blown
  /// 20 m onto the hop's shed in 2 s with a 400-ms link. (lab blows 1.0 +/-
  /// 0.3 m/s, harsh 3.0 +/- 0.5.)
  double watch_wind_speed = 1.6;
  double wind_watch_min_s = 3.0;
  double wind_watch_tau_s = 2.0;  ///< s: the estimate's smoothing while watching (4 s after)
  double wind_settle_s = 1.5;     ///< s clear of the pad before the drift tells the wind
  double wind_steady_mps = 0.8;   ///< (harsh's gusts are 1 m/s rms)
  double wind_steady_s = 1.0;
  double wind_watch_max_s = 12.0;
  /// m/s: the airspeed wanted while climbing out to takeoff_height. Slower,
  /// the rudder does not bite (tail_rotor_speed) and the hull goes where a
  /// cross wind carries it and turns as the air turns it (a tail wind turns
  /// it broadside), so that it meets a near first gate far off its
  /// approach line; the cruise's climbs out as an aeroplane does, the
  /// thrust forwards and up, and the rudder bites within a couple of seconds.
  double climb_out_airspeed = 6.0;
  // Height.
  double height_gain = 0.6;  ///< 1/s: climb rate per metre of height error
  double max_climb = 1.5;    ///< m/s
  double max_sink = 1.5;     ///< m/s
  /// m/s: landing, the fastest sink at the ground, growing by flare_gain
  /// per metre above it (up to landing_max_sink).
  double touchdown_sink = 0.4;
  double flare_gain = 0.3;         ///< 1/s
  double landing_max_sink = 0.8;   ///< m/s (the course's crash speed is 1.5)
  double vertical_gain = 10.0;     ///< N per m/s of climb-rate error
  double vertical_integral = 3.0;  ///< N per m of integrated climb-rate error (trims the weight)
  double vertical_drag_per_speed2 =
      2.9;  ///< N/(m/s)²: the feel for the hull's resistance to climbing
  // Speed.
  double speed_gain = 6.0;        ///< N per m/s of speed error
  double speed_integral = 1.5;    ///< N per m of integrated speed error
  double drag_per_speed2 = 0.31;  ///< N/(m/s)²: the pilot's feel for the hull's drag (feed-forward)
  /// Landing: the ground speed wanted d metres from the circle's centre is
  /// landing_speed·exp(d / landing_coast_length) (at most the cruise), the
  /// speed a hull coasting on its axial drag alone keeps — it cannot
  /// reverse its propellers to brake — tapering to nothing over the last 2 m.
  double landing_speed = 0.6;          ///< m/s
  double landing_coast_length = 48.0;  ///< m: axial added mass over the drag's factor
  /// The glide down: landing_hover + landing_glide·d above the start's
  /// height (at most the last gate's); over the circle (within sink_share
  /// of its radius) and slower than 0.9 of its max_speed, down onto the
  /// ground (and on down, unless it drifts out beyond rise_share).
  double landing_hover = 1.0;  ///< m
  double landing_glide = 0.1;  ///< m per m
  double landing_climb = 0.3;  ///< m/s: the fastest climb while landing
  /// Shares of the circle's radius: within sink_share (and slow) it sinks,
  /// beyond rise_share it rises again.
  double sink_share = 0.6;
  double rise_share = 0.85;
  /// Landed: the helix plane down at this power, holding the gondola on the
  /// ground (friction against the wind).
  double landed_press_power = 0.3;
  // Steering.
  double heading_gain = 3.0;      ///< rudder per rad of course error
  double yaw_rate_gain = 2.5;     ///< rudder per rad/s of yaw rate
  double tail_rotor_speed = 2.2;  ///< m/s: below this airspeed the rudder barely bites (8 km/h)
  /// rad: slower than tail_rotor_speed and further off the heading wanted,
  /// a turnabout (power off, the tail rotor on) until within turnabout_done_error.
  double turnabout_error = 0.8;
  double turnabout_done_error = 0.2;  ///< rad
  /// rad: landing, slow all the way, the tail rotor is the only steering
  /// left: a turnabout for smaller errors.
  double landing_turnabout_error = 0.35;
  /// m/s: landing in a wind faster than tail_rotor_speed, the air velocity
  /// wanted (the ground velocity wanted less the wind) gives the heading
  /// when faster than this; slower, the nose goes into the wind.
  double landing_min_air = 0.4;
  /// m/s: a head wind over this on the way to the circle (beyond 0.8 of its
  /// radius): the ground speed wanted is no slower than gives the rudder's
  /// bite through the air (tail_rotor_speed + 0.5) — the head wind brakes
  /// the hull when the power goes. At the coasting speed instead, downwind
  /// of the circle in lab's 1 m/s, the rudder did not bite and the hull
  /// circled on its tail rotor, drifting away to the lap's cap.
  double landing_headwind = 0.3;
  /// s: a turnabout lasts at most this long, and the next begins no sooner
  /// after it (flying on with power in between).
  double turnabout_max_s = 8.0;
  /// The power is the only way up or down: a turnabout begins only with
  /// the height within this (m) of the target and the climb rate under
  /// turnabout_climb (m/s), and ends at twice either, drifting away.
  double turnabout_height_error = 1.5;
  double turnabout_climb = 0.35;
  double pitch_gain = 2.0;        ///< elevator per rad of pitch error
  double pitch_rate_gain = 1.0;   ///< elevator per rad/s of pitch rate
  double pitch_per_climb = 0.08;  ///< rad of nose-up per m/s of climb wanted
  // What the pilot knows of its blimp (PilotKnowing).
  double full_thrust_n = 29.4;     ///< both main motors at full power
  double max_helix_deg = 90.0;     ///< the helix plane's tilt at full command
  double helix_rate_deg_s = 90.0;  ///< how fast the helix plane tilts

  void ValidateOrThrow() const;
};

/// The pilot's knowledge of its blimp taken from the airship's own
/// parameters — full thrust, the helix plane's range and rate — so that its
/// hands give the forces it means on the blimp the vehicle file describes;
/// the rest of `config` as given. (Its feel for the drag stays its own:
/// drag_per_speed2 is a rounded 0.31 where ½·ρ·Cd·V^⅔ of sim-blimp.yaml is
/// 0.312.)
BlimpPilotConfig PilotKnowing(const AirshipConfig& airship, BlimpPilotConfig config = {});

class BlimpAutoPilot {
 public:
  /// kTakeOff: up over the pad, watching the wind; kClimbOut: into the
  /// wind until the rudder bites (in a wind that needs it).
  enum class Phase { kGround, kTakeOff, kClimbOut, kGates, kLanding, kLanded };

  /// Validates and copies both (ConfigFieldError).
  BlimpAutoPilot(const BlimpCourseConfig& course, const BlimpPilotConfig& config = {});

  /// Something the pilot saw (t_s increasing). Allocation-free.
  void Observe(const BlimpObservation& observation);
  /// With a predictive display, what the pilot flies by (Observe) is the
  /// blimp as the predictor models it, whose ground velocity and airspeed
  /// differ by the model's own wind (the file's, or the predictor's
  /// estimate): a wind the model does not know the pilot would never see.
  /// The wind it estimates comes from the states as the blimp reported them
  /// instead (`reported`, t_s increasing: their ground velocity against the
  /// airspeed the blimp measured along its heading), once this is called.
  /// Allocation-free.
  void ObserveReported(const BlimpObservation& reported);
  /// What the pilot commands at t_s (increasing), from what it saw
  /// reaction_delay_s before. Neutral until it has seen anything.
  /// Allocation-free.
  BlimpCommand Decide(double t_s);

  Phase phase() const { return phase_; }
  /// The height it aims at now, m.
  double target_height() const { return target_z_; }
  /// The horizontal wind it estimates (world frame, m/s).
  const Eigen::Vector2d& wind() const { return wind_; }
  /// The wind estimate is steady (the take-off's watch is over); when.
  bool wind_known() const { return wind_known_s_ >= 0.0; }
  double wind_known_s() const { return wind_known_s_; }

 private:
  /// The newest observation seen at or before t; null when none.
  const BlimpObservation* Seen(double t) const;
  /// The lowest safe height on the way from o's position to the target
  /// point, and on the way it drifts (drift_lookahead_s of its ground velocity).
  double SafeHeight(const BlimpObservation& o, const Eigen::Vector2d& target) const;
  Eigen::Vector2d Pursue(const BlimpGateFrame& gate, const Eigen::Vector3d& p) const;

  /// What a phase wants of the hands: a direction and a speed.
  struct Aim {
    double bearing = 0.0;  ///< rad: the direction wanted over the ground (crab) or the heading
    bool crab = true;      ///< head into the wind enough to make good the bearing
    double forward_speed = 0.0;  ///< m/s along the heading
    bool ground_speed = false;   ///< forward_speed over the ground, not through the air
    bool landing = false;        ///< thrust up only: it sinks on its own weight
  };
  /// What an observation newer than the last one used tells: the rates, the
  /// gate crossed, the wind (unless the reported states tell it). The first
  /// one starts the take-off.
  void TakeIn(const BlimpObservation& o);
  /// The wind from `o`, `h` seconds after the last one it came from.
  void EstimateWind(const BlimpObservation& o, double h);
  /// On the pad: the airspeed at rest, the wind's speed (pad_wind_).
  void ReadPad(const BlimpObservation& o);
  /// Off the ground, through the last gate, down in (or out of) the circle.
  void NextPhase(const BlimpObservation& o);
  // One function per phase: each sets target_z_ and says what it wants.
  Aim WatchWind(const BlimpObservation& o);
  Aim ClimbOut(const BlimpObservation& o);
  Aim FlyGate(const BlimpObservation& o);
  Aim Land(const BlimpObservation& o);
  BlimpCommand Landed();
  /// A wind the rudder bites in, heading into it (at least tail_rotor_speed).
  bool StrongWind() const { return wind_.norm() >= config_.tail_rotor_speed; }
  /// The wind read on the pad is fresh: watched before leaving, then into it.
  bool StrongPadWind() const { return pad_wind_ >= config_.watch_wind_speed; }
  /// The camera at the next gate, or at the landing circle.
  void Look(const BlimpObservation& o, BlimpCommand& c) const;
  /// The turn (rudder, or tail rotor) towards the aim's heading; begins and
  /// ends a turnabout.
  double Steer(const BlimpObservation& o, const Aim& aim, double t_s);
  /// The forward and vertical forces as power and the helix plane's tilt.
  void Thrust(const BlimpObservation& o, const Aim& aim, double dt, BlimpCommand& c);
  /// The ground speed wanted `distance` metres from the landing circle's
  /// centre: what a hull coasting on its drag keeps, at most the cruise.
  double ApproachSpeed(double distance) const;

  BlimpCourseConfig course_;
  BlimpPilotConfig config_;
  std::vector<BlimpGateFrame> gates_;
  std::vector<BlimpFootprint> footprints_;
  /// Observations kept: 10 s at 50 Hz (the oldest stands in for older ones).
  static constexpr size_t kSeen = 512;
  std::array<BlimpObservation, kSeen> seen_{};
  size_t seen_count_ = 0;  ///< total ever observed
  Phase phase_ = Phase::kGround;
  int gate_ = 0;
  double start_z_ = 0.0;
  bool have_used_ = false;
  BlimpObservation used_;  ///< the observation the last decision used
  double yaw_rate_ = 0.0, pitch_rate_ = 0.0;
  double last_decide_t_ = 0.0;
  bool decided_ = false;
  double speed_i_ = 0.0, vertical_i_ = 0.0;
  double target_z_ = 0.0;
  double climb_ = 0.0;          ///< m/s: the climb rate wanted
  bool height_settled_ = true;  ///< landing: near the height wanted and steady
  double helix_ = 0.0;
  bool helix_up_ = true;
  bool sinking_ = false;           ///< over the landing circle, on the way down
  bool turnabout_ = false;         ///< power off, turning on the tail rotor
  double turnabout_since_ = -1e9;  ///< when the turnabout began, or the last one ended
  Eigen::Vector2d wind_ = Eigen::Vector2d::Zero();
  bool wind_from_reports_ = false;  ///< ObserveReported was called: the wind is theirs
  double airborne_since_ = -1.0;    ///< the first observation off the ground (watching the wind)
  double wind_steady_since_ = 0.0;  ///< since when the measured wind agrees with the estimate
  double wind_known_s_ = -1.0;      ///< when the wind estimate became steady
  // The pad's reading (ReadPad): from the reported states once they come apart.
  double pad_since_ = 0.0, pad_airspeed_sum_ = 0.0, pad_wind_ = 0.0;
  int pad_samples_ = 0;
  bool pad_read_ = false;
  double takeoff_t_ = -1.0;  ///< when the first decision was taken (the helix plane tilts up)
  double last_report_t_ = 0.0;
};

}  // namespace haptel::mediator
