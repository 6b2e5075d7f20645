// The blimp family's part of a session (family_session.hpp): its course
// and lap timer, the gesture cockpit or a person's keys or game controller,
// the automatic pilot or a person, and the view's head-tracked screen.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "family_session.hpp"
#include "haptel/config/error.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/log.hpp"
#include "haptel/haptics/sim_device.hpp"
#include "haptel/interfaces/catalog.hpp"
#include "haptel/mediator/blimp/blimp_lap_timer.hpp"
#include "haptel/mediator/blimp/blimp_pilot.hpp"
#include "haptel/mediator/blimp_predictor.hpp"
#include "haptel/mediator/controller_errors.hpp"
#include "haptel/mediator/haptic_side.hpp"
#include "haptel/mediator/notice_log.hpp"
#include "haptel/mediator/operator.hpp"
#include "haptel/mediator/predictive_display.hpp"
#include "haptel/mediator/run_counters.hpp"

namespace haptel::mediator {

namespace {

BlimpObservation Observe(double t_s, const msg::BlimpState& s) {
  BlimpObservation o;
  o.t_s = t_s;
  o.position = Eigen::Vector3d(s.x(), s.y(), s.z());
  o.yaw = s.yaw();
  o.pitch = s.pitch();
  o.velocity = Eigen::Vector3d(s.vx(), s.vy(), s.vz());
  o.airspeed = s.airspeed();
  o.contact = s.contact();
  o.contacts = s.contacts();
  o.impact_speed = s.impact_speed();
  return o;
}

/// What the predictor takes of a state that arrived at `received_s`
/// (operator's clock, from `t0_ns`).
BlimpStateSample Sample(double received_s, const msg::BlimpState& s, int64_t t0_ns) {
  BlimpStateSample out;
  out.received_s = received_s;
  out.stamp_ns = s.stamp_ns();
  out.position = Eigen::Vector3d(s.x(), s.y(), s.z());
  out.yaw = s.yaw();
  out.pitch = s.pitch();
  out.roll = s.roll();
  out.velocity = Eigen::Vector3d(s.vx(), s.vy(), s.vz());
  const auto& o = s.outputs();  // in BlimpCommand's order
  out.applied = BlimpCommand{o[0], o[1], o[2], o[3], o[4], o[5], o[6]};
  if (s.last_command_sent_ns() > 0) {
    out.command_sent_s = NsToS(s.last_command_sent_ns() - t0_ns);
    out.command_age_s = NsToS(s.last_command_age_ns());
  }
  return out;
}

/// What the pilot sees with the predictive display: the blimp as predicted
/// (`p`), seen at `t_s`; the contact count as last reported.
BlimpObservation Observe(double t_s, const BlimpPredictedPose& p, const msg::BlimpState& last) {
  BlimpObservation o;
  o.t_s = t_s;
  o.position = p.position;
  o.yaw = p.yaw;
  o.pitch = p.pitch;
  o.velocity = p.velocity;
  o.airspeed = p.airspeed;
  o.contact = p.contact;
  o.contacts = last.contacts();
  o.impact_speed = last.impact_speed();
  return o;
}

/// The progress line; `controller`: the servo controller's errors since the
/// last line ("" when none, or no controller).
void LogBlimpProgress(double t, const BlimpLapTimer& lap, const VehicleLink& link,
                      const msg::BlimpState& s, const BlimpCommand& command,
                      const std::string& controller) {
  char line[300];
  std::snprintf(
      line, sizeof line,
      "%6.1f s  blimp  lap %5.1f s  gates %d/%d  obstacles %d  at %.0f %.0f m  height %.1f m  "
      "airspeed %.1f m/s  "
      "power %.2f  helix %+.2f  rudder %+.2f  elevator %+.2f  tail %+.2f  camera %+.2f %+.2f rad  "
      "rtt p50 %.2f ms  video %.1f fps",
      t, lap.lap_time_s(), lap.next_gate(), lap.gates_total(), lap.obstacles_touched(), s.x(),
      s.y(), s.z(), s.airspeed(), command.power, command.helix, command.rudder, command.elevator,
      command.tail_rotor, s.outputs()[5], s.outputs()[6], link.Rtt().Percentile(0.5) * 1e-3,
      link.video().Stats().fps);
  log::Info(line + controller);
}

/// What the blimp's view shows over the picture: the lap, the gates, the
/// last contact, the airspeed on the HUD's dial (full scale: the model's top
/// speed in still air) and a line of height and engine. Builds it without allocating.
class BlimpOverlay {
 public:
  BlimpOverlay(const SessionSetup& setup, std::string interface, int gates_total)
      : setup_(setup), interface_(std::move(interface)), gates_total_(gates_total) {}

