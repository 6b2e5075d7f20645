#pragma once
/// @file The camera role (issue 38; thesis 8.2.1: a second person drives the
/// blimp's surveillance camera from the Surveillance Control Room): one
/// station at a time holds each steerable camera of a vehicle, as one
/// operator at a time drives it. A camera's lease is a CommandOwner of its
/// own (command_intake.hpp): bound to the station's CameraCommand writer
/// (its DDS GUID, not the session its commands name), taken by the first
/// writer whose command reaches a free camera, kept while its commands keep
/// coming, freed by its release (a station that ends) or its silence for
/// `free_after_s` (a station whose liveliness is lost). Other writers'
/// commands are refused and counted; the vehicle's CameraStatus names the
/// holder and since when, so a refused station can say who has the camera.
///
/// And a camera station never drives: as a DrivingBar, the leases bar the
/// driving commands of any writer whose participant holds one of the
/// vehicle's cameras (with DDS Security its identity may not even write
/// them; without, this is what refuses them).
///
/// Threads: Admit from the DDS thread that delivers the camera's commands;
/// Holder, Bars and the counters from any thread. Allocation-free.
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>

#include "haptel/core/seqlock.hpp"
#include "haptel/vehicles/command_intake.hpp"

namespace haptel::vehicles {

class CameraLeases final : public DrivingBar {
 public:
  static constexpr int kMaxCameras = 8;

  /// Leases for cameras 0 .. `cameras` − 1 (at most kMaxCameras), each free
  /// after `free_after_s` of its holder's silence.
  explicit CameraLeases(int cameras, double free_after_s = CommandOwner::kFreeAfter_s);

  /// A command for camera `index` from `from`, received at `now_ns`
  /// (monotonic): the holder's (kOwner, kNewOwner: apply it) or another's
  /// (kRefused: drop it). A release frees the camera at once.
  CommandOwner::Verdict Admit(int index, const CommandSender& from, int64_t now_ns);
  /// Who holds camera `index` at `now_ns`: nobody (empty) once its holder
  /// released it or fell silent.
  CommandOwnerInfo Holder(int index, int64_t now_ns) const;
  /// Commands for camera `index` refused: another held it.
  uint64_t Refused(int index) const;
  /// DrivingBar: `writer`'s participant holds a camera at `now_ns`.
  bool Bars(const link::WriterId& writer, int64_t now_ns) const override;

  int cameras() const { return cameras_; }

 private:
  struct Lease {
    explicit Lease(double free_after_s) : owner(free_after_s) {}
    CommandOwner owner;
    std::atomic<int64_t> last_ns{0};  ///< the holder's last command (0: none)
  };
  int cameras_;
  int64_t free_after_ns_;
  std::array<std::unique_ptr<Lease>, kMaxCameras> leases_;
};

}  // namespace haptel::vehicles
