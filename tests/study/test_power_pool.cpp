// The pool `haptel study power` simulates: the study file's profiles, each
// order row getting each profile alike, every trait varied about ±10 % and
// kept in its valid range, a seed per participant, the same pool for the
// same seed.
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "haptel/config/paths.hpp"
#include "haptel/study/design.hpp"
#include "haptel/study/plan.hpp"
#include "haptel/study/power_pool.hpp"

using namespace haptel;
using namespace haptel::study;

namespace {

/// The file's profile a pool profile was varied from: "S07-hasty" -> "hasty".
std::string ModelOf(const std::string& pool_profile) {
  return pool_profile.substr(pool_profile.find('-') + 1);
}

}  // namespace

TEST_CASE(
    "power pool: each order row gets each of the file's profiles alike, in the study's design",
    "[power]") {
  const StudyConfig study = LoadStudy(ShippedFile("config/studies/grand-prix-synthetic.yaml"));
  REQUIRE(BlockSize(study) == 4);
  const StudyConfig pool = PowerPoolStudy(study, 32, 4, 1);
  REQUIRE(pool.participants.size() == 32);
  CHECK(pool.name == "grand-prix-synthetic-power");
  CHECK(IsPlainName(pool.name));
  CHECK(pool.conditions.size() == study.conditions.size());
  std::map<int, std::map<std::string, int>> per_row;
  for (size_t i = 0; i < pool.participants.size(); ++i) {
    per_row[static_cast<int>(i % 4)][ModelOf(pool.participants[i].profile)] += 1;
  }
  for (const auto& [row, profiles] : per_row) {
    INFO("row " << row);
    CHECK(profiles.size() == 4);
    for (const auto& [name, count] : profiles) CHECK(count == 2);
  }
  // Participant i runs Williams row i mod 4, as the study's plan has it.
  const std::vector<PlannedTrial> plan = PlanTrials(pool);
  REQUIRE(plan.size() == 32 * 4);
  const std::vector<std::vector<int>> rows = WilliamsRows(4);
  for (size_t i = 0; i < 32; ++i) {
    for (size_t position = 0; position < 4; ++position) {
      const PlannedTrial& t = plan[i * 4 + position];
      CHECK(t.participant == pool.participants[i].id);
      CHECK(t.condition == study.conditions[static_cast<size_t>(rows[i % 4][position])].name);
    }
  }
}

TEST_CASE("power pool: traits vary about 10 % around the profile's, within range, a seed each",
          "[power]") {
  const StudyConfig study = LoadStudy(ShippedFile("config/studies/grand-prix-synthetic.yaml"));
  const StudyConfig pool = PowerPoolStudy(study, 200, 4, 7);
  std::set<uint64_t> seeds;
  double sum = 0.0;
  double sum_squares = 0.0;
  int n = 0;
  for (const StudyParticipant& p : pool.participants) {
    const DriverProfile& varied = pool.profiles.at(p.profile);
    const DriverProfile& model = study.profiles.at(ModelOf(p.profile));
    REQUIRE_NOTHROW(varied.ValidateOrThrow());
    seeds.insert(varied.seed);
    for (const DriverProfileTrait& t : DriverProfileTraits()) {
      const double base = model.*t.member;
      const double value = varied.*t.member;
      if (base == 0.0) {
        CHECK(value == 0.0);
        continue;
      }
      if (value <= t.min || value >= t.max) continue;  // clamped
      const double log_ratio = std::log(value / base);
      sum += log_ratio;
      sum_squares += log_ratio * log_ratio;
      ++n;
    }
  }
  CHECK(seeds.size() == pool.participants.size());
  REQUIRE(n > 1000);
  const double mean = sum / n;
  const double sd = std::sqrt(sum_squares / n - mean * mean);
  INFO("mean log factor " << mean << ", sd " << sd << " over " << n);
  CHECK(std::abs(mean) < 0.01);
  CHECK(sd > 0.09);
  CHECK(sd < 0.11);
}

TEST_CASE("power pool: the same seed gives the same participants, whatever the pool's size",
          "[power]") {
  const StudyConfig study = LoadStudy(ShippedFile("config/studies/grand-prix-synthetic.yaml"));
  const StudyConfig small = PowerPoolStudy(study, 8, 4, 3);
  const StudyConfig large = PowerPoolStudy(study, 32, 4, 3);
  const StudyConfig other = PowerPoolStudy(study, 8, 4, 4);
  for (size_t i = 0; i < small.participants.size(); ++i) {
    const DriverProfile& a = small.profiles.at(small.participants[i].profile);
    const DriverProfile& b = large.profiles.at(large.participants[i].profile);
    const DriverProfile& c = other.profiles.at(other.participants[i].profile);
    CHECK(a.seed == b.seed);
    CHECK(a.steering_noise == b.steering_noise);
    CHECK(a.holding_cruise == b.holding_cruise);
    CHECK(a.seed != c.seed);
  }
}
