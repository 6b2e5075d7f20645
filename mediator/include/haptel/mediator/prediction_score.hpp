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
#include <string>
#include <vector>

#include "haptel/config/track.hpp"
#include "haptel/mediator/session.hpp"
#include "haptel/record/truth_record.hpp"

namespace haptel::mediator {

void ScorePrediction(const record::TruthRecord& truth, SessionResult& result);

/// The lap judged again from the truth record's path (RunRecord::truth_lap):
/// the same LapTimer the live lap runs on the vehicle's odometry, fed where
/// the vehicle truly was (times in s since the session's start). Left
/// unjudged when the record has no rows. The run ends as the odometry
/// crosses the finish: a robot truly short of the line then (its odometry
/// ran ahead), all gates reached, has its finish projected from where it
/// truly was at that moment at its true speed along the track (at most
/// 0.5 m short; further, the truth's lap is not completed).
void JudgeLapOnTruth(const record::TruthRecord& truth, const Track& track, SessionResult& result);

/// The gates the live lap and the truth judged differently, each as "gate N:
/// the odometry passed it, the vehicle truly missed it" (or the reverse, or
/// reached by one only); empty when they agree or the lap was not judged.
std::vector<std::string> TruthLapDisagreements(const RunRecord& record);

}  // namespace haptel::mediator
