#include "haptel/mediator/blimp_predictor.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "haptel/models/airship.hpp"

namespace haptel::mediator {

namespace {

/// s: two states further apart than this (on the vehicle's clock) say
/// little of the rates now (states lost); the model's own rates are kept.
constexpr double kMaxRateGap_s = 0.25;

/// The wind estimator (blimp_predictor.hpp): two scalar updates a state,
/// λ = 0.9995 each: a memory of 1000 states, 20 s at 50 Hz; the velocity
/// residual's noise taken as at least 5 mm/s; a prior (the file's mean
/// wind) worth a standard deviation of 3 m/s, a fresh wind for a blimp; the
/// nudge (m/s) the sensitivity is taken over; the covariance's bound; the
/// largest wind believed (m/s). (A prior worth nothing let the first state
/// off the ground, whose run says almost nothing of the wind — the
/// sensitivity 2e-4 — turn a few mm/s of a loaded machine's timing into a
/// 25-m/s wind, from which the estimate crept back over twenty seconds,
/// taken as known on the way.)
constexpr double kWindForgetting = 0.9995;
constexpr double kWindNoiseFloor_mps = 0.005;
constexpr double kWindPriorSd_mps = 3.0;
constexpr double kWindInitialCovariance =
    (kWindPriorSd_mps / kWindNoiseFloor_mps) * (kWindPriorSd_mps / kWindNoiseFloor_mps);
constexpr double kWindNudge_mps = 0.5;
constexpr double kWindMax_mps = 15.0;

/// The model the predictor runs: the vehicle file's, without the gusts
/// (their phases are the vehicle's own: foreseeing them would be a guess).
AirshipConfig WithoutGusts(AirshipConfig airship) {
  airship.wind.gust_rms = 0.0;
  return airship;
}

/// The actuators settled at the channels `applied`.
void SettleActuators(const AirshipConfig& k, const BlimpCommand& applied, models::AirshipState& s) {
  s.thrust = std::clamp(applied.power, 0.0, 1.0) * k.max_thrust;
  s.helix_rad = std::clamp(applied.helix, -1.0, 1.0) * k.max_helix_deg * M_PI / 180.0;
  s.tail = std::clamp(applied.tail_rotor, -1.0, 1.0) * k.tail_thrust;
}

}  // namespace

BlimpPredictor::BlimpPredictor(const AirshipConfig& airship, const BlimpCourseConfig& course,
                               double watchdog_s, PredictionModel model)
    : airship_(WithoutGusts(airship)),
      model_kind_(model),
      watchdog_s_(watchdog_s),
      replay_wind_(airship.wind.mean[0], airship.wind.mean[1], airship.wind.mean[2]),
      wind_(replay_wind_.head<2>(), kWindInitialCovariance, kWindForgetting, kWindNoiseFloor_mps),
      model_(airship_, course) {}

Eigen::Vector2d BlimpPredictor::wind() const {
  if (!wind_known()) return {airship_.wind.mean[0], airship_.wind.mean[1]};
  const Eigen::Vector2d w = wind_.estimate();
  return w.norm() > kWindMax_mps ? Eigen::Vector2d(w * (kWindMax_mps / w.norm())) : w;
}

const BlimpPredictor::Arrived* BlimpPredictor::ArrivedBy(const BlimpStateSample& state,
                                                         double sample_s, const Base& before,
                                                         Arrived& out) {
  if (state.command_sent_s < 0.0 || state.command_age_s < 0.0) return nullptr;
  out.sent_s = state.command_sent_s;
  out.arrival_s = std::clamp(sample_s - state.command_age_s, before.sample_s, sample_s);
  return &out;
}

void BlimpPredictor::UpdateWind(const Base& before, double sample_s,
                                const BlimpStateSample& state) {
  const double run_s = sample_s - before.sample_s;
  if (!(run_s > 1e-3) || run_s > kMaxRateGap_s) return;
  // The commands as they truly arrived: a delay's jitter (a loaded machine's
  // late threads) would otherwise be read as wind.
  Arrived arrived_store;
  const Arrived* arrived = ArrivedBy(state, sample_s, before, arrived_store);
  const Eigen::Vector2d w = wind_.estimate();
  const Eigen::Vector3d kept = replay_wind_;
  Eigen::Vector2d v[3];
  bool contact = false;
  const Eigen::Vector2d nudge[3] = {{0.0, 0.0}, {kWindNudge_mps, 0.0}, {0.0, kWindNudge_mps}};
  for (int i = 0; i < 3; ++i) {
    replay_wind_ = {w.x() + nudge[i].x(), w.y() + nudge[i].y(), kept.z()};
    Run(
        before, nullptr, {sample_s},
        [&](double, const models::SimBlimp& m) {
          v[i] = m.ground_velocity().head<2>();
          contact = contact || m.in_contact();
        },
        arrived);
  }
  replay_wind_ = kept;
  if (contact) return;  // friction holds it, not the air
  Eigen::Matrix2d sensitivity;
  sensitivity.col(0) = (v[1] - v[0]) / kWindNudge_mps;
  sensitivity.col(1) = (v[2] - v[0]) / kWindNudge_mps;
  const Eigen::Vector2d residual = state.velocity.head<2>() - v[0];
  for (int row = 0; row < 2; ++row) {
    const Eigen::Vector2d phi = sensitivity.row(row).transpose();
    wind_.Update(phi, residual(row) + phi.dot(w));
  }
  wind_.BoundCovariance(2.0 * kWindInitialCovariance);
  ++wind_updates_;
  if (!wind_known() && wind_.StandardDeviation(0) < kWindKnown_mps &&
      wind_.StandardDeviation(1) < kWindKnown_mps) {
    wind_known_s_ = state.received_s;
  }
}

void BlimpPredictor::OnCommand(double t_s, const BlimpCommand& command) {
  commands_.push_back({t_s, Clamped(command)});
}

double BlimpPredictor::OnState(const BlimpStateSample& state) {
  const double d = delay_.one_way_s();
  const double sample_s = SampleTime(state, d);
  // What the operator was shown of this moment at this moment: the
  // prediction from the newest state it had then.
  double error_m = -1.0;
  const Base* known = nullptr;
  for (const Base& b : bases_) {
    if (b.received_s <= sample_s && b.sample_s <= sample_s) known = &b;
  }
  if (known != nullptr) {
    Run(*known, nullptr, {sample_s}, [&](double, const models::SimBlimp& m) {
      error_m = (m.position() - state.position).norm();
    });
    errors_m_.push_back(error_m);
  }

  Base base;
  base.received_s = state.received_s;
  base.sample_s = sample_s;
  base.stamp_ns = state.stamp_ns;
  base.applied = Clamped(state.applied);
  base.applied_sent_s = state.command_sent_s;
  base.applied_since_s = state.command_age_s >= 0.0 ? sample_s - state.command_age_s : sample_s;
  models::AirshipState& s = base.state;
  s.position = state.position;
  s.attitude = models::AttitudeFromYawPitchRoll(state.yaw, state.pitch, state.roll);
  s.velocity = s.attitude.conjugate() * state.velocity;
  if (bases_.empty()) {
    SettleActuators(airship_, base.applied, s);
  } else {
    // What the state does not carry, from the model run on from the state
    // before: the actuators (driven by the commands alone) and, unless the
    // two states' turn gives them, the rates.
    const Base& before = bases_.back();
    UpdateWind(before, sample_s, state);
    if (model_kind_ == PredictionModel::kLearn && wind_known()) {
      const Eigen::Vector2d w = wind();
      replay_wind_ = {w.x(), w.y(), airship_.wind.mean[2]};
    }
    Eigen::Quaterniond model_attitude = before.state.attitude;
    Arrived arrived_store;
    Run(
        before, nullptr, {sample_s},
        [&](double, const models::SimBlimp& m) {
          const models::AirshipState& run = m.airship().state();
          s.thrust = run.thrust;
          s.helix_rad = run.helix_rad;
          s.tail = run.tail;
          s.rates = run.rates;
          model_attitude = run.attitude;
        },
        ArrivedBy(state, sample_s, before, arrived_store));
    const double gap_s = 1e-9 * static_cast<double>(state.stamp_ns - before.stamp_ns);
    const double run_s = sample_s - before.sample_s;
    if (gap_s > 0.0 && gap_s <= kMaxRateGap_s) {
      // The two states' turn is the mean rate between them, half a state
      // period behind; the model's rates now, corrected by how far its own
      // mean rate over the same stretch missed the measured one, are not.
      const Eigen::AngleAxisd measured(before.state.attitude.conjugate() * s.attitude);
      const Eigen::Vector3d measured_rates = measured.angle() / gap_s * measured.axis();
      if (run_s > 1e-6) {
        const Eigen::AngleAxisd modelled(before.state.attitude.conjugate() * model_attitude);
        s.rates += measured_rates - modelled.angle() / run_s * modelled.axis();
      } else {
        s.rates = measured_rates;
      }
    }
  }
  bases_.push_back(base);
  // A state is needed while no later one had arrived by the newest's sample.
  while (bases_.size() > 1 && bases_[1].received_s <= sample_s) bases_.pop_front();
  // Commands that took effect before the oldest state kept are in its
  // applied channels; a second's margin for a late state.
  while (!commands_.empty() && commands_.front().sent_s + d < bases_.front().sample_s - 1.0)
    commands_.pop_front();
  const BlimpPredictedPose now = PoseAt(state.received_s);
  shown_.push_back({now.t_s, now.position.x(), now.position.y(), now.position.z()});
  return error_m;
}

double BlimpPredictor::SampleTime(const BlimpStateSample& state, double d) {
  return dating_.SampleTime(state.received_s, 1e-9 * static_cast<double>(state.stamp_ns), d);
}

void BlimpPredictor::Run(const Base& base, const Command* extra, const std::vector<double>& at,
                         const std::function<void(double, const models::SimBlimp&)>& emit,
                         const Arrived* arrived) const {
  const double d = delay_.one_way_s();
  model_.airship().set_mean_wind(replay_wind_);
  model_.Place(base.state, base.applied);
  double t = base.sample_s;
  BlimpCommand command = base.applied;
  // Every channel goes to neutral `watchdog_s_` after the last command
  // reached the blimp; the command being given (`extra`) is taken as given
  // on and on.
  double last_arrival = base.applied_since_s;
  bool held = false;
  const double step_s = airship_.step_s;
  auto advance = [&](double to) {
    while (t < to - 1e-12) {
      const double neutral_s =
          held ? std::numeric_limits<double>::infinity() : last_arrival + watchdog_s_;
      double end = std::min(to, t + step_s);
      const bool neutral = t >= neutral_s;
      if (!neutral && end > neutral_s) end = neutral_s;
      model_.Step(end - t, neutral ? BlimpCommand{} : command);
      t = end;
    }
  };
  size_t next_time = 0;
  auto emit_until = [&](double limit) {
    while (next_time < at.size() && at[next_time] <= limit) {
      advance(std::max(at[next_time], base.sample_s));
      emit(at[next_time], model_);
      ++next_time;
    }
  };
  // `echoed`: the command `arrived` names (arrived then); those before it
  // arrived by then.
  auto apply = [&](const Command& c, bool is_extra, bool echoed) {
    // In the state's applied channels already: the one it echoes and those
    // before (without an echo: those that had arrived by its sample).
    if (base.applied_sent_s >= 0.0 ? c.sent_s <= base.applied_sent_s
                                   : c.sent_s + d <= base.sample_s)
      return;
    // Not there yet when the state was sampled, whatever the delay says.
    double arrival = std::max(c.sent_s + d, base.sample_s);
    if (arrived != nullptr) {
      if (c.sent_s > arrived->sent_s) return;  // not arrived by the run's end
      arrival = echoed ? arrived->arrival_s : std::min(arrival, arrived->arrival_s);
    }
    if (next_time == at.size()) return;  // every pose wanted is out
    emit_until(arrival);
    advance(arrival);
    command = c.command;
    last_arrival = arrival;
    held = is_extra;
  };
  for (size_t i = 0; i < commands_.size(); ++i) {
    // The echoed command: the last one sent by the echo's send time (a
    // command is noted when its loop began, before it went out).
    const bool echoed = arrived != nullptr && commands_[i].sent_s <= arrived->sent_s &&
                        (i + 1 == commands_.size() || commands_[i + 1].sent_s > arrived->sent_s);
    apply(commands_[i], false, echoed);
  }
  if (extra != nullptr) apply(*extra, true, false);
  emit_until(std::numeric_limits<double>::infinity());
}

BlimpPredictedPose BlimpPredictor::PoseOf(double t_s, const models::SimBlimp& model) {
  BlimpPredictedPose p;
  p.t_s = t_s;
  p.position = model.position();
  p.yaw = model.yaw();
  p.pitch = model.pitch();
  p.velocity = model.ground_velocity();
  p.airspeed = model.airspeed();
  p.contact = model.in_contact();
  return p;
}

BlimpPredictedPose BlimpPredictor::PoseAt(double t_s) const {
  BlimpPredictedPose pose;
  pose.t_s = t_s;
  if (bases_.empty()) return pose;
  Run(bases_.back(), nullptr, {t_s},
      [&](double t, const models::SimBlimp& m) { pose = PoseOf(t, m); });
  return pose;
}

void BlimpPredictor::PathAhead(double now_s, double horizon_s, const BlimpCommand& given,
                               std::vector<BlimpPredictedPose>& path, double spacing_s) const {
  path.clear();
  if (bases_.empty() || !(spacing_s > 0.0)) return;
  std::vector<double> at;
  for (double t = now_s; t <= now_s + horizon_s + 1e-9; t += spacing_s) at.push_back(t);
  const Command held{now_s, Clamped(given)};
  Run(bases_.back(), &held, at,
      [&](double t, const models::SimBlimp& m) { path.push_back(PoseOf(t, m)); });
}

}  // namespace haptel::mediator