  /// `help`: the interface's line of help for a person's first seconds (null: none);
  /// `notice`: what stops the person now (Interface::Notice; null: nothing), shown while it lasts.
  view::Overlay Make(double t, const BlimpLapTimer& lap, const msg::BlimpState& s,
                     const BlimpCommand& c, bool vehicle_up, const char* help, const char* notice) {
    view::Overlay o = LapOverlay(setup_, interface_.c_str(), t, lap.lap_time_s(), lap.next_gate(),
                                 gates_total_, lap.obstacles_touched());
    // A new contact onset, not the blimp resting on its pad at the start.
    if (s.pose_valid() && contacts_seen_ < 0) contacts_seen_ = s.contacts();
    if (contacts_seen_ >= 0 && s.contacts() > static_cast<uint32_t>(contacts_seen_)) {
      contacts_seen_ = s.contacts();
      touched_ = true;
      std::snprintf(last_contact_, sizeof last_contact_, "%.1f m/s at %.1f s", s.impact_speed(), t);
    }
    if (!s.contact()) touched_ = false;
    std::snprintf(o.last_contact, sizeof o.last_contact, "%s", last_contact_);
    o.contact_now = touched_;
    o.hud = true;
    o.speed_mps = s.airspeed();
    o.speed_max_mps = setup_.vehicle.airship.StillAirTopSpeed();
    std::snprintf(o.status, sizeof o.status, "height %.1f m  power %.0f%%  helix %+.0f%%", s.z(),
                  100.0 * c.power, 100.0 * c.helix);
    if (!vehicle_up) {
      std::snprintf(o.message, sizeof o.message, "waiting for vehicle '%s'",
                    setup_.vehicle.name.c_str());
    } else if (s.failsafe()) {
      std::snprintf(o.message, sizeof o.message, "failsafe: every channel at neutral");
    } else if (notice != nullptr) {
      std::snprintf(o.message, sizeof o.message, "%s", notice);
    } else if (setup_.operator_kind == "person" && t < kHelpS && help != nullptr) {
      std::snprintf(o.message, sizeof o.message, "%s", help);
    }
    return o;
  }

 private:
  static constexpr double kHelpS = 15.0;
  const SessionSetup& setup_;
  std::string interface_;
  int gates_total_;
  int64_t contacts_seen_ = -1;  ///< contact onsets when the first pose came; -1: none yet
  bool touched_ = false;        ///< in a contact that began in flight (the border shows it)
  char last_contact_[40] = "";
};

class BlimpSession final : public FamilySession {
 public:
  BlimpSession(const SessionSetup& setup, HapticSide& haptic, interfaces::InputBox& input,
               RunRecord& rec)
      : setup_(setup),
        course_(*setup.course),
        lap_(course_),
        spec_(setup.interfaces.at(0)),
        overlay_feed_(setup, spec_.name, static_cast<int>(course_.gates.size())),
        predictor_(setup.vehicle.airship, course_, setup.vehicle.watchdog_timeout_s,
                   setup.predict_model) {
    hull_length_ = setup.vehicle.airship.length;
    rec.track = course_.name;
    rec.predict = setup.predict;
    rec.predict_model = PredictionModelName(setup.predict_model);
    rec.gates_total = static_cast<int>(course_.gates.size());
    // The gesture cockpit, or a person's keys or game controller.
    interfaces::InterfaceParts parts;
    parts.input = &input;
    interface_ = interfaces::MakeBlimpInterface(spec_, parts);
    rec.interface = interface_->name();
    if (setup.operator_kind == "auto") {
      if (spec_.manual()) {
        throw ConfigError("the automatic pilot flies the blimp gesture cockpit, not '" +
                          rec.interface + "'");
      }
      if (haptic.sim() == nullptr) {
        throw ConfigError(
            setup.device.file.string() +
            ": the automatic pilot moves the simulated arms (driver 'sim'); device '" +
            setup.device.name + "' is flown by a person: use --operator person");
      }
      pilot_ = std::make_unique<BlimpAutoPilot>(course_, PilotKnowing(setup.vehicle.airship));
      PlaceHands(*haptic.sim(), interface_->HandTargetsFor({}));
    }
  }

