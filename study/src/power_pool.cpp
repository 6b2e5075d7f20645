#include "haptel/study/power_pool.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace haptel::study {
namespace {

/// A standard normal draw by Box–Muller from the engine's 53-bit uniforms
/// (std::normal_distribution's algorithm is the library's choice; this is
/// the same on every platform).
double StandardNormal(std::mt19937_64& random) {
  const double u1 = (static_cast<double>(random() >> 11) + 1.0) * 0x1.0p-53;  // (0, 1]
  const double u2 = static_cast<double>(random() >> 11) * 0x1.0p-53;          // [0, 1)
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * 3.14159265358979323846 * u2);
}

}  // namespace

DriverProfile VariedProfile(const DriverProfile& profile, std::mt19937_64& random) {
  DriverProfile varied = profile;
  for (const DriverProfileTrait& t : DriverProfileTraits()) {
    const double value = profile.*t.member * std::exp(kPoolTraitLogSpread * StandardNormal(random));
    varied.*t.member = std::clamp(value, t.min, t.max);
  }
  varied.seed = 1 + random() % (1u << 30);  // the study file's range for a seed
  return varied;
}

StudyConfig PowerPoolStudy(const StudyConfig& study, int pool, int rows, std::uint64_t seed) {
  StudyConfig config = study;
  // A plain name of at most 40 characters, as the study file's.
  config.name = study.name.substr(0, 34) + "-power";
  config.description = "the simulated participants of `haptel study power` for study " + study.name;
  config.participants.clear();
  config.profiles.clear();
  config.sessions = false;  // thousands of simulated laps: their estimate, not their recordings
  const int width = pool >= 100 ? 3 : 2;
  for (int i = 0; i < pool; ++i) {
    const StudyParticipant& model = study.participants.at(
        static_cast<size_t>((i / rows + i % rows) % static_cast<int>(study.participants.size())));
    std::seed_seq seeds{static_cast<std::uint32_t>(seed & 0xffffffffu),
                        static_cast<std::uint32_t>(seed >> 32), static_cast<std::uint32_t>(i)};
    std::mt19937_64 random(seeds);
    char id[16];
    std::snprintf(id, sizeof id, "S%0*d", width, i + 1);
    const std::string profile = std::string(id) + "-" + model.profile;
    config.profiles[profile] = VariedProfile(study.profiles.at(model.profile), random);
    config.participants.push_back({id, profile});
  }
  return config;
}

}  // namespace haptel::study
