#include "haptel/mediator/prediction_score.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "haptel/core/clock.hpp"
#include "haptel/mediator/blimp/blimp_lap_timer.hpp"
#include "haptel/mediator/lap_timer.hpp"

namespace haptel::mediator {

namespace {

/// The drawn value named `name` (DrawnReality::ForEach), NaN when none is.
double DrawnValue(const DrawnReality& drawn, const std::string& name) {
  double value = std::nan("");
  DrawnReality::ForEach(drawn, [&](const char* n, double v) {
    if (name == n) value = v;
  });
  return value;
}

/// Each feature of the track as built and in its file (built, file's): each
/// wall corner once (walls share corners), then each post's centre.
std::vector<std::pair<Vec2, Vec2>> AsBuiltFeatures(const DrawnReality& drawn, const Track& track) {
  std::vector<std::pair<Vec2, Vec2>> pairs;
  const auto add = [&](const Vec2& built, const Vec2& file) {
    for (const auto& [b, f] : pairs) {
      if (f == file) return;
    }
    pairs.emplace_back(built, file);
  };
  const std::vector<Segment2>& walls = TrueWalls(drawn, track);
  for (size_t i = 0; i < walls.size() && i < track.walls().size(); ++i) {
    add(walls[i].a, track.walls()[i].a);
    add(walls[i].b, track.walls()[i].b);
  }
  const std::vector<CircleObstacle>& posts = TruePosts(drawn, track);
  for (size_t i = 0; i < posts.size() && i < track.round_obstacles().size(); ++i)
    add(posts[i].center, track.round_obstacles()[i].center);
  return pairs;
}

/// The RMS distance (m) of the map's features from where they truly stand
/// in the map's frame, as learnt (`learnt` true) or as the file has them;
/// NaN when no feature of `map` is on the track.
double MapRms(const std::vector<std::pair<Vec2, Vec2>>& map,
              const std::vector<std::pair<Vec2, Vec2>>& built, const RigidFit2& fit, bool learnt) {
  double sum = 0.0;
  int n = 0;
  for (const auto& [file, position] : map) {
    for (const auto& [b, f] : built) {
      if (f != file) continue;
      sum += ((learnt ? position : file) - fit.Apply(b)).squaredNorm();
      ++n;
      break;
    }
  }
  return n > 0 ? std::sqrt(sum / n) : std::nan("");
}

/// The track's gates where their posts truly stand (TruePosts: each gate's
/// left and right post, in the track's order), in the truth's world: each
/// gate's line and direction turned with its posts about their midpoint.
/// The file's gates when the reality moved nothing.
std::vector<Gate> GatesAsBuilt(const DrawnReality& drawn, const Track& track) {
  std::vector<Gate> gates = track.gates();
  const std::vector<CircleObstacle>& posts = TruePosts(drawn, track);
  for (size_t i = 0; i < gates.size() && 2 * i + 1 < posts.size(); ++i) {
    Gate& g = gates[i];
    const Vec2 left = posts[2 * i].center, right = posts[2 * i + 1].center;
    if (left == g.left_post && right == g.right_post) continue;
    const Vec2 file_across = g.left_post - g.right_post, across = left - right;
    const double turn = std::atan2(file_across.x() * across.y() - file_across.y() * across.x(),
                                   file_across.dot(across));
    const RigidFit2 move{turn, Vec2::Zero()};
    const Vec2 centre = 0.5 * (left + right);
    const auto moved = [&](const Vec2& p) -> Vec2 { return centre + move.Apply(p - g.center); };
    g.line = {moved(g.line.a), moved(g.line.b)};
    g.tangent = move.Apply(g.tangent);
    g.center = centre;
    g.left_post = left;
    g.right_post = right;
  }
  return gates;
}

}  // namespace

Vec2 RigidFit2::Apply(const Vec2& p) const {
  const double c = std::cos(rotation_rad), s = std::sin(rotation_rad);
  return Vec2(c * p.x() - s * p.y(), s * p.x() + c * p.y()) + offset;
}

RigidFit2 FitAsBuiltToFile(const DrawnReality& drawn, const Track& track) {
  RigidFit2 fit;
  if (drawn.true_walls.empty() && drawn.true_posts.empty()) return fit;
  const std::vector<std::pair<Vec2, Vec2>> pairs = AsBuiltFeatures(drawn, track);
  if (pairs.size() < 2) return fit;
  // Umeyama's least squares in the plane: the centroids matched, the turn
  // from the centred points' cross terms.
  Vec2 built_mean = Vec2::Zero(), file_mean = Vec2::Zero();
  for (const auto& [b, f] : pairs) built_mean += b, file_mean += f;
  built_mean /= static_cast<double>(pairs.size());
  file_mean /= static_cast<double>(pairs.size());
  double dot = 0.0, cross = 0.0;
  for (const auto& [b, f] : pairs) {
    const Vec2 u = b - built_mean, v = f - file_mean;
    dot += u.dot(v);
    cross += u.x() * v.y() - u.y() * v.x();
  }
  fit.rotation_rad = std::atan2(cross, dot);
  fit.offset = file_mean - RigidFit2{fit.rotation_rad}.Apply(built_mean);
  fit.features = static_cast<int>(pairs.size());
  double sum = 0.0;
  for (const auto& [b, f] : pairs) sum += (fit.Apply(b) - f).squaredNorm();
  fit.residual_m_rms = std::sqrt(sum / static_cast<double>(pairs.size()));
  return fit;
}

void ScorePrediction(const record::TruthRecord& truth, const Track* track, SessionResult& result) {
  RunRecord& rec = result.record;
  if (!truth.empty()) {
    const RigidFit2 fit = track != nullptr ? FitAsBuiltToFile(truth.params(), *track) : RigidFit2{};
    rec.map_fit = {fit.rotation_rad * 180.0 / std::numbers::pi, fit.offset.x(), fit.offset.y(),
                   fit.features, fit.residual_m_rms};
    const double start_s = NsToS(result.started_ns);
    // Where the vehicle truly was: in the world, or in the map's frame.
    const auto truth_in = [&](bool map_frame) -> TruthAt {
      return [&truth, &fit, start_s, map_frame](double t_s, double& x, double& y, double& z) {
        if (!truth.Covers(start_s + t_s)) return false;
        const TruthRow row = truth.PoseAt(start_s + t_s);
        const Vec2 p = map_frame ? fit.Apply(Vec2(row.x, row.y)) : Vec2(row.x, row.y);
        x = p.x();
        y = p.y();
        z = row.z;
        return true;
      };
    };
    const TruthAt in_map = truth_in(true), in_world = truth_in(false);
    const ErrorPercentiles e = ScoreAgainstTruth(result.shown, in_map, result.shown_height);
    const ErrorPercentiles w = ScoreAgainstTruth(result.shown, in_world, result.shown_height);
    rec.prediction_error_m_p50 = e.p50;
    rec.prediction_error_m_p95 = e.p95;
    rec.prediction_error_world_m_p50 = w.p50;
    rec.prediction_error_world_m_p95 = w.p95;
    // The robot's pose at each state's moment, localised or not, and its odometry.
    if (!result.located.empty()) {
      const ErrorPercentiles l = ScoreAgainstTruth(result.located, in_map, false);
      const ErrorPercentiles lw = ScoreAgainstTruth(result.located, in_world, false);
      const ErrorPercentiles o = ScoreAgainstTruth(result.odometry, in_map, false);
      rec.localisation_error_m_p50 = l.p50;
      rec.localisation_error_m_p95 = l.p95;
      rec.localisation_error_world_m_p50 = lw.p50;
      rec.localisation_error_world_m_p95 = lw.p95;
      rec.odometry_error_m_p50 = o.p50;
      rec.odometry_error_m_p95 = o.p95;
    }
  }
  const DrawnReality& drawn = truth.params();
  // The battery's fade over the run (the speed never below half).
  double fade = 1.0;
  if (truth.rows().size() > 1) {
    const double minutes =
        NsToS(truth.rows().back().operator_ns - truth.rows().front().operator_ns) / 60.0;
    fade = std::max(0.5, 1.0 - drawn.battery_fade_per_min * minutes);
  }
  for (EstimatedParameter& p : rec.estimated) {
    p.truth = DrawnValue(drawn, p.name);
    if (p.name == "left_gain" || p.name == "right_gain") p.truth *= fade;
  }
  // The map: its features' distance from where they truly stand (the map's
  // frame), as learnt and as the file has them.
  if (!truth.empty() && track != nullptr && !result.learnt_map.empty()) {
    const RigidFit2 fit = FitAsBuiltToFile(drawn, *track);
    const std::vector<std::pair<Vec2, Vec2>> built = AsBuiltFeatures(drawn, *track);
    rec.map_estimated = {static_cast<int>(result.learnt_map.size()),
                         MapRms(result.learnt_map, built, fit, true),
                         MapRms(result.learnt_map, built, fit, false)};
  }
}

void JudgeLapOnTruth(const record::TruthRecord& truth, const Track& track, SessionResult& result) {
  record::TruthLap& lap = result.record.truth_lap;
  lap = {};
  if (truth.empty()) return;
  LapTimer timer(track, GatesAsBuilt(truth.params(), track));
  for (const TruthRow& row : truth.rows())
    timer.Update(NsToS(row.operator_ns - result.started_ns), Vec2(row.x, row.y));
  lap.judged = true;
  lap.completed = timer.completed();
  lap.lap_time_s = timer.completed() ? timer.lap_time_s() : std::nan("");
  const RunRecord& live = result.record;
  if (!timer.completed() && timer.started() && timer.next_gate() == timer.gates_total() &&
      live.completed && std::isfinite(live.approach_s)) {
    // The run ended as the odometry crossed the finish; the robot truly
    // short of it then: the rest of the way at its true speed.
    constexpr double kMaxProjectedM = 0.5;
    const double end_s = live.approach_s + live.lap_time_s;
    const TruthRow at = truth.PoseAt(NsToS(result.started_ns) + end_s);
    const Vec2 forward = track.TangentAt(0.0);
    const double rest = (track.PointAt(0.0) - Vec2(at.x, at.y)).dot(forward);
    const double speed = at.speed * std::cos(at.heading - std::atan2(forward.y(), forward.x()));
    if (rest >= 0.0 && rest <= kMaxProjectedM && speed > 0.02) {
      lap.completed = true;
      lap.projected = true;
      lap.lap_time_s = end_s + rest / speed - timer.start_t_s();
    }
  }
  lap.gates_passed = timer.gates_passed();
  lap.gates_missed = timer.gates_missed();
  lap.splits = timer.splits();
}

void JudgeLapOnTruth(const record::TruthRecord& truth, const BlimpCourseConfig& course,
                     SessionResult& result) {
  record::TruthLap& lap = result.record.truth_lap;
  lap = {};
  if (truth.empty()) return;
  BlimpLapTimer timer(course);
  const std::vector<TruthRow>& rows = truth.rows();
  const double start_z = rows.front().z;
  for (size_t i = 0; i < rows.size(); ++i) {
    const TruthRow& row = rows[i];
    BlimpObservation o;
    o.t_s = NsToS(row.operator_ns - result.started_ns);
    o.position = Eigen::Vector3d(row.x, row.y, row.z);
    o.yaw = row.heading;
    // The truth's horizontal ground speed along the heading (the course of
    // a crabbing hull differs, its speed not), its climb from the rows.
    double climb = 0.0;
    if (i > 0 && row.operator_ns > rows[i - 1].operator_ns)
      climb = (row.z - rows[i - 1].z) / NsToS(row.operator_ns - rows[i - 1].operator_ns);
    o.velocity = Eigen::Vector3d(row.speed * std::cos(row.heading),
                                 row.speed * std::sin(row.heading), climb);
    o.contact = row.z <= start_z + kBlimpRestingM;
    timer.Update(o);
  }
  lap.judged = true;
  lap.completed = timer.completed();
  lap.lap_time_s = timer.completed() ? timer.lap_time_s() : std::nan("");
  lap.gates_passed = timer.gates_passed();
  lap.gates_missed = timer.gates_missed();
  for (const BlimpGateSplit& split : timer.splits())
    lap.splits.push_back({split.gate, split.passed, split.split_s});
}

std::vector<std::string> TruthLapDisagreements(const RunRecord& record) {
  std::vector<std::string> lines;
  if (!record.truth_lap.judged) return lines;
  const std::vector<GateSplit>& truth = record.truth_lap.splits;
  const auto what = [](const GateSplit& s) {
    return s.split_s < 0.0 ? "never reached it" : s.passed ? "passed it" : "missed it";
  };
  for (size_t i = 0; i < record.splits.size() && i < truth.size(); ++i) {
    const GateSplit& live = record.splits[i];
    const GateSplit& real = truth[i];
    if (live.passed == real.passed && (live.split_s < 0.0) == (real.split_s < 0.0)) continue;
    lines.push_back("gate " + std::to_string(live.gate + 1) + ": the odometry " + what(live) +
                    ", the vehicle truly " + what(real));
  }
  return lines;
}

}  // namespace haptel::mediator