  void Start(HapticSide&) override {}
  void AbandonSetup(SessionResult&) override {}

  /// The pilot camera's picture on a screen that turns with the camera, the
  /// view turning with the head (mouse-look in the window).
  void ConfigureView(SessionView::Parts& parts, view::ViewOptions& options) const override {
    parts.hands = spec_.hands();
    options.screen = view::HeadTrackedScreen();
    if (setup_.predict) parts.map = std::make_shared<const view::TrackMap>(CourseMapOf(course_));
  }
  bool UsesGamepad() const override { return spec_.is_gamepad(); }

  void Drain(VehicleLink& link, VehicleHealth& health, HapticSide& haptic, RunTrace& trace,
             int64_t t0) override {
    t0_ns_ = t0;  // the shown poses' clock, for scoring after the run
    for (const auto& e : link.channel<link::BlimpMessages>().inbox().Drain()) {
      const msg::BlimpState& s = e.state;
      if (health.FromAnotherProcess(s))
        continue;  // a stranger under the name: the next check ends the run
      const double ts = NsToS(e.received_ns - t0);
      if (health.OnState(s, e.received_ns)) haptic.OnVehicleUp();
      controller_errors_.ObserveState(s);
      last_ = s;
      have_state_ = true;
      if (s.last_command_sent_ns() > 0) {
        predictor_.OnRoundTrip(
            NsToS(e.received_ns - s.last_command_sent_ns() - s.last_command_age_ns()));
      }
      if (!s.pose_valid()) continue;
      // A contact begun since (not the pad under it at the start): the
      // devices show it on the hands (a shake) at their next tick.
      if (contacts_marked_ < 0) contacts_marked_ = s.contacts();
      if (s.contacts() > contacts_marked_) {
        contacts_marked_ = s.contacts();
        haptic.hal().MarkContact();
      }
      predictor_.OnState(Sample(ts, s, t0));
      const BlimpObservation o = Observe(ts, s);
      // With prediction the pilot sees the blimp as it will be (Command),
      // and the wind in what the blimp reports (the model's is its own).
      if (pilot_ && !setup_.predict) pilot_->Observe(o);
      if (pilot_ && setup_.predict) pilot_->ObserveReported(o);
      lap_.Update(o);
      trace.Add(ts, s.x(), s.y(), s.z(), o.velocity.norm(), s.contact());
    }
  }

