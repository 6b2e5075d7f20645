#include "haptel/gravity/gravity_sampler.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace haptel::haptics {
namespace {

/// metres = scale · raw + offset (private so this file does not depend on the
/// calibration helpers being written alongside).
Vec3d ToMetres(const ArmCalibration& c, const Vec3d& raw) {
  return {c.tracker_scale[0] * raw[0] + c.tracker_offset[0],
          c.tracker_scale[1] * raw[1] + c.tracker_offset[1],
          c.tracker_scale[2] * raw[2] + c.tracker_offset[2]};
}

/// command = newtons / slope.
Vec3d ToCommand(const ArmCalibration& c, const Vec3d& newtons) {
  return {newtons[0] / c.force_slope[0], newtons[1] / c.force_slope[1],
          newtons[2] / c.force_slope[2]};
}

int64_t SecondsToNs(double s) { return static_cast<int64_t>(std::llround(s * 1e9)); }

std::string Format(const char* format, auto... values) {
  char buffer[512];
  std::snprintf(buffer, sizeof buffer, format, values...);
  return buffer;
}

}  // namespace

// --------------------------------------------------------------- offline ---

GravitySampler::GravitySampler(Device& device, Side side, const ArmCalibration& calibration,
                               const GravitySamplerConfig& config, PlaceArm place)
    : device_(device),
      side_(side),
      calibration_(calibration),
      config_(config),
      place_(std::move(place)) {
  auto require = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("gravity sampler: ") + what);
  };
  const GravitySamplerConfig& c = config_;
  for (int a = 0; a < 3; ++a) {
    require(c.counts[a] >= 2 && c.counts[a] <= kGravityGridMaxCount,
            "counts must be in [2, 1000] on every axis");
    require(
        std::isfinite(c.box_min[a]) && std::isfinite(c.box_max[a]) && c.box_min[a] < c.box_max[a],
        "box_min < box_max (finite) on every axis");
    require(std::isfinite(calibration.tracker_scale[a]) && calibration.tracker_scale[a] != 0.0 &&
                std::isfinite(calibration.tracker_offset[a]) &&
                std::isfinite(calibration.force_slope[a]) && calibration.force_slope[a] != 0.0,
            "the calibration needs finite, non-zero tracker scales and force slopes");
  }
  require(c.position_tolerance_m > 0.0 && c.speed_tolerance_m_s > 0.0, "tolerances must be > 0");
  require(c.hold_s > 0.0 && c.hold_speed_window_s > 0.0 && c.hold_speed_window_s <= 10.0,
          "hold_s > 0 and hold_speed_window_s in (0, 10] s");
  require(c.decision_period_s > 0.0 && c.decision_period_s <= 10.0,
          "decision_period_s in (0, 10] s");
  require(c.vertex_timeout_s > c.hold_s, "vertex_timeout_s must exceed hold_s");
  require(c.small_step_n >= 0.0 && c.large_step_n >= c.small_step_n,
          "0 <= small_step_n <= large_step_n");
  require(c.max_force_n > 0.0 && std::isfinite(c.initial_force_n),
          "max_force_n > 0, finite initial_force_n");
  require(c.xy_stiffness_n_m >= 0.0 && c.xy_damping_n_s_m >= 0.0 && c.xy_force_limit_n >= 0.0,
          "horizontal gains and limit must be >= 0");
  require(static_cast<bool>(place_), "a PlaceArm function is needed");
  require(c.z_damping_n_s_m >= 0.0 && c.motion_still_m_s > 0.0,
          "z_damping_n_s_m >= 0, motion_still_m_s > 0");
  force_limit_ = std::min(c.max_force_n, device_.description().wrist_force_limit);
  require(force_limit_ > 0.0, "the device allows no wrist force");

  // Snake order: every vertex is a neighbour of the one before, so its
  // starting force (the previous one's) is close.
  const auto [nx, ny, nz] = c.counts;
  order_.reserve(static_cast<std::size_t>(nx) * ny * nz);
  for (int k = 0; k < nz; ++k) {
    for (int jj = 0; jj < ny; ++jj) {
      const int j = k % 2 == 0 ? jj : ny - 1 - jj;
      for (int ii = 0; ii < nx; ++ii) {
        const int i = (k * ny + jj) % 2 == 0 ? ii : nx - 1 - ii;
        order_.push_back({i, j, k});
      }
    }
  }
  // History long enough for the longer window at ticks down to 0.1 ms.
  const double window = std::max(c.hold_speed_window_s, c.decision_period_s);
  history_.resize(static_cast<std::size_t>(std::ceil(window / 1e-4)) + 2);
  report_.vertices.reserve(order_.size());
  report_.grid.min = c.box_min;
  report_.grid.max = c.box_max;
  report_.grid.counts = c.counts;
  report_.grid.device = c.device;
  report_.grid.force_z.assign(order_.size(), 0.0);
}

