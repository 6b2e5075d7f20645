#pragma once
/// @file What one vehicle kind reports beside its family's state, on a
/// topic of its own (the CAN robot's bus log on haptel/<vehicle>/can_log),
/// so that the family's state carries only what every kind of the family
/// has. A kind's factory hands one over with its adapter (KindParts); the
/// node opens it once on DDS and publishes it after each state, on the
/// control thread that steps the adapter.
#include <string>

#include "haptel/link/participant.hpp"

namespace haptel::vehicles {

class KindReport {
 public:
  virtual ~KindReport() = default;
  /// Creates the topic's writer for `vehicle` (its name).
  virtual void Open(link::Participant& participant, const std::string& vehicle) = 0;
  /// Publishes what changed since the last call (after the adapter's Update).
  virtual void Publish() = 0;
};

}  // namespace haptel::vehicles