  std::optional<LoopEnd> Command(double t, int64_t now, const interfaces::InputState& person,
                                 bool vehicle_up, bool engaged, HapticSide& haptic,
                                 VehicleLink& link) override {
    // The pilot's hands and gaze; a person's head turns with mouse-look.
    head_ = {person.head_pan, person.head_tilt};
    // With prediction the pilot flies the blimp as it will be when the
    // command given now reaches it (the commands on their way are known),
    // as the robot's driver does.
    if (pilot_ && setup_.predict && predictor_.ready()) {
      pilot_->Observe(Observe(t, predictor_.PoseAt(t + predictor_.one_way_delay_s()), last_));
    }
    if (pilot_) {
      head_ = {};
      if (vehicle_up && !engaged && flown_) {
        // Let go after flying: the hands back to neutral, so that it engages again.
        HoldHands(*haptic.sim(), interface_->HandTargetsFor({}));
      }
      if (vehicle_up && engaged) {  // it flies once the interface engages
        flown_ = true;
        const BlimpCommand intent = pilot_->Decide(t);
        HoldHands(*haptic.sim(), interface_->HandTargetsFor(intent));
        head_ = {intent.camera_pan, intent.camera_tilt};
      }
    }
    command_ = interface_->Update(t, Reading(person), haptic.hal());
    if (const char* notice = notice_log_.Update(t, interface_->Notice())) log::Warn(notice);
    if (interface_->lost())
      return LoopEnd{Outcome::kAborted, "the game controller was disconnected"};
    if (next_command_ns_ == 0) next_command_ns_ = now;
    if (CommandDue(next_command_ns_, now, static_cast<int64_t>(1e9 / spec_.command_rate_hz()))) {
      // Disengaged: the neutral command, the camera still where the pilot looks.
      BlimpCommand sent{};
      if (vehicle_up && engaged) {
        sent = command_;
      } else if (vehicle_up) {
        sent.camera_pan = command_.camera_pan;
        sent.camera_tilt = command_.camera_tilt;
      }
      link.Send(sent);
      predictor_.OnCommand(t, sent);
    }
    return std::nullopt;
  }

  InterfaceRest Rest() const override {
    if (spec_.manual()) return {};
    return RestOf(spec_.hands(), interface_->HandTargetsFor(BlimpCommand{}), AtRest(command_));
  }

  // --- A fleet's interface handover (interface_handover.hpp). ---
  void RenderForces(double, haptics::Hal& hal) override {
    // Its command goes nowhere: the blimp is held at neutral meanwhile.
    if (!spec_.manual()) {
      interface_->Update(0.0, Reading({}), hal);
    } else {
      hal.SetField(haptics::Side::kLeft,
                   haptics::ForceField{});  // keys and controllers render none
      hal.SetField(haptics::Side::kRight, haptics::ForceField{});
    }
  }
  void PauseForces(haptics::Hal&) override {}  // no physics world: its fields went with the fade
  void ResumeForces(haptics::Hal&, const interfaces::InputState& now) override {
    // Keys pressed while another vehicle was driven were that one's, and the
    // blimp was held at neutral: its levels start from rest again.
    interface_->Rebase(now);
    command_ = {};
  }

  std::optional<LoopEnd> LapEnd() const override {
    if (lap_.crashed()) {
      return LoopEnd{Outcome::kCrashed,
                     "the blimp crashed: a contact at " +
                         std::to_string(lap_.crash_speed()).substr(0, 4) + " m/s (more than " +
                         std::to_string(course_.crash_speed).substr(0, 4) + " m/s)"};
    }
    if (lap_.completed()) return LoopEnd{Outcome::kCompleted, "landed: lap completed"};
    return std::nullopt;
  }
  const std::filesystem::path& world_file() const override { return course_.file; }
  double lap_cap_s() const override { return course_.lap_cap_s; }
  std::optional<double> lap_start_s() const override {
    return lap_.started() ? std::optional<double>(lap_.start_t_s()) : std::nullopt;
  }

  view::Overlay Overlay(double t, bool vehicle_up, bool) override {
    return overlay_feed_.Make(t, lap_, last_, command_, vehicle_up, interface_->Help(false),
                              interface_->Notice());
  }
  /// With prediction on: on the course map, the blimp as last reported, as
  /// it is now by its model, and its path over the next second with the
  /// command being given, each with its height (predictive_display.hpp).
  /// Remade at most every kPredictionPeriod_s: each is a run of the airship
  /// model through the delay and the second ahead.
  std::optional<view::Prediction> Prediction(double t) override {
    if (!setup_.predict) return std::nullopt;
    if (!predictor_.ready() || !have_state_) return view::Prediction{};  // nothing to draw yet
    if (t < next_prediction_s_) return prediction_;
    next_prediction_s_ = t + kPredictionPeriod_s;
    predictor_.PathAhead(t, 1.0, command_, path_ahead_, 0.05);
    BlimpPredictedPose reported;
    reported.position = Eigen::Vector3d(last_.x(), last_.y(), last_.z());
    reported.yaw = last_.yaw();
    MakeBlimpPrediction(reported, path_ahead_, hull_length_, predictor_.one_way_delay_s(),
                        prediction_);
    return prediction_;
  }

