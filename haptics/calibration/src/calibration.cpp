#include "haptel/calibration/calibration.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace haptel::haptics {

namespace {

constexpr const char* kAxisNames[3] = {"x", "y", "z"};

/// Angles (rad) of the flexion joints in a fist: MCP, PIP, DIP.
constexpr double kFistMcp = 1.5;
constexpr double kFistPip = 1.6;
constexpr double kFistDip = 1.1;

std::array<GlovePosture, kGlovePostureCount> MakePostures() {
  std::array<GlovePosture, kGlovePostureCount> p{};
  p[0].name = "flat";
  p[0].how = "hand flat, fingers straight and together, thumb alongside, wrist straight";

  p[1].name = "fist";
  p[1].how = "a firm fist, thumb wrapped over the index and middle fingers, wrist straight";
  p[1].angles[0] = 0.9;  // thumb roll
  p[1].angles[1] = 0.8;  // thumb MCP
  p[1].angles[2] = 0.9;  // thumb IP
  p[1].angles[3] = 0.3;  // thumb abduction
  for (int f = 0; f < 4; ++f) {
    p[1].angles[4 + 3 * f] = kFistMcp;
    p[1].angles[5 + 3 * f] = kFistPip;
    p[1].angles[6 + 3 * f] = kFistDip;
  }
  p[1].angles[19] = 0.5;  // palm arch

  p[2].name = "spread";
  p[2].how =
      "a 'stop' sign: fingers straight and spread wide, thumb out, wrist bent back and toward the "
      "thumb";
  p[2].angles[3] = 1.0;    // thumb abduction
  p[2].angles[16] = 0.4;   // index-middle abduction
  p[2].angles[17] = 0.3;   // middle-ring abduction
  p[2].angles[18] = 0.4;   // ring-pinky abduction
  p[2].angles[20] = -0.8;  // wrist extended
  p[2].angles[21] = 0.3;   // radial deviation

  p[3].name = "bent";
  p[3].how = "hand flat, fingers together, wrist bent down and toward the little finger";
  p[3].angles[20] = 0.9;   // wrist flexed
  p[3].angles[21] = -0.4;  // ulnar deviation
  return p;
}

bool AllFinite(const Vec3d& v) {
  return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}

std::string Join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : ", ") + s;
  return out;
}

}  // namespace

const std::array<GlovePosture, kGlovePostureCount>& GlovePostures() {
  static const std::array<GlovePosture, kGlovePostureCount> postures = MakePostures();
  return postures;
}

int GlovePostureIndex(std::string_view name) {
  const auto& postures = GlovePostures();
  for (int i = 0; i < kGlovePostureCount; ++i) {
    if (postures[static_cast<size_t>(i)].name == name) return i;
  }
  return -1;
}

// ---------------------------------------------------------------- glove ----

void GloveFit::ApplyTo(ArmCalibration& arm) const {
  for (size_t j = 0; j < sensors.size(); ++j) {
    arm.glove_gain[j] = sensors[j].gain;
    arm.glove_offset[j] = sensors[j].offset;
  }
}

void GloveCalibrator::Store(int index, const std::array<double, kGloveJoints>& raw) {
  for (int j = 0; j < kGloveJoints; ++j) {
    if (!std::isfinite(raw[static_cast<size_t>(j)])) {
      throw CalibrationError("glove posture '" +
                             std::string(GlovePostures()[static_cast<size_t>(index)].name) +
                             "': sensor " + std::string(kGloveSensorNames[static_cast<size_t>(j)]) +
                             " read a non-finite value");
    }
  }
  raw_[static_cast<size_t>(index)] = raw;
}

namespace {
int RequirePosture(std::string_view posture) {
  const int index = GlovePostureIndex(posture);
  if (index < 0) {
    std::string names;
    for (const auto& p : GlovePostures())
      names += (names.empty() ? "" : ", ") + std::string(p.name);
    throw CalibrationError("unknown glove posture '" + std::string(posture) +
                           "' (expected one of: " + names + ")");
  }
  return index;
}
}  // namespace

void GloveCalibrator::Capture(std::string_view posture,
                              const std::array<double, kGloveJoints>& raw) {
  const int index = RequirePosture(posture);
  if (raw_[static_cast<size_t>(index)]) {
    throw CalibrationError("glove posture '" + std::string(posture) +
                           "' is already captured (redo it with Recapture)");
  }
  Store(index, raw);
}

