#pragma once
/// @file The run's record (record/recorder.hpp) as the session fills it:
/// its types by their short names inside the mediator.
#include "haptel/record/recorder.hpp"

namespace haptel::mediator {

using record::ContactPoint;
using record::EstimatedParameter;
using record::GateSplit;
using record::PathPoint;
using record::Recorder;
using record::RunCounter;
using record::RunRecord;
using record::SwitchRecord;

}  // namespace haptel::mediator
