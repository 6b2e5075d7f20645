#include "haptel/haptics/hal.hpp"

#include <algorithm>
#include <vector>

#include "haptel/config/error.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/haptics/calibrated_units.hpp"

namespace haptel::haptics {

Hal::Hal(const DeviceCalibration& calibration) : calibration_(Validated(calibration)) {}

Vec3d Hal::ToMetres(Side side, const Vec3d& raw) const {
  return TrackerToMetres(calibration(side), raw);
}

void Hal::PublishWrist(Side side, const WristRaw& raw) {
  const int s = Index(side);
  wrist_[s].Store(raw);
  const uint64_t n = wrist_count_[s].load(std::memory_order_relaxed);
  history_[s][n % kTrackerHistory].Store({raw.t_ns, raw.position});
  wrist_count_[s].store(n + 1, std::memory_order_release);
}

void Hal::PublishGlove(Side side, const GloveRaw& raw) {
  const int s = Index(side);
  glove_[s].Store(raw);
  glove_count_[s].fetch_add(1, std::memory_order_release);
}

void Hal::PublishForces(Side side, const AppliedForces& forces) {
  forces_[Index(side)].Store(forces);
}

void Hal::PublishLost(Side side, bool lost) {
  lost_[Index(side)].store(lost, std::memory_order_release);
}

void Hal::SetSetpoint(Side side, ForceSetpoint setpoint, int64_t now_ns) {
  setpoint.stamp_ns = now_ns;
  setpoint.field = ForceField{};
  contacts_[Index(side)].Store(setpoint);
}

void Hal::SetField(Side side, const ForceField& field) { SetField(side, field, MonotonicNs()); }

void Hal::SetField(Side side, const ForceField& field, int64_t now_ns) {
  fields_[Index(side)].Store({now_ns, field});
}

void Hal::ZeroForces() {
  for (auto& f : fields_) f.Store(StampedField{});
}

void Hal::SetForceScale(double scale) {
  force_scale_.store(std::clamp(scale, 0.0, 1.0), std::memory_order_relaxed);
}

ForceSetpoint Hal::Setpoint(Side side) const {
  const StampedField f = fields_[Index(side)].Load();
  return Combine(contacts_[Index(side)].Load(), f.field, f.stamp_ns);
}

bool Hal::TrySetpoint(Side side, ForceSetpoint& out) const {
  ForceSetpoint contacts;
  StampedField f;
  if (!contacts_[Index(side)].TryLoad(contacts, kSetpointReadAttempts)) return false;
  if (!fields_[Index(side)].TryLoad(f, kSetpointReadAttempts)) return false;
  out = Combine(contacts, f.field, f.stamp_ns);
  return true;
}

void Hal::SetCue(Side side, const Cue& cue) { cues_[Index(side)].Store(cue); }

bool Hal::TryCue(Side side, Cue& out) const {
  return cues_[Index(side)].TryLoad(out, kSetpointReadAttempts);
}

ForceSetpoint Hal::Combine(ForceSetpoint sp, const ForceField& latest_field,
                           int64_t field_stamp_ns) const {
  sp.field = latest_field;
  sp.contacts = contacts_begun();
  if (sp.stamp_ns == 0 || (field_stamp_ns != 0 && field_stamp_ns < sp.stamp_ns))
    sp.stamp_ns = field_stamp_ns;
  const double k = force_scale_.load(std::memory_order_relaxed);
  if (k != 1.0) {
    // Every force is linear in these gains, so scaling them scales the force.
    ForceField& field = sp.field;
    field.stiffness *= k;
    field.stiffness_growth *= k;
    field.damping *= k;
    field.wall_stiffness *= k;
    field.wall_damping *= k;
    field.guidance_stiffness *= k;
    field.guidance_max_force *= k;
    sp.coupling_stiffness *= k;
    sp.coupling_damping *= k;
    for (double& w : sp.wrist_force) w *= k;
    for (double& finger : sp.finger_forces) finger *= k;
  }
  return sp;
}

size_t Hal::TrackerHistory(Side side, std::span<TrackerSample> out) const {
  const int s = Index(side);
  const uint64_t end = wrist_count_[s].load(std::memory_order_acquire);
  const uint64_t want =
      std::min<uint64_t>({out.size(), end, static_cast<uint64_t>(kTrackerHistory)});
  size_t n = 0;
  int64_t previous_t = 0;
  for (uint64_t i = end - want; i < end; ++i) {
    const TrackerSample sample = history_[s][i % kTrackerHistory].Load();
    // A slot the writer lapped while we read is newer than its neighbours: drop it.
    if (n > 0 && sample.t_ns <= previous_t) continue;
    out[n++] = sample;
    previous_t = sample.t_ns;
  }
  return n;
}

std::optional<Vec3d> Hal::TrackerVelocity(Side side) const {
  std::array<TrackerSample, 3> s{};
  if (TrackerHistory(side, s) < 3) return std::nullopt;
  // Second-order backward difference for unevenly spaced samples t0 < t1 < t2.
  const double h1 = static_cast<double>(s[2].t_ns - s[1].t_ns) * 1e-9;
  const double h0 = static_cast<double>(s[1].t_ns - s[0].t_ns) * 1e-9;
  if (h1 <= 0 || h0 <= 0) return std::nullopt;
  const Vec3d p0 = ToMetres(side, s[0].raw);
  const Vec3d p1 = ToMetres(side, s[1].raw);
  const Vec3d p2 = ToMetres(side, s[2].raw);
  Vec3d v{};
  for (int i = 0; i < 3; ++i) {
    v[i] = (h0 + 2 * h1) / (h1 * (h0 + h1)) * p2[i] - (h0 + h1) / (h0 * h1) * p1[i] +
           h1 / (h0 * (h0 + h1)) * p0[i];
  }
  return v;
}

std::optional<Vec3d> Hal::MeanAcceleration(Side side, double window_s) const {
  std::vector<TrackerSample> samples(kTrackerHistory);
  const size_t n = TrackerHistory(side, samples);
  if (n < 6) return std::nullopt;
  // The samples covering the window: the newest back to t_end − window.
  const int64_t t_end = samples[n - 1].t_ns;
  size_t first = n - 1;
  while (first > 0 && static_cast<double>(t_end - samples[first - 1].t_ns) * 1e-9 <= window_s)
    --first;
  if (n - first < 6) return std::nullopt;
  // Mean acceleration = (velocity at the end − velocity at the start) / span,
  // with each velocity a least-squares slope over three samples at each end.
  auto slope = [&](size_t a) {
    Vec3d v{};
    const double ta = static_cast<double>(samples[a].t_ns) * 1e-9;
    const double tc = static_cast<double>(samples[a + 2].t_ns) * 1e-9;
    const Vec3d pa = ToMetres(side, samples[a].raw);
    const Vec3d pc = ToMetres(side, samples[a + 2].raw);
    for (int i = 0; i < 3; ++i) v[i] = (pc[i] - pa[i]) / (tc - ta);
    return v;
  };
  const Vec3d v_start = slope(first);
  const Vec3d v_end = slope(n - 3);
  const double span = static_cast<double>(samples[n - 2].t_ns - samples[first + 1].t_ns) * 1e-9;
  if (span <= 0) return std::nullopt;
  Vec3d a{};
  for (int i = 0; i < 3; ++i) a[i] = (v_end[i] - v_start[i]) / span;
  return a;
}

HandSample Hal::LatestSample(Side side) const {
  const int s = Index(side);
  HandSample out;
  if (wrist_count_[s].load(std::memory_order_acquire) == 0 ||
      lost_[s].load(std::memory_order_acquire)) {
    return out;  // valid = false
  }
  const WristRaw raw = wrist_[s].Load();
  out.t_ns = raw.t_ns;
  out.valid = true;
  out.position = ToMetres(side, raw.position);
  out.orientation = raw.orientation;
  out.velocity = TrackerVelocity(side).value_or(Vec3d{});
  if (glove_count_[s].load(std::memory_order_acquire) > 0) {
    const GloveRaw glove = glove_[s].Load();
    const ArmCalibration& c = calibration(side);
    GloveToRadians(c, glove.sensors, out.finger_angles);
  }
  out.force = forces_[s].Load().wrist;
  return out;
}

}  // namespace haptel::haptics