Vec3d GravitySampler::VelocityOver(int64_t window_ns) const {
  if (history_size_ < 2) return {};
  const std::size_t cap = history_.size();
  const Sample& newest = history_[(history_head_ + cap - 1) % cap];
  const Sample* oldest = &newest;
  for (std::size_t n = 1; n < history_size_; ++n) {
    oldest = &history_[(history_head_ + cap - 1 - n) % cap];
    if (oldest->t_ns <= newest.t_ns - window_ns) break;
  }
  const double dt = static_cast<double>(newest.t_ns - oldest->t_ns) * 1e-9;
  if (dt <= 0.0) return {};
  return {(newest.p[0] - oldest->p[0]) / dt, (newest.p[1] - oldest->p[1]) / dt,
          (newest.p[2] - oldest->p[2]) / dt};
}

void GravitySampler::WriteForce(const Vec3d& newtons) {
  device_.WriteWristForce(side_, ToCommand(calibration_, newtons));
}

void GravitySampler::StartVertex(int64_t now_ns) {
  const std::array<int, 3>& n = order_[static_cast<std::size_t>(current_)];
  for (int a = 0; a < 3; ++a) {
    target_[a] = config_.box_min[a] + (config_.box_max[a] - config_.box_min[a]) * n[a] /
                                          static_cast<double>(config_.counts[a] - 1);
  }
  force_z_ = current_ == 0 ? config_.initial_force_n : report_.vertices.back().force_n;
  force_z_ = std::clamp(force_z_, -force_limit_, force_limit_);
  place_(target_);
  history_head_ = 0;
  history_size_ = 0;
  vertex_start_ns_ = now_ns;
  next_decision_ns_ = now_ns + SecondsToNs(config_.decision_period_s);
  hold_start_ns_ = -1;
  decisions_ = 0;
  GravityVertexReport v;
  v.index = n;
  v.target = target_;
  v.start_force_n = force_z_;
  report_.vertices.push_back(v);
  state_ = State::kRefine;
}

void GravitySampler::Fail(const std::string& why) {
  report_.ok = false;
  report_.error = why;
  state_ = State::kFailed;
  WriteForce({});
}