  /// The screen hangs where the camera points as the vehicle applied it.
  std::optional<view::Gaze> Gaze() const override {
    return view::Gaze{true, head_.pan, head_.tilt, last_.outputs()[5], last_.outputs()[6]};
  }
  void LogProgress(double t, const VehicleLink& link, double) const override {
    LogBlimpProgress(t, lap_, link, last_, command_, controller_errors_.TakeProgressText());
  }
  const char* MadeSafe() const override { return "forces zeroed, blimp to neutral"; }

  void Finish(SessionResult& result, bool) override {
    RunRecord& rec = result.record;
    result.controller_errors = controller_errors_.seen();
    rec.controller_errors = controller_errors_.seen();
    rec.lap_time_s = lap_.lap_time_s();
    rec.gates_passed = lap_.gates_passed();
    rec.gates_missed = lap_.gates_missed();
    rec.obstacles_touched = lap_.obstacles_touched();
    for (const BlimpGateSplit& split : lap_.splits())
      rec.splits.push_back({split.gate, split.passed, split.split_s});
    RecordPredictionErrors(predictor_.errors_m(), rec);
    result.shown = predictor_.shown();
    result.started_ns = t0_ns_;
    result.shown_height = true;
    // The wind estimated, under the truth record's names.
    const Eigen::Vector2d wind = predictor_.wind();
    const double known_s = predictor_.wind_known() ? predictor_.wind_known_s() : std::nan("");
    rec.estimated = {{"wind_x", wind.x(), std::nan(""), known_s},
                     {"wind_y", wind.y(), std::nan(""), known_s}};
  }

 private:
  /// What the interface reads now: the person's input, the head, stamped now.
  interfaces::BlimpReading Reading(const interfaces::InputState& person) const {
    return {person, head_, MonotonicNs()};
  }

  const SessionSetup& setup_;
  const BlimpCourseConfig& course_;
  BlimpLapTimer lap_;
  const interfaces::InterfaceSpec& spec_;  ///< the interface flown (the catalogue's)
  BlimpOverlay overlay_feed_;
  NoticeLog notice_log_;
  std::unique_ptr<interfaces::BlimpInterface> interface_;
  std::unique_ptr<BlimpAutoPilot> pilot_;
  msg::BlimpState last_;
  /// Taken from by the progress line (LogProgress is const to the session loop).
  mutable ControllerErrorWatch controller_errors_;
  BlimpCommand command_;
  interfaces::HeadDirection head_;
  int64_t next_command_ns_ = 0;
  /// Runs with prediction on or off: its error goes into the record either way.
  BlimpPredictor predictor_;
  int64_t t0_ns_ = 0;  ///< the session's start (MonotonicNs), as Drain is given it
  static constexpr double kPredictionPeriod_s = 0.05;
  bool have_state_ = false;
  int64_t contacts_marked_ =
      -1;               ///< the state's contact count last marked in the HAL (-1: none yet)
  bool flown_ = false;  ///< the pilot has flown (engaged) since the start
  double hull_length_ = 0.0;
  double next_prediction_s_ = 0.0;
  std::vector<BlimpPredictedPose> path_ahead_;
  view::Prediction prediction_;
};

}  // namespace

std::unique_ptr<FamilySession> MakeBlimpSession(const SessionSetup& setup, HapticSide& haptic,
                                                interfaces::InputBox& input, RunRecord& rec) {
  return std::make_unique<BlimpSession>(setup, haptic, input, rec);
}

}  // namespace haptel::mediator
