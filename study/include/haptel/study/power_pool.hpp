#pragma once
/// @file The pool of simulated participants `haptel study power` runs: the
/// study file's driver profiles, varied, as a study of its own.
#include <cstdint>
#include <random>

#include "haptel/config/study.hpp"

namespace haptel::study {

/// How much a pool participant's traits vary around their profile's: the
/// standard deviation of the log of each trait's factor (0.1: about ±10 %).
inline constexpr double kPoolTraitLogSpread = 0.1;

/// `profile` with every numeric trait (DriverProfileTraits) multiplied by
/// exp(N(0, kPoolTraitLogSpread²)), one draw each, and clamped to the range
/// the study file accepts for it (a trait at 0 stays 0), and a new seed in
/// the file's range 1..2^30. The normal draws are Box–Muller on the engine's
/// 53-bit uniforms, the same on every platform.
DriverProfile VariedProfile(const DriverProfile& profile, std::mt19937_64& random);

/// The pool as a study of its own, named "<study>-power" (the study's name
/// cut to 34 characters): the study's conditions, design, track, cap,
/// practice and link, and `pool` simulated participants S01, S02, ... (S001
/// from 100 on). Participant i (0-based) runs order row i mod `rows` of the
/// design (PlanTrials) with a VariedProfile of the profile of the file's
/// participant (i / rows + i mod rows) mod (the file's participants), so
/// each row gets each profile alike; its variation is drawn from
/// std::mt19937_64(seed_seq{seed's low and high 32 bits, i}): the same
/// participant for the same seed and index whatever the pool's size.
/// The caller checks that the study has simulated participants.
StudyConfig PowerPoolStudy(const StudyConfig& study, int pool, int rows, std::uint64_t seed);

}  // namespace haptel::study