bool GravitySampler::Tick(int64_t now_ns) {
  if (first_ns_ < 0) first_ns_ = now_ns;
  report_.end_ns = now_ns;
  report_.sim_time_s = static_cast<double>(now_ns - first_ns_) * 1e-9;
  if (finished()) {
    WriteForce({});
    return false;
  }
  if (state_ == State::kStartVertex) StartVertex(now_ns);
  GravityVertexReport& vertex = report_.vertices.back();
  const std::array<int, 3>& n = vertex.index;

  WristRaw raw;
  const DeviceStatus status = device_.ReadWrist(side_, now_ns, raw);
  if (status == DeviceStatus::kLost) {
    Fail(Format("gravity sampling: the device was lost at vertex %d of %d (%d,%d,%d)", current_ + 1,
                vertex_count(), n[0], n[1], n[2]));
    return false;
  }
  if (status == DeviceStatus::kOk) {
    history_[history_head_] = {now_ns, ToMetres(calibration_, raw.position)};
    history_head_ = (history_head_ + 1) % history_.size();
    history_size_ = std::min(history_size_ + 1, history_.size());
  }
  if (history_size_ == 0) {  // nothing read yet at this vertex
    WriteForce({0.0, 0.0, force_z_});
    return true;
  }
  const Vec3d p = history_[(history_head_ + history_.size() - 1) % history_.size()].p;
  const Vec3d v_motion = VelocityOver(SecondsToNs(config_.decision_period_s));
  const double v_hold = VelocityOver(SecondsToNs(config_.hold_speed_window_s))[2];
  const double z_error = p[2] - target_[2];

  // The decision table, once per decision period.
  if (now_ns >= next_decision_ns_) {
    const ForceStep step = Decide(ClassifyPosition(z_error, config_.position_tolerance_m),
                                  ClassifyMotion(v_motion[2], config_.motion_still_m_s));
    force_z_ = std::clamp(force_z_ + StepNewtons(step, config_.small_step_n, config_.large_step_n),
                          -force_limit_, force_limit_);
    ++decisions_;
    next_decision_ns_ += SecondsToNs(config_.decision_period_s);
    if (next_decision_ns_ <= now_ns)
      next_decision_ns_ = now_ns + SecondsToNs(config_.decision_period_s);
  }

  // Horizontal hold on target.
  Vec3d force{0.0, 0.0, force_z_ - config_.z_damping_n_s_m * v_motion[2]};
  for (int a = 0; a < 2; ++a) {
    force[a] = std::clamp(
        config_.xy_stiffness_n_m * (target_[a] - p[a]) - config_.xy_damping_n_s_m * v_motion[a],
        -config_.xy_force_limit_n, config_.xy_force_limit_n);
  }

  // Convergence: on target and still, continuously for hold_s.
  const bool holding = std::abs(z_error) <= config_.position_tolerance_m &&
                       std::abs(v_hold) < config_.speed_tolerance_m_s;
  if (!holding) {
    hold_start_ns_ = -1;
  } else if (hold_start_ns_ < 0) {
    hold_start_ns_ = now_ns;
  }
  vertex.decisions = decisions_;
  vertex.z_error_m = z_error;
  vertex.speed_m_s = v_hold;
  vertex.sim_time_s = static_cast<double>(now_ns - vertex_start_ns_) * 1e-9;
  if (hold_start_ns_ >= 0 && now_ns - hold_start_ns_ >= SecondsToNs(config_.hold_s)) {
    vertex.converged = true;
    vertex.force_n = force_z_;
    report_.grid.force_z[GravityVertexIndex(config_.counts, n[0], n[1], n[2])] = force_z_;
    ++current_;
    if (current_ == vertex_count()) {
      report_.ok = true;
      state_ = State::kDone;
      WriteForce({});
      return false;
    }
    state_ = State::kStartVertex;  // the next tick places the arm at the next vertex
  } else if (now_ns - vertex_start_ns_ > SecondsToNs(config_.vertex_timeout_s)) {
    Fail(
        Format("gravity sampling: vertex %d of %d (%d,%d,%d) at (%.3f, %.3f, %.3f) m did not hold "
               "still within "
               "%.1f s: z error %+.2f mm (tolerance %.2f), speed %+.2f mm/s (tolerance %.2f), "
               "force %.3f N "
               "(started from %.3f N)",
               current_ + 1, vertex_count(), n[0], n[1], n[2], target_[0], target_[1], target_[2],
               config_.vertex_timeout_s, z_error * 1e3, config_.position_tolerance_m * 1e3,
               v_hold * 1e3, config_.speed_tolerance_m_s * 1e3, force_z_, vertex.start_force_n));
    return false;
  }
  WriteForce(force);
  return true;
}

}  // namespace haptel::haptics
