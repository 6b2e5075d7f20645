#pragma once
/// @file Hardware abstraction layer: the only place data crosses between the
/// servo thread and slower threads.
///
/// The servo thread publishes timestamped hand samples and reads force
/// fields; slower threads do the opposite. Every hand-off is a seqlock, so
/// the servo thread never waits for anyone.
#include <array>
#include <atomic>

#include "haptel/core/seqlock.hpp"
#include "haptel/haptics/types.hpp"

namespace haptel::haptics {

class Hal {
 public:
  /// Servo thread.
  void PublishSample(Side side, const HandSample& sample) { samples_[Index(side)].Store(sample); }
  ForceField Field(Side side) const { return fields_[Index(side)].Load(); }

  /// Slower threads.
  HandSample LatestSample(Side side) const { return samples_[Index(side)].Load(); }
  void SetField(Side side, const ForceField& field) { fields_[Index(side)].Store(field); }
  /// Disables every field: forces go to zero at the next servo tick.
  void ZeroForces() {
    for (auto& f : fields_) f.Store(ForceField{});
  }

 private:
  std::array<Seqlock<HandSample>, kSides> samples_;
  std::array<Seqlock<ForceField>, kSides> fields_;
};

}  // namespace haptel::haptics
