#pragma once
/// @file The run's prediction scored against the simulated vehicle's truth
/// record (record/truth_record.hpp), after the run — the only place the
/// operator side reads it, once the vehicle has stopped: each pose the
/// operator was shown as the vehicle now (SessionResult::shown) against
/// where the vehicle truly was at that moment (the record interpolated at
/// the operator's clock), into the record's prediction_error_m_p50/_p95;
/// a robot's pose at each state's moment (SessionResult::located: localised
/// on the track, or its odometry) and its odometry alone, likewise, into
/// localisation_error_m_* and odometry_error_m_*;
/// and each estimated parameter's truth (RunRecord::estimated), the drawn
/// value under the same name. A tread's gain is its truth at the run's end
/// (the battery's fade applied: the estimator follows it), the rest as drawn.
/// A localised robot's map (SessionResult::learnt_map) is scored into
/// RunRecord::map_estimated: the RMS distance of its wall corners and post
/// centres, as learnt and as the file has them, from where they truly
/// stand in the map's frame (the two equal with the nominal model, which
/// learns no map).
#include <string>
#include <vector>

#include "haptel/config/blimp_course.hpp"
#include "haptel/config/track.hpp"
#include "haptel/mediator/session.hpp"
#include "haptel/record/truth_record.hpp"

namespace haptel::mediator {

///
/// Every figure against the truth is in the map's frame: the truth moved by
/// the best rigid fit of the as-built track onto its file (FitAsBuiltToFile),
/// so that a lab's arbitrary global turn and offset of the whole layout (a
/// choice of frame: the operator's map and the ghost are in the file's) does
/// not count, while each post and wall's own error against the map does (the
/// operator meets it). The prediction's and the localisation's error against
/// the raw truth (the world frame the vehicle was placed in) are kept beside
/// them (*_world_m_*). `track`: the robot's (null for the blimp: no map, the
/// frames are one).
void ScorePrediction(const record::TruthRecord& truth, const Track* track, SessionResult& result);

/// A rigid motion of the plane: p ↦ R(rotation)·p + offset.
struct RigidFit2 {
  double rotation_rad = 0.0;
  Vec2 offset = Vec2::Zero();
  int features = 0;             ///< the points fitted (0: the identity, nothing displaced)
  double residual_m_rms = 0.0;  ///< what the fit leaves: the local map error
  Vec2 Apply(const Vec2& p) const;
};

/// The best rigid fit, in least squares, taking the track as `drawn` built it
/// (TrueWalls' corners, each once, and TruePosts' centres) onto `track`'s file:
/// Umeyama (1991) without scale, in closed form for the plane, every
/// feature weighted alike. The identity when the reality displaced nothing.
RigidFit2 FitAsBuiltToFile(const DrawnReality& drawn, const Track& track);

/// The lap judged again from the truth record's path (RunRecord::truth_lap):
/// the same LapTimer the live lap runs on the vehicle's odometry, fed where
/// the vehicle truly was (times in s since the session's start), at the
/// gates as built: where their posts truly stand (the reality's map error),
/// not where the file puts them. Left
/// unjudged when the record has no rows. The run ends as the odometry
/// crosses the finish: a robot truly short of the line then (its odometry
/// ran ahead), all gates reached, has its finish projected from where it
/// truly was at that moment at its true speed along the track (at most
/// 0.5 m short; further, the truth's lap is not completed).
void JudgeLapOnTruth(const record::TruthRecord& truth, const Track& track, SessionResult& result);

/// The blimp's lap judged again from the truth record's path: the same
/// BlimpLapTimer the live lap runs on the states, fed where the blimp truly
/// was — the take-off, each gate passed or missed and its split, and the
/// landing: on the circle's ground (OnLandingGround) resting on it (its
/// true height within kBlimpRestingM of its height at the start, on the
/// same flat ground) and slower than the circle's max_speed. The truth
/// records no contacts: crashes and obstacles touched stay the live lap's
/// (the simulated blimp reports its contacts as they happened).
void JudgeLapOnTruth(const record::TruthRecord& truth, const BlimpCourseConfig& course,
                     SessionResult& result);
/// m: a blimp this close to its starting height is resting on the ground.
inline constexpr double kBlimpRestingM = 0.05;

/// The gates the live lap and the truth judged differently, each as "gate N:
/// the odometry passed it, the vehicle truly missed it" (or the reverse, or
/// reached by one only); empty when they agree or the lap was not judged.
std::vector<std::string> TruthLapDisagreements(const RunRecord& record);

}  // namespace haptel::mediator
