#include "haptel/mediator/controller_errors.hpp"

#include "haptel/core/maestro_errors.hpp"

namespace haptel::mediator {

std::string ControllerErrorWatch::TakeProgressText() {
  const uint16_t errors = since_line_;
  since_line_ = 0;
  if (errors == 0) return "";
  return "  controller errors: " + maestro_errors::ErrorsText(errors);
}

std::string ControllerErrorsLine(uint16_t errors) {
  return "servo controller errors: " + maestro_errors::ErrorsText(errors);
}

std::vector<std::string> ControllerErrorNames(uint16_t errors) {
  std::vector<std::string> names;
  for (int bit = 15; bit >= 0; --bit) {
    if ((errors & (1U << bit)) != 0) names.emplace_back(maestro_errors::ErrorBitName(bit));
  }
  return names;
}

}  // namespace haptel::mediator