void GloveCalibrator::Recapture(std::string_view posture,
                                const std::array<double, kGloveJoints>& raw) {
  const int index = RequirePosture(posture);
  if (!raw_[static_cast<size_t>(index)]) {
    throw CalibrationError("glove posture '" + std::string(posture) +
                           "' was never captured: nothing to redo");
  }
  Store(index, raw);
}

bool GloveCalibrator::Captured(std::string_view posture) const {
  const int index = GlovePostureIndex(posture);
  return index >= 0 && raw_[static_cast<size_t>(index)].has_value();
}

std::vector<std::string_view> GloveCalibrator::Undetermined() const {
  const auto& postures = GlovePostures();
  std::vector<std::string_view> out;
  for (size_t j = 0; j < kGloveJoints; ++j) {
    bool determined = false;
    for (size_t a = 0; a < raw_.size() && !determined; ++a) {
      for (size_t b = a + 1; b < raw_.size() && !determined; ++b) {
        determined =
            raw_[a] && raw_[b] &&
            std::abs(postures[b].angles[j] - postures[a].angles[j]) >= kMinPostureAngleSpan;
      }
    }
    if (!determined) out.push_back(kGloveSensorNames[j]);
  }
  return out;
}

bool GloveCalibrator::Ready() const { return Undetermined().empty(); }

GloveFit GloveCalibrator::Fit() const {
  const std::vector<std::string_view> undetermined = Undetermined();
  if (!undetermined.empty()) {
    std::vector<std::string> names(undetermined.begin(), undetermined.end());
    std::string missing;
    for (size_t i = 0; i < raw_.size(); ++i) {
      if (!raw_[i]) missing += (missing.empty() ? "" : ", ") + std::string(GlovePostures()[i].name);
    }
    throw CalibrationError("glove: sensors not determined by the captured postures: " +
                           Join(names) + " (capture: " + missing + ")");
  }
  const auto& postures = GlovePostures();
  GloveFit fit;
  std::vector<std::string> degenerate;
  for (size_t j = 0; j < kGloveJoints; ++j) {
    GloveSensorFit& s = fit.sensors[j];
    // The pair of captured postures (with clearly different known angles)
    // whose readings differ most; ties keep the first pair in table order,
    // so the result does not depend on the order of capture.
    for (size_t a = 0; a < raw_.size(); ++a) {
      for (size_t b = a + 1; b < raw_.size(); ++b) {
        if (!raw_[a] || !raw_[b]) continue;
        if (std::abs(postures[b].angles[j] - postures[a].angles[j]) < kMinPostureAngleSpan)
          continue;
        const double span = std::abs((*raw_[b])[j] - (*raw_[a])[j]);
        if (s.posture_a < 0 || span > s.raw_span) {
          s.posture_a = static_cast<int>(a);
          s.posture_b = static_cast<int>(b);
          s.raw_span = span;
        }
      }
    }
    if (s.raw_span < min_raw_span_) {
      std::ostringstream why;
      why << kGloveSensorNames[j] << " (" << s.raw_span << " counts between '"
          << postures[static_cast<size_t>(s.posture_a)].name << "' and '"
          << postures[static_cast<size_t>(s.posture_b)].name << "')";
      degenerate.push_back(why.str());
      continue;
    }
    const size_t a = static_cast<size_t>(s.posture_a);
    const size_t b = static_cast<size_t>(s.posture_b);
    const double ra = (*raw_[a])[j];
    const double rb = (*raw_[b])[j];
    const double ta = postures[a].angles[j];
    const double tb = postures[b].angles[j];
    s.gain = (tb - ta) / (rb - ra);
    s.offset = 0.5 * (ta + tb) - s.gain * 0.5 * (ra + rb);
    for (size_t k = 0; k < raw_.size(); ++k) {
      if (raw_[k])
        s.check_error = std::max(
            s.check_error, std::abs(s.gain * (*raw_[k])[j] + s.offset - postures[k].angles[j]));
    }
  }
  if (!degenerate.empty()) {
    std::ostringstream msg;
    msg << "glove: sensors barely changed between postures (need >= " << min_raw_span_
        << " counts; stuck, unplugged or the postures were not made): " << Join(degenerate);
    throw CalibrationError(msg.str());
  }
  return fit;
}

// -------------------------------------------------------------- tracker ----

void TrackerFit::ApplyTo(ArmCalibration& arm) const {
  arm.tracker_scale = scale;
  arm.tracker_offset = offset;
}

