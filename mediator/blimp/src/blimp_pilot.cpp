#include "haptel/mediator/blimp/blimp_pilot.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "haptel/config/check.hpp"
#include "haptel/config/error.hpp"
#include "haptel/core/geometry2d.hpp"

namespace haptel::mediator {

namespace check = config_check;

namespace {

Eigen::Vector2d Horizontal(const Eigen::Vector3d& v) { return {v.x(), v.y()}; }

double Bearing(const Eigen::Vector2d& d) { return std::atan2(d.y(), d.x()); }

/// The airspeed's horizontal part: the air's vertical speed taken as the
/// climb's (no vertical wind). Climbing straight up in still air, the whole
/// airspeed is the climb's, none of it along the heading.
double HorizontalAirspeed(const BlimpObservation& o) {
  return std::sqrt(std::max(0.0, o.airspeed * o.airspeed - o.velocity.z() * o.velocity.z()));
}

}  // namespace

void BlimpPilotConfig::ValidateOrThrow() const {
  check::Number("cruise_airspeed", cruise_airspeed, 0.5, 15.0);
  check::Number("reaction_delay_s", reaction_delay_s, 0.0, 2.0);
  check::Number("lookahead", lookahead, 1.0, 200.0);
  check::Number("exit_distance", exit_distance, 0.0, 200.0);
  check::Number("turn_back_distance", turn_back_distance, 1.0, 500.0);
  check::Number("approach_slope", approach_slope, 0.0, 10.0);
  check::Number("building_clearance", building_clearance, 0.0, 100.0);
  check::Number("building_margin", building_margin, 0.0, 100.0);
  check::Number("drift_lookahead_s", drift_lookahead_s, 0.0, 60.0);
  check::Number("takeoff_height", takeoff_height, 0.1, 50.0);
  check::Number("climb_out_airspeed", climb_out_airspeed, 0.0, cruise_airspeed);
  check::Number("pad_watch_s", pad_watch_s, 0.0, 60.0);
  check::Number("watch_wind_speed", watch_wind_speed, 0.0, 20.0);
  check::Number("wind_watch_min_s", wind_watch_min_s, 0.0, 60.0);
  check::Number("wind_watch_tau_s", wind_watch_tau_s, 0.1, 60.0);
  check::Number("wind_settle_s", wind_settle_s, 0.0, wind_watch_min_s);
  check::Number("wind_steady_mps", wind_steady_mps, 0.01, 10.0);
  check::Number("wind_steady_s", wind_steady_s, 0.0, 60.0);
  check::Number("wind_watch_max_s", wind_watch_max_s, wind_watch_min_s, 120.0);
  check::Number("height_gain", height_gain, 0.01, 10.0);
  check::Number("max_climb", max_climb, 0.05, 10.0);
  check::Number("max_sink", max_sink, 0.05, 10.0);
  check::Number("touchdown_sink", touchdown_sink, 0.05, max_sink);
  check::Number("vertical_gain", vertical_gain, 0.0, 1000.0);
  check::Number("vertical_integral", vertical_integral, 0.0, 1000.0);
  check::Number("vertical_drag_per_speed2", vertical_drag_per_speed2, 0.0, 100.0);
  check::Number("speed_gain", speed_gain, 0.0, 1000.0);
  check::Number("speed_integral", speed_integral, 0.0, 1000.0);
  check::Number("drag_per_speed2", drag_per_speed2, 0.0, 100.0);
  check::Number("landing_speed", landing_speed, 0.05, 5.0);
  check::Number("landing_coast_length", landing_coast_length, 1.0, 1000.0);
  check::Number("landing_hover", landing_hover, 0.0, 20.0);
  check::Number("landing_glide", landing_glide, 0.0, 1.0);
  check::Number("landing_climb", landing_climb, 0.01, 5.0);
  check::Number("flare_gain", flare_gain, 0.0, 10.0);
  check::Number("landing_max_sink", landing_max_sink, touchdown_sink, max_sink);
  check::Number("sink_share", sink_share, 0.05, 1.0);
  check::Number("rise_share", rise_share, sink_share, 1.0);
  check::Number("landed_press_power", landed_press_power, 0.0, 1.0);
  check::Number("heading_gain", heading_gain, 0.0, 100.0);
  check::Number("yaw_rate_gain", yaw_rate_gain, 0.0, 100.0);
  check::Number("tail_rotor_speed", tail_rotor_speed, 0.0, 20.0);
  check::Number("turnabout_error", turnabout_error, 0.01, 3.2);
  check::Number("turnabout_done_error", turnabout_done_error, 0.0, turnabout_error);
  check::Number("turnabout_max_s", turnabout_max_s, 0.5, 120.0);
  check::Number("turnabout_height_error", turnabout_height_error, 0.05, 100.0);
  check::Number("turnabout_climb", turnabout_climb, 0.01, 10.0);
  check::Number("landing_min_air", landing_min_air, 0.0, 5.0);
  check::Number("landing_turnabout_error", landing_turnabout_error, turnabout_done_error, 3.2);
  check::Number("pitch_gain", pitch_gain, 0.0, 100.0);
  check::Number("pitch_rate_gain", pitch_rate_gain, 0.0, 100.0);
  check::Number("pitch_per_climb", pitch_per_climb, 0.0, 1.0);
  check::Number("full_thrust_n", full_thrust_n, 0.01, 1e5);
  check::Number("max_helix_deg", max_helix_deg, 1.0, 180.0);
  check::Number("helix_rate_deg_s", helix_rate_deg_s, 1.0, 10000.0);
}

BlimpPilotConfig PilotKnowing(const AirshipConfig& airship, BlimpPilotConfig config) {
  config.full_thrust_n = airship.max_thrust;
  config.max_helix_deg = airship.max_helix_deg;
  config.helix_rate_deg_s = airship.helix_rate_deg_s;
  return config;
}

BlimpAutoPilot::BlimpAutoPilot(const BlimpCourseConfig& course, const BlimpPilotConfig& config)
    : course_(Validated(course)),
      config_(Validated(config)),
      gates_(MakeGateFrames(course)),
      footprints_(MakeFootprints(course)) {}

double BlimpAutoPilot::ApproachSpeed(double distance) const {
  return std::min(config_.cruise_airspeed,
                  config_.landing_speed * std::exp(distance / config_.landing_coast_length));
}

void BlimpAutoPilot::Observe(const BlimpObservation& observation) {
  seen_[seen_count_ % kSeen] = observation;
  ++seen_count_;
}

const BlimpObservation* BlimpAutoPilot::Seen(double t) const {
  const size_t held = std::min(seen_count_, kSeen);
  for (size_t k = 0; k < held; ++k) {
    const BlimpObservation& o = seen_[(seen_count_ - 1 - k) % kSeen];
    if (o.t_s <= t) return &o;
  }
  // All newer: nothing seen long enough ago yet, or (the ring overrun) the oldest kept.
  return seen_count_ > kSeen ? &seen_[seen_count_ % kSeen] : nullptr;
}

double BlimpAutoPilot::SafeHeight(const BlimpObservation& o, const Eigen::Vector2d& target) const {
  const Eigen::Vector2d p = Horizontal(o.position);
  const Eigen::Vector2d drift = p + Horizontal(o.velocity) * config_.drift_lookahead_s;
  double z = -std::numeric_limits<double>::infinity();
  for (const BlimpFootprint& b : footprints_) {
    if (b.Distance(p, target) < config_.building_margin ||
        b.Distance(p, drift) < config_.building_margin)
      z = std::max(z, b.height() + config_.building_clearance);
  }
  return z;
}

Eigen::Vector2d BlimpAutoPilot::Pursue(const BlimpGateFrame& gate, const Eigen::Vector3d& p) const {
  const Eigen::Vector2d c = Horizontal(gate.centre), forward = Horizontal(gate.forward);
  const Eigen::Vector2d d = Horizontal(p) - c;
  const double along = d.dot(forward);
  const double off = std::abs(d.dot(Horizontal(gate.left)));
  if (along > 0.0)
    return c - config_.turn_back_distance * forward;  // past it: go round and come again
  double ahead = std::min(along + config_.lookahead, config_.exit_distance);
  if (off > gate.half_width)
    ahead = std::min(ahead, -config_.approach_slope * (off - gate.half_width));
  return c + ahead * forward;
}

void BlimpAutoPilot::TakeIn(const BlimpObservation& o) {
  if (!have_used_) {
    have_used_ = true;
    start_z_ = o.position.z();
    phase_ = Phase::kGround;
    if (!wind_from_reports_) ReadPad(o);
    used_ = o;
    return;
  }
  if (o.t_s <= used_.t_s) return;
  const double h = o.t_s - used_.t_s;
  yaw_rate_ = WrapAngle(o.yaw - used_.yaw) / h;
  pitch_rate_ = (o.pitch - used_.pitch) / h;
  // The gate flown to, crossed (through it, or near it: missed, on to the next).
  if (phase_ == Phase::kGates || phase_ == Phase::kClimbOut) {
    const auto pass = CrossGate(gates_[static_cast<size_t>(gate_)], used_.position, o.position);
    if (pass && pass->crossing != BlimpGateCrossing::kIgnored) ++gate_;
    if (gate_ >= static_cast<int>(gates_.size())) phase_ = Phase::kLanding;
  }
  if (!wind_from_reports_) {
    ReadPad(o);
    EstimateWind(o, h);
  }
  used_ = o;
}

void BlimpAutoPilot::ReadPad(const BlimpObservation& o) {
  // At rest on the pad the airspeed is the wind's speed (an anemometer at
  // the mast). Read for pad_watch_s, or until the wind drags the hull along.
  if (pad_read_) return;
  if (pad_samples_ == 0) pad_since_ = o.t_s;
  const bool at_rest = Horizontal(o.velocity).norm() < 0.3;
  if (at_rest) {
    pad_airspeed_sum_ += o.airspeed;
    ++pad_samples_;
  }
  if (o.t_s - pad_since_ >= config_.pad_watch_s || !at_rest) {
    pad_read_ = true;
    pad_wind_ = pad_samples_ > 0 ? pad_airspeed_sum_ / pad_samples_ : 0.0;
    // Dragged along the ground, the hull goes with the wind, slower than it
    // (harsh's heavier gondola slides from the start: seen a moment late,
    // through a 400-ms link, it was never at rest and read as calm).
    if (!at_rest && o.contact)
      pad_wind_ = std::max(pad_wind_, Horizontal(o.velocity).norm() + o.airspeed);
  }
}

void BlimpAutoPilot::EstimateWind(const BlimpObservation& o, double h) {
  // What the ground speed has beyond the airspeed along the heading
  // (sideslip neglected), smoothed over a few seconds.
  if (o.contact) return;
  const Eigen::Vector2d heading(std::cos(o.yaw), std::sin(o.yaw));
  // (While watching the wind, the airspeed's horizontal part: the hull climbs straight up.)
  const Eigen::Vector2d measured =
      Horizontal(o.velocity) - (wind_known() ? o.airspeed : HorizontalAirspeed(o)) * heading;
  if (wind_known()) {
    // Slower than the rudder bites the hull slips sideways through the air
    // (turnabouts, the landing), and the slip would be read as wind (0.8
    // m/s of it in lab's landings, and the nose put 25 deg off the wind):
    // the estimate holds until the hull flies along its heading again.
    if (HorizontalAirspeed(o) >= config_.tail_rotor_speed)
      wind_ += (measured - wind_) * std::min(1.0, h / 4.0);
    return;
  }
  // Watching: the first second off the pad tells nothing (the air still
  // comes from the side, taken as from ahead); then the drift, smoothed.
  // (Clear of the pad: a hull the wind drags along the ground is held back by it.)
  // (Nor before the pilot has seen where the pad is: the reported states
  // come before its first decision, and at rest on the pad they would read
  // the air from the side as a steady wind from ahead.)
  if (airborne_since_ < 0.0 && (!have_used_ || o.position.z() - start_z_ < 0.5)) return;
  if (airborne_since_ < 0.0) airborne_since_ = o.t_s;
  if (o.t_s - airborne_since_ < config_.wind_settle_s) {
    wind_ = measured;
    wind_steady_since_ = o.t_s;
    return;
  }
  wind_ += (measured - wind_) * std::min(1.0, h / config_.wind_watch_tau_s);
  // Known once off the ground long enough and the drift measures what the
  // estimate says for a while (or at the latest wind_watch_max_s).
  if ((measured - wind_).norm() > config_.wind_steady_mps) wind_steady_since_ = o.t_s;
  const double airborne = o.t_s - airborne_since_;
  if ((airborne >= config_.wind_watch_min_s &&
       o.t_s - wind_steady_since_ >= config_.wind_steady_s) ||
      airborne >= config_.wind_watch_max_s)
    wind_known_s_ = o.t_s;
}

void BlimpAutoPilot::ObserveReported(const BlimpObservation& reported) {
  ReadPad(reported);
  if (wind_from_reports_ && reported.t_s > last_report_t_)
    EstimateWind(reported, reported.t_s - last_report_t_);
  wind_from_reports_ = true;
  last_report_t_ = reported.t_s;
}

void BlimpAutoPilot::NextPhase(const BlimpObservation& o) {
  // The wind read on the pad: a fresh one is watched from over the pad
  // before leaving; a light one is not.
  if (phase_ == Phase::kGround && pad_read_) {
    if (StrongPadWind()) {
      phase_ = Phase::kTakeOff;
    } else {
      phase_ = Phase::kClimbOut;
      wind_known_s_ = o.t_s;  // light: learnt on the way, the rudder biting over it
    }
  }
  // Up over the pad, and the wind known: into it.
  if (phase_ == Phase::kTakeOff && wind_known() &&
      o.position.z() - start_z_ > config_.takeoff_height)
    phase_ = Phase::kClimbOut;
  // Climbing out: in a strong wind until the rudder bites, heading into
  // it; in a light one, up to takeoff_height.
  if (phase_ == Phase::kClimbOut &&
      (StrongPadWind() ? HorizontalAirspeed(o) > config_.tail_rotor_speed + 1.0 &&
                             std::abs(WrapAngle(Bearing(-wind_) - o.yaw)) < config_.turnabout_error
                       : o.position.z() - start_z_ > config_.takeoff_height))
    phase_ = Phase::kGates;  // a course has at least one gate
  if (phase_ == Phase::kLanding && o.contact && OnLandingGround(course_, o.position, start_z_))
    phase_ = Phase::kLanded;
  // Slid out of the circle on the ground: up and in again.
  const Eigen::Vector2d landing(course_.landing.centre[0], course_.landing.centre[1]);
  if (phase_ == Phase::kLanded &&
      (Horizontal(o.position) - landing).norm() > course_.landing.radius) {
    phase_ = Phase::kLanding;
    sinking_ = false;
  }
}

BlimpAutoPilot::Aim BlimpAutoPilot::WatchWind(const BlimpObservation& o) {
  // Straight up and hold, no forward thrust, the heading let be: the hull
  // drifts with the air, which shows the wind. Higher over what it drifts onto.
  // Once the drift shows which way the wind blows, the nose turns into it
  // (on the tail rotor: slow, the rudder does not bite), ready to leave.
  Aim aim;
  aim.bearing = airborne_since_ >= 0.0 && wind_.norm() > 0.5 ? Bearing(-wind_) : o.yaw;
  aim.crab = false;
  aim.forward_speed = 0.0;
  target_z_ =
      std::max(start_z_ + config_.takeoff_height + 0.5, SafeHeight(o, Horizontal(o.position)));
  return aim;
}

BlimpAutoPilot::Aim BlimpAutoPilot::ClimbOut(const BlimpObservation& o) {
  // In a strong wind, into it, as an airship is launched: the airspeed
  // (and with it the rudder) comes without ground speed, and the hull is
  // not blown broadside onto what lies downwind; over anything on the way
  // upwind. In a light one, for the first gate at the cruise's airspeed.
  const BlimpGateFrame& g = gates_.front();
  Aim aim;
  aim.crab = false;
  aim.forward_speed = config_.climb_out_airspeed;
  target_z_ = std::max(g.centre.z(), SafeHeight(o, Horizontal(g.centre)));
  if (StrongPadWind()) {
    aim.bearing = Bearing(-wind_);
    const Eigen::Vector2d upwind = Horizontal(o.position) - wind_.normalized() * config_.lookahead;
    target_z_ = std::max(target_z_, SafeHeight(o, upwind));
  } else {
    aim.bearing = Bearing(Pursue(g, o.position) - Horizontal(o.position));
  }
  return aim;
}

BlimpAutoPilot::Aim BlimpAutoPilot::FlyGate(const BlimpObservation& o) {
  const BlimpGateFrame& g = gates_[static_cast<size_t>(gate_)];
  const Eigen::Vector2d position = Horizontal(o.position);
  Aim aim;
  aim.bearing = Bearing(Pursue(g, o.position) - position);
  aim.forward_speed = config_.cruise_airspeed;
  target_z_ = std::max(g.centre.z(), SafeHeight(o, Horizontal(g.centre)));
  // The landing near after the last gate: through it no faster than
  // the approach's speed there, or the hull coasts past the circle.
  // (Only once lined up on it: slow, the rudder bites less, and turning
  // onto the line in a tail wind the hull is carried past the post.)
  const Eigen::Vector2d forward = Horizontal(g.forward);
  const bool lined_up =
      std::abs((position - Horizontal(g.centre)).dot(Horizontal(g.left))) < g.half_width &&
      std::abs(WrapAngle(Bearing(Horizontal(o.velocity)) - Bearing(forward))) < 0.35;
  if (gate_ == static_cast<int>(gates_.size()) - 1 && lined_up) {
    const Eigen::Vector2d landing(course_.landing.centre[0], course_.landing.centre[1]);
    const double to_landing =
        (Horizontal(g.centre) - position).norm() + (landing - Horizontal(g.centre)).norm();
    // (No slower than half as fast again as the rudder bites; at twice, the
    // hull coasted through the circle at 1.3-1.5 m/s with a 400-ms link and
    // turned back from beyond it: the twin's hop 60 s, not 38.)
    aim.forward_speed = std::max(ApproachSpeed(to_landing),
                                 std::min(1.5 * config_.tail_rotor_speed, config_.cruise_airspeed));
  }
  return aim;
}

BlimpAutoPilot::Aim BlimpAutoPilot::Land(const BlimpObservation& o) {
  const Eigen::Vector2d landing(course_.landing.centre[0], course_.landing.centre[1]);
  const Eigen::Vector2d to = landing - Horizontal(o.position);
  const double distance = to.norm();
  // A glide down to a little above the ground, then, over the circle
  // and slow, down onto it.
  target_z_ = std::min(gates_.back().centre.z(),
                       start_z_ + config_.landing_hover + config_.landing_glide * distance);
  // Once sinking it sinks on, unless it drifts out towards the circle's edge.
  if (distance < config_.sink_share * course_.landing.radius &&
      Horizontal(o.velocity).norm() < 0.9 * course_.landing.max_speed)
    sinking_ = true;
  if (distance > config_.rise_share * course_.landing.radius) sinking_ = false;
  if (sinking_) target_z_ = start_z_ - 2.0;
  target_z_ = std::max(target_z_, SafeHeight(o, landing));
  // The ground velocity wanted: towards the centre, slowing as it nears
  // it as fast as the hull coasts down on its own drag.
  double speed = ApproachSpeed(distance) * std::min(1.0, distance / 2.0);
  // Against the wind, short of the circle, no slower than the rudder bites
  // through the air: the head wind brakes the hull when the power goes
  // (downwind of the circle, at the coasting speed the rudder did not bite
  // and the hull circled on its tail rotor, drifting away).
  if (distance > 0.8 * course_.landing.radius) {
    const double headwind = -wind_.dot(to / distance);
    if (headwind > config_.landing_headwind)
      speed = std::max(speed, std::min(config_.tail_rotor_speed + 0.5 - headwind,
                                       config_.cruise_airspeed - headwind));
  }
  const Eigen::Vector2d wanted =
      distance > 1e-6 ? Eigen::Vector2d(to / distance * speed) : Eigen::Vector2d::Zero();
  Aim aim;
  aim.landing = true;
  aim.ground_speed = true;
  const Eigen::Vector2d heading(std::cos(o.yaw), std::sin(o.yaw));
  aim.forward_speed = wanted.dot(heading);
  if (StrongWind()) {
    // A wind the rudder bites in: the wind triangle. The hull heads along
    // the velocity through the air that makes good the ground velocity
    // wanted (the wanted less the wind): into the wind, crabbed across it
    // towards the circle, its last metres flown from downwind, nose to the
    // wind, the rudder biting on the airspeed the wind gives — a blimp's
    // landing. (Heading for the circle at the approach's speed instead,
    // under a metre a second, the rudder does not bite, the tail rotor
    // loses to the wind, and the hull hovers against it off the circle.)
    const Eigen::Vector2d air = wanted - wind_;
    aim.crab = false;
    aim.bearing = air.norm() > config_.landing_min_air ? Bearing(air) : Bearing(-wind_);
  } else if (distance > 0.8 * course_.landing.radius) {
    // A light wind: for the centre, the tail rotor turning the slow hull.
    aim.bearing = Bearing(to);
  } else {
    // Close: face into the wind (the thrust can only push forwards); in
    // calm air hold the heading (steered for the centre to the last 3 m,
    // the hull turned on its tail rotor round the centre and touched).
    aim.bearing = wind_.norm() > 0.4 ? Bearing(-wind_) : o.yaw;
    aim.crab = false;
  }
  return aim;
}

BlimpCommand BlimpAutoPilot::Landed() {
  // Down: the helix plane down, pressing the gondola onto the ground
  // until it stops sliding, then the power off; surfaces centred.
  BlimpCommand c;
  c.helix = -1.0;
  c.power = config_.landed_press_power;
  speed_i_ = vertical_i_ = 0.0;
  return c;
}

void BlimpAutoPilot::Look(const BlimpObservation& o, BlimpCommand& c) const {
  // The camera: at the next gate, or at the landing circle.
  const Eigen::Vector3d look =
      phase_ != Phase::kLanding && phase_ != Phase::kLanded
          ? gates_[static_cast<size_t>(gate_)].centre
          : Eigen::Vector3d(course_.landing.centre[0], course_.landing.centre[1], 0.0);
  const Eigen::Vector3d sight = look - o.position;
  c.camera_pan = std::clamp(WrapAngle(Bearing(Horizontal(sight)) - o.yaw), -kBlimpCameraPanMax,
                            kBlimpCameraPanMax);
  c.camera_tilt = std::clamp(std::atan2(sight.z(), Horizontal(sight).norm()) - o.pitch,
                             -kBlimpCameraTiltMax, kBlimpCameraTiltMax);
}

BlimpCommand BlimpAutoPilot::Decide(double t_s) {
  const double dt = decided_ ? std::clamp(t_s - last_decide_t_, 0.0, 0.5) : 0.0;
  decided_ = true;
  last_decide_t_ = t_s;
  const BlimpObservation* seen = Seen(t_s - config_.reaction_delay_s);
  if (seen == nullptr) return BlimpCommand{};
  const BlimpObservation o = *seen;
  TakeIn(o);
  NextPhase(o);
  Aim aim;
  switch (phase_) {
    case Phase::kGround: {  // on the pad, reading the wind
      BlimpCommand c;
      Look(o, c);
      return c;
    }
    case Phase::kTakeOff:
      aim = WatchWind(o);
      break;
    case Phase::kClimbOut:
      aim = ClimbOut(o);
      break;
    case Phase::kGates:
      aim = FlyGate(o);
      break;
    case Phase::kLanding:
      aim = Land(o);
      break;
    case Phase::kLanded: {
      BlimpCommand c = Landed();
      Look(o, c);
      return c;
    }
  }
  BlimpCommand c;
  Look(o, c);
  const double turn = Steer(o, aim, t_s);
  c.rudder = turn;
  Thrust(o, aim, dt, c);
  // The tail rotor with the power off, as the cockpit allows; a weak thrust
  // is let go too, so that the tail rotor can hold the heading.
  // Lifting off, no power until the helix plane has tilted up from level:
  // the propellers would push the hull forwards, and on its low axial drag
  // it coasts on for tens of metres (the drift would not show the wind).
  if (takeoff_t_ < 0.0 && phase_ == Phase::kTakeOff) takeoff_t_ = t_s;
  if (phase_ == Phase::kTakeOff &&
      t_s - takeoff_t_ < config_.max_helix_deg / config_.helix_rate_deg_s + 0.3)
    c.power = 0.0;
  if (turnabout_ || c.power < 0.02) {
    c.power = 0.0;
    c.tail_rotor = turn;
  }
  // The elevator: a little nose-up to climb, damped; landing, level only
  // (slow, the surface's own force is most of what it does: nose-down
  // pushes the tail, and so the blimp, up).
  // Watching the wind, level too: a pitched hull going up or down glides
  // off along its axis through the air, and the drift no longer shows the wind.
  const double pitch_wanted = aim.landing || phase_ == Phase::kTakeOff
                                  ? 0.0
                                  : std::clamp(config_.pitch_per_climb * climb_, -0.15, 0.15);
  c.elevator = std::clamp(
      config_.pitch_gain * (pitch_wanted - o.pitch) - config_.pitch_rate_gain * pitch_rate_, -1.0,
      1.0);
  return Clamped(c);
}

double BlimpAutoPilot::Steer(const BlimpObservation& o, const Aim& aim, double t_s) {
  // Steering on the heading: the bearing, turned into the wind by the wind
  // triangle's angle (steering on the track over the ground instead lags the
  // heading by the hull's sideways inertia, and weaves).
  double heading_wanted = aim.bearing;
  if (aim.crab && o.airspeed > 1.5) {
    const double across = wind_.dot(Eigen::Vector2d(-std::sin(aim.bearing), std::cos(aim.bearing)));
    heading_wanted -= std::asin(std::clamp(across / o.airspeed, -0.7, 0.7));
  }
  const double error = WrapAngle(heading_wanted - o.yaw);
  const double turn =
      std::clamp(config_.heading_gain * error - config_.yaw_rate_gain * yaw_rate_, -1.0, 1.0);
  // The power is the only way up or down: landing, near the ground, a
  // turnabout waits for the height to settle, and ends when it drifts off
  // (higher up, the height can wait for the heading).
  const double height_error = target_z_ - o.position.z();
  const double climb_rate = std::abs(o.velocity.z());
  height_settled_ = !aim.landing || (std::abs(height_error) < config_.turnabout_height_error &&
                                     climb_rate < config_.turnabout_climb);
  // (Climbing out too: a hull heavier than its air sinks with the power
  // off, and near the pad the ground is close.)
  // Nor with the ground a metre below and coming up, unless landing on it
  // (a heavier gondola sank 3 m onto it, the height error never twice the limit).
  const bool height_lost =
      ((aim.landing || phase_ == Phase::kTakeOff || phase_ == Phase::kClimbOut) &&
       (std::abs(height_error) > 2.0 * config_.turnabout_height_error ||
        (climb_rate > 2.0 * config_.turnabout_climb && o.velocity.z() * height_error < 0.0))) ||
      (!sinking_ && height_error > 0.0 && o.position.z() - start_z_ < config_.landing_hover &&
       o.velocity.z() < -0.1);
  // Slow and off course, a turnabout: the gesture cockpit's tail rotor turns
  // only with the power off (the left hand sideways at zero power), so the
  // pilot lets go of the power and turns on the tail rotor until it heads
  // nearly right. Faster, the rudder bites and the power stays on.
  // A turnabout that does not get there — the wind weathercocks the hull
  // against the small tail rotor: after 2 s it turns the wrong way or
  // slower than 3°/s — gives way to power for turnabout_max_s.
  if (turnabout_) {
    const double lasted = t_s - turnabout_since_;
    const bool stuck = lasted > 2.0 && yaw_rate_ * (error > 0.0 ? 1.0 : -1.0) < 0.05;
    if (std::abs(error) < config_.turnabout_done_error ||
        o.airspeed > config_.tail_rotor_speed + 1.0 || lasted > config_.turnabout_max_s || stuck ||
        height_lost) {
      turnabout_ = false;
      turnabout_since_ = t_s;
    }
  } else if (o.airspeed < config_.tail_rotor_speed &&
             std::abs(error) >
                 (aim.landing ? config_.landing_turnabout_error : config_.turnabout_error) &&
             t_s - turnabout_since_ > config_.turnabout_max_s && height_settled_) {
    turnabout_ = true;
    turnabout_since_ = t_s;
  }
  return turn;
}

void BlimpAutoPilot::Thrust(const BlimpObservation& o, const Aim& aim, double dt, BlimpCommand& c) {
  // Height: a climb rate towards the target, a vertical force for it.
  // Landing, the sink slows as the ground nears (a flare): touchdown well
  // under the course's crash speed.
  const double height = o.position.z() - start_z_;
  const double max_sink =
      aim.landing ? std::min(config_.landing_max_sink,
                             config_.touchdown_sink + config_.flare_gain * std::max(0.0, height))
                  : config_.max_sink;
  climb_ = std::clamp(config_.height_gain * (target_z_ - o.position.z()), -max_sink,
                      aim.landing ? config_.landing_climb : config_.max_climb);
  const double climb_error = climb_ - o.velocity.z();
  // (The integrators hold still while the power is off for a turnabout.)
  if (!turnabout_)
    vertical_i_ = std::clamp(vertical_i_ + config_.vertical_integral * climb_error * dt, -6.0, 6.0);
  double up_force = config_.vertical_gain * climb_error + vertical_i_ +
                    config_.vertical_drag_per_speed2 * climb_ * std::abs(climb_);
  // Landing, near enough the height and steady: no vertical thrust, so the
  // power can stay off and the tail rotor steer (the hull floats level).
  // In a wind the rudder bites in (Land's wind triangle) the rudder steers
  // on the airspeed the wind gives, and the height is held: a hull heavier
  // than the air it displaces (harsh's short buoyancy, a heavier gondola)
  // would sink onto the ground short of the circle.
  // Not below the height wanted, though: a hull heavier than its air (a
  // heavier gondola) sinks while it floats, onto the ground short of the
  // circle in a light wind, before the height counts as lost.
  if (aim.landing && !sinking_ && height_settled_ && !StrongWind() &&
      o.position.z() > target_z_ - 0.5) {
    up_force = 0.0;
    vertical_i_ = 0.0;
  }

  // Speed: a forward force (the propellers push only forwards).
  const Eigen::Vector2d heading(std::cos(o.yaw), std::sin(o.yaw));
  const Eigen::Vector2d ground = Horizontal(o.velocity);
  const double measured = aim.ground_speed ? ground.dot(heading) : o.airspeed;
  const double speed_error = aim.forward_speed - measured;
  const double air_target =
      aim.ground_speed ? std::max(0.0, aim.forward_speed - wind_.dot(heading)) : aim.forward_speed;
  double forward_force = config_.drag_per_speed2 * air_target * air_target +
                         config_.speed_gain * speed_error + speed_i_;
  if (!turnabout_ && (forward_force > 0.0 || speed_error > 0.0)) {
    speed_i_ = std::clamp(speed_i_ + config_.speed_integral * speed_error * dt, -8.0, 8.0);
  }
  forward_force = std::max(0.0, forward_force);

  // Slow, the helix plane must not turn over between up and down (through
  // forwards: a push forwards, and the lag rocks the blimp up and down).
  // Sinking onto the circle: thrust only down, forwards, or between. On the
  // way to it: some forward thrust with any vertical thrust, so the tilt
  // passes smoothly through level. Else the plane turns over only for a
  // firm need.
  if (aim.landing && sinking_) {
    up_force = std::min(0.0, up_force);
  } else if (aim.landing && speed_error > 0.0) {
    forward_force = std::max(forward_force, 0.5 * std::abs(up_force));
  } else if (aim.landing) {
    // Too fast for the approach: no forward thrust at all, whatever the
    // height wants (the plane may turn straight up or down).
    forward_force = 0.0;
  } else if (forward_force < 2.0) {
    if (up_force > 1.5) helix_up_ = true;
    if (up_force < -1.5) helix_up_ = false;
    up_force = helix_up_ ? std::max(0.0, up_force) : std::min(0.0, up_force);
  } else {
    helix_up_ = up_force >= 0.0;
  }
  // The two forces as power and the helix plane's tilt.
  const double thrust = std::min(std::hypot(forward_force, up_force), config_.full_thrust_n);
  if (thrust > 1.0)
    helix_ = std::atan2(up_force, forward_force);  // (a weak thrust's direction is noise)
  c.power = thrust / config_.full_thrust_n;
  c.helix = std::clamp(helix_ / (config_.max_helix_deg * std::numbers::pi / 180.0), -1.0, 1.0);
}

}  // namespace haptel::mediator
