#pragma once
/// @file Evaluation of a ForceField: allocation-free, for the servo loop.
#include "haptel/haptics/types.hpp"

namespace haptel::haptics {

/// Force of `field` on a hand at `position` moving at `velocity`. Zero when
/// the field is disabled. Not clamped: the servo loop applies the device
/// limit (the guidance term alone is bounded by its own guidance_max_force).
Vec3d EvaluateForceField(const ForceField& field, const Vec3d& position, const Vec3d& velocity);

/// Scales `force` down to at most `limit` N in magnitude; non-finite forces
/// become zero. Returns true when it had to change the force.
bool LimitForce(Vec3d& force, double limit);

}  // namespace haptel::haptics