TrackerFit FitTracker(const std::vector<TrackerReference>& references, double default_scale) {
  if (references.empty()) throw CalibrationError("tracker: no reference pose");
  if (!std::isfinite(default_scale) || default_scale == 0.0) {
    throw CalibrationError("tracker: the default scale must be a finite non-zero number");
  }
  for (size_t k = 0; k < references.size(); ++k) {
    if (!AllFinite(references[k].raw) || !AllFinite(references[k].metres)) {
      throw CalibrationError("tracker: reference pose " + std::to_string(k + 1) + " is not finite");
    }
  }
  const double n = static_cast<double>(references.size());
  TrackerFit fit;
  for (size_t i = 0; i < 3; ++i) {
    double raw_mean = 0.0;
    double metres_mean = 0.0;
    double metres_min = references[0].metres[i];
    double metres_max = metres_min;
    double raw_min = references[0].raw[i];
    double raw_max = raw_min;
    for (const auto& r : references) {
      raw_mean += r.raw[i] / n;
      metres_mean += r.metres[i] / n;
      metres_min = std::min(metres_min, r.metres[i]);
      metres_max = std::max(metres_max, r.metres[i]);
      raw_min = std::min(raw_min, r.raw[i]);
      raw_max = std::max(raw_max, r.raw[i]);
    }
    int parameters = 1;
    if (metres_max - metres_min >= kMinTrackerScaleSpan) {
      if (raw_max == raw_min) {
        std::ostringstream msg;
        msg << "tracker axis " << kAxisNames[i]
            << ": the reading did not change between reference poses " << (metres_max - metres_min)
            << " m apart";
        throw CalibrationError(msg.str());
      }
      double sxy = 0.0;
      double sxx = 0.0;
      for (const auto& r : references) {
        sxy += (r.raw[i] - raw_mean) * (r.metres[i] - metres_mean);
        sxx += (r.raw[i] - raw_mean) * (r.raw[i] - raw_mean);
      }
      fit.scale[i] = sxy / sxx;
      fit.scale_fitted[i] = true;
      parameters = 2;
    } else {
      fit.scale[i] = default_scale;
    }
    fit.offset[i] = metres_mean - fit.scale[i] * raw_mean;
    if (fit.scale[i] == 0.0 || !std::isfinite(fit.scale[i]) || !std::isfinite(fit.offset[i])) {
      throw CalibrationError(std::string("tracker axis ") + kAxisNames[i] +
                             ": the fit is degenerate");
    }
    double ssr = 0.0;
    for (const auto& r : references) {
      const double e = fit.scale[i] * r.raw[i] + fit.offset[i] - r.metres[i];
      ssr += e * e;
    }
    const double dof = n - parameters;
    fit.residual_rms[i] = dof > 0 ? std::sqrt(ssr / dof) : 0.0;
  }
  return fit;
}

// ---------------------------------------------------------------- force ----

void ForceFit::ApplyTo(ArmCalibration& arm) const {
  arm.force_slope = slope;
  arm.force_residual = residual;
}

ForceFit FitForce(const std::vector<ForceSample>& samples) {
  for (size_t k = 0; k < samples.size(); ++k) {
    if (!AllFinite(samples[k].command) || !AllFinite(samples[k].newtons)) {
      throw CalibrationError("force: sample " + std::to_string(k + 1) + " is not finite");
    }
  }
  ForceFit fit;
  double ssr_total = 0.0;
  for (size_t i = 0; i < 3; ++i) {
    double scc = 0.0;
    double scf = 0.0;
    int excited = 0;
    for (const auto& s : samples) {
      scc += s.command[i] * s.command[i];
      scf += s.command[i] * s.newtons[i];
      if (s.command[i] != 0.0) ++excited;
    }
    if (excited < 2) {
      throw CalibrationError(std::string("force axis ") + kAxisNames[i] +
                             ": needs at least two commands with a non-zero " + kAxisNames[i] +
                             " component, got " + std::to_string(excited));
    }
    fit.slope[i] = scf / scc;
    if (!std::isfinite(fit.slope[i]) || fit.slope[i] == 0.0) {
      throw CalibrationError(std::string("force axis ") + kAxisNames[i] +
                             ": the gauge read no force (is the motor powered?)");
    }
    double ssr = 0.0;
    for (const auto& s : samples) {
      const double e = s.newtons[i] - fit.slope[i] * s.command[i];
      ssr += e * e;
    }
    ssr_total += ssr;
    fit.residual_axis[i] = std::sqrt(ssr / static_cast<double>(samples.size() - 1));
  }
  fit.residual = std::sqrt(ssr_total / static_cast<double>(3 * samples.size() - 3));
  return fit;
}

}  // namespace haptel::haptics
