#include "haptel/mediator/engagement.hpp"

#include <algorithm>
#include <cmath>

#include "haptel/haptics/calibrated_units.hpp"

namespace haptel::mediator {

namespace {

using haptics::Side;

constexpr int kBins = static_cast<int>(HandMotionRule::kWindow_s / HandMotionRule::kBin_s + 0.5);
/// A window covered to this share is judged (a sample or two late is not "too early").
constexpr double kCoveredShare = 0.9;

}  // namespace

HandMotion MeasureHandMotion(std::span<const haptics::TrackerSample> samples,
                             const ArmCalibration& arm) {
  HandMotion out;
  if (samples.size() < 2) return out;
  const int64_t end_ns = samples.back().t_ns;
  const auto window_ns = static_cast<int64_t>(HandMotionRule::kWindow_s * 1e9);
  const auto bin_ns = static_cast<int64_t>(HandMotionRule::kBin_s * 1e9);
  const int64_t start_ns = end_ns - window_ns;
  // The positions averaged over each bin of the window (m); an empty bin
  // (a late tick) keeps the one before.
  std::array<haptics::Vec3d, kBins> mean{};
  std::array<int, kBins> count{};
  int64_t first_ns = end_ns;
  for (const haptics::TrackerSample& s : samples) {
    if (s.t_ns <= start_ns) continue;
    first_ns = std::min(first_ns, s.t_ns);
    const int b = std::clamp(static_cast<int>((s.t_ns - start_ns - 1) / bin_ns), 0, kBins - 1);
    const haptics::Vec3d p = haptics::TrackerToMetres(arm, s.raw);
    for (int i = 0; i < 3; ++i) mean[b][i] += p[i];
    ++count[b];
  }
  out.span_s = static_cast<double>(end_ns - first_ns) * 1e-9;
  if (out.span_s < kCoveredShare * (HandMotionRule::kWindow_s - HandMotionRule::kBin_s)) return out;
  int filled = -1;
  for (int b = 0; b < kBins; ++b) {
    if (count[b] > 0) {
      for (int i = 0; i < 3; ++i) mean[b][i] /= count[b];
      filled = b;
    } else if (filled >= 0) {
      mean[b] = mean[filled];
    }
  }
  // Bins before the first sample take its place (no motion there).
  const int first = static_cast<int>(
      std::find_if(count.begin(), count.end(), [](int c) { return c > 0; }) - count.begin());
  for (int b = 0; b < first; ++b) mean[b] = mean[first];

  // The velocity between bins, high-passed: less its centred mean.
  constexpr int kVelocities = kBins - 1;
  constexpr int kHalf = HandMotionRule::kHighPassBins / 2;
  constexpr int kPassed = kVelocities - 2 * kHalf;
  std::array<std::array<double, kVelocities>, 3> v{};
  for (int k = 0; k < kVelocities; ++k) {
    for (int i = 0; i < 3; ++i) v[i][k] = (mean[k + 1][i] - mean[k][i]) / HandMotionRule::kBin_s;
  }
  std::array<std::array<double, kPassed>, 3> passed{};
  std::array<double, 3> sum_squares{};
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < kPassed; ++k) {
      double local = 0.0;
      for (int j = 0; j < HandMotionRule::kHighPassBins; ++j) local += v[i][k + j];
      passed[i][k] = v[i][k + kHalf] - local / HandMotionRule::kHighPassBins;
      sum_squares[i] += passed[i][k] * passed[i][k];
    }
  }
  const int axis = static_cast<int>(std::max_element(sum_squares.begin(), sum_squares.end()) -
                                    sum_squares.begin());
  out.rms_mps = std::sqrt(sum_squares[axis] / kPassed);
  // Reversals past a band of ±half the floor, so that noise about zero does not count.
  const double band = 0.5 * HandMotionRule::kMinRms_mps;
  int sign = 0;
  int reversals = 0;
  for (double x : passed[axis]) {
    const int now = x > band ? 1 : (x < -band ? -1 : 0);
    if (now == 0) continue;
    if (sign != 0 && now != sign) ++reversals;
    sign = now;
  }
  out.reversals_hz = reversals / (kPassed * HandMotionRule::kBin_s);
  out.held = out.rms_mps >= HandMotionRule::kMinRms_mps &&
             out.reversals_hz >= HandMotionRule::kMinReversals_hz;
  return out;
}

