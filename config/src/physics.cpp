#include "haptel/config/physics.hpp"

#include <string>

#include "haptel/config/archives.hpp"
#include "haptel/config/check.hpp"
#include "haptel/config/yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

void PhysicsMaterial::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  if (spinning_friction > 0.0 && !(rolling_friction > 0.0)) {
    // Bullet adds the spinning-friction row only next to the rolling ones.
    check::Fail("spinning_friction",
                "spinning_friction 0 unless rolling_friction > 0 (Bullet ignores spinning "
                "friction without rolling friction)",
                {"rolling_friction"});
  }
}

void ProxyHandConfig::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  for (double length : phalanx_length) {
    if (length < 2.0 * phalanx_radius) {
      check::Fail("phalanx_length",
                  "every phalanx_length >= 2 * phalanx_radius (capsules joint to joint)",
                  {"phalanx_radius"});
    }
  }
}

void PhysicsConfig::ValidateOrThrow() const {
  check::Number("step_s", step_s, reference ? kMinReferenceStepS : kMinStepS, kMaxStepS);
  config_detail::CheckFields(*this);
}

PhysicsConfig LoadPhysics(const std::filesystem::path& file) {
  return config_detail::LoadFile<PhysicsConfig>(file);
}

}  // namespace haptel
