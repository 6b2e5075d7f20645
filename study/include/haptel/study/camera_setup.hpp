#pragma once
/// @file A study condition's camera set-up at the start of its trials
/// (StudyCondition::cameras, ::station): what the console's trial card says
/// of it, and whether the second person a `station:` condition needs is at
/// the station before the experimenter may start the trial.
///
/// A station (`haptel station --vehicle V --camera C`) writes the camera's
/// commands on haptel/<V>/camera/<C> from its start, while it waits for the
/// vehicle; the trial's vehicle is spawned only when the trial starts. So a
/// station is "there" when a command writer of that topic is matched, and
/// once a vehicle runs under the name its CameraStatus (haptel/<V>/cameras)
/// names who holds the camera.
#include <memory>
#include <string>

#include "haptel/config/link.hpp"
#include "haptel/config/study.hpp"

namespace haptel::study {

/// The trial card's line for `condition`'s set-up, e.g. "participant A,
/// two-cameras (position 2); cameras pilot + surveillance, a station holds
/// surveillance": `next` with the set-up appended (`next` alone without one).
std::string WithCameraSetup(const std::string& next, const StudyCondition& condition);

/// The refusal while no station is there: names the condition, the camera,
/// the vehicle and the command that starts one on the domain.
std::string StationMissingLine(const std::string& condition, const std::string& camera,
                               const std::string& vehicle, int domain);

/// Watches for a station holding `camera` of `vehicle` on `link`'s domain.
class StationWatch {
 public:
  StationWatch(const LinkConfig& link, const std::string& vehicle, const std::string& camera,
               const std::string& condition);
  ~StationWatch();
  StationWatch(const StationWatch&) = delete;
  StationWatch& operator=(const StationWatch&) = delete;
  /// "" while a station is there for the camera; else StationMissingLine.
  std::string Missing() const;
  /// Who holds it, as the vehicle last said ("" before a vehicle said).
  std::string holder() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace haptel::study