bool AtRest(const TreadCommand& c) {
  return std::abs(c.left) <= kCommandAtRest && std::abs(c.right) <= kCommandAtRest;
}

bool AtRest(const BlimpCommand& c) {
  return std::abs(c.power) <= kCommandAtRest && std::abs(c.helix) <= kCommandAtRest &&
         std::abs(c.rudder) <= kCommandAtRest && std::abs(c.elevator) <= kCommandAtRest &&
         std::abs(c.tail_rotor) <= kCommandAtRest;
}

InterfaceRest RestOf(const std::array<bool, haptics::kSides>& hands,
                     const interfaces::HandTargets& targets, bool at_rest) {
  InterfaceRest rest;
  rest.hands = hands;
  rest.command_at_rest = at_rest;
  for (size_t s = 0; s < rest.neutral.size(); ++s) {
    if (hands[s] && targets[s]) rest.neutral[s] = targets[s]->position;
  }
  return rest;
}

const char* ToString(Disengaged why) {
  switch (why) {
    case Disengaged::kNone:
      return "engaged";
    case Disengaged::kReleased:
      return "the device says nobody holds it";
    case Disengaged::kNoHand:
      return "no hand on the device (it does not move as a held hand moves)";
    case Disengaged::kOutOfReach:
      return "the hand is out of reach of the neutral point";
    case Disengaged::kNotAtNeutral:
      return "held, waiting for the command to come back to zero";
  }
  return "?";
}

Engagement::Engagement(bool engaged)
    : why_(engaged ? Disengaged::kNone : Disengaged::kNoHand),
      history_(haptics::Hal::kTrackerHistory) {}

Disengaged Engagement::Held(const haptics::Hal& hal, Side side) {
  if (hal.lost(side)) return Disengaged::kNoHand;
  switch (hal.presence(side)) {
    case haptics::HandPresence::kHeld:
      return Disengaged::kNone;
    case haptics::HandPresence::kReleased:
      return Disengaged::kReleased;
    case haptics::HandPresence::kUnknown:
      break;
  }
  const size_t n = hal.TrackerHistory(side, history_);
  HandMotion& motion = motion_[static_cast<size_t>(haptics::Index(side))];
  motion = MeasureHandMotion(std::span(history_.data(), n), hal.calibration(side));
  return motion.held ? Disengaged::kNone : Disengaged::kNoHand;
}

bool Engagement::Update(const haptics::Hal& hal, const InterfaceRest& rest) {
  Disengaged why = Disengaged::kNone;
  for (int s = 0; s < haptics::kSides && why == Disengaged::kNone; ++s) {
    if (!rest.hands[static_cast<size_t>(s)]) continue;
    const auto side = static_cast<Side>(s);
    why = Held(hal, side);
    const std::optional<haptics::Vec3d>& neutral = rest.neutral[static_cast<size_t>(s)];
    if (why != Disengaged::kNone || !neutral) continue;
    const haptics::HandSample hand = hal.LatestSample(side);
    const double dx = hand.position[0] - (*neutral)[0];
    const double dy = hand.position[1] - (*neutral)[1];
    const double dz = hand.position[2] - (*neutral)[2];
    if (!hand.valid || dx * dx + dy * dy + dz * dz > kReach_m * kReach_m)
      why = Disengaged::kOutOfReach;
  }
  // Engaged again only from rest: a hand grabbed away from neutral waits.
  if (why == Disengaged::kNone && !engaged() && !rest.command_at_rest)
    why = Disengaged::kNotAtNeutral;
  why_ = why;
  return engaged();
}

const char* Engagement::Line() const {
  switch (why_) {
    case Disengaged::kNone:
      return "";
    case Disengaged::kReleased:
      return "Not engaged - hold the button in the window (or the deadman) to drive";
    case Disengaged::kNoHand:
      return "Not engaged - nobody holds the device: take hold of it to drive";
    case Disengaged::kOutOfReach:
      return "Not engaged - hand out of reach: bring it back to the neutral point";
    case Disengaged::kNotAtNeutral:
      return "Not engaged - bring the hand back to neutral (zero command) to drive";
  }
  return "";
}

}  // namespace haptel::mediator
