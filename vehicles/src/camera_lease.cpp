#include "haptel/vehicles/camera_lease.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "haptel/core/clock.hpp"

namespace haptel::vehicles {

CameraLeases::CameraLeases(int cameras, double free_after_s)
    : cameras_(cameras), free_after_ns_(SToNs(free_after_s)) {
  if (cameras < 0 || cameras > kMaxCameras) {
    throw std::invalid_argument("camera leases: " + std::to_string(cameras) +
                                " cameras; expected 0 to " + std::to_string(kMaxCameras));
  }
  for (int i = 0; i < cameras; ++i)
    leases_[static_cast<size_t>(i)] = std::make_unique<Lease>(free_after_s);
}

CommandOwner::Verdict CameraLeases::Admit(int index, const CommandSender& from, int64_t now_ns) {
  Lease& lease = *leases_.at(static_cast<size_t>(index));
  const CommandOwner::Verdict verdict = lease.owner.Admit(from, now_ns);
  if (verdict != CommandOwner::Verdict::kRefused)
    lease.last_ns.store(from.release ? 0 : now_ns, std::memory_order_release);
  return verdict;
}

CommandOwnerInfo CameraLeases::Holder(int index, int64_t now_ns) const {
  const Lease& lease = *leases_.at(static_cast<size_t>(index));
  const int64_t last = lease.last_ns.load(std::memory_order_acquire);
  if (last == 0 || now_ns - last > free_after_ns_) return {};
  return lease.owner.owner();
}

uint64_t CameraLeases::Refused(int index) const {
  return leases_.at(static_cast<size_t>(index))->owner.refused();
}

bool CameraLeases::Bars(const link::WriterId& writer, int64_t now_ns) const {
  for (int i = 0; i < cameras_; ++i) {
    const CommandOwnerInfo holder = Holder(i, now_ns);
    if (!holder.writer.empty() && holder.writer.SameParticipant(writer)) return true;
  }
  return false;
}

}  // namespace haptel::vehicles
