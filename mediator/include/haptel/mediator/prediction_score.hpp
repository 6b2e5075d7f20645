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
#include "haptel/mediator/session.hpp"
#include "haptel/record/truth_record.hpp"

namespace haptel::mediator {

void ScorePrediction(const record::TruthRecord& truth, SessionResult& result);

}  // namespace haptel::mediator
