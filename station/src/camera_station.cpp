#include "haptel/station/camera_station.hpp"

#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <exception>
#include <thread>

#include "haptel/core/clock.hpp"

namespace haptel::station {

const char* ToString(Role role) {
  switch (role) {
    case Role::kWaiting:
      return "waiting";
    case Role::kNoSuchCamera:
      return "no such camera";
    case Role::kDriven:
      return "driver's camera";
    case Role::kFixed:
      return "fixed camera";
    case Role::kFree:
      return "free";
    case Role::kHolding:
      return "holding";
    case Role::kRefused:
      return "refused";
  }
  return "?";
}

namespace {

/// "03:12:45 UTC" of a CLOCK_REALTIME stamp.
std::string WallClockText(int64_t wall_ns) {
  const std::time_t t = static_cast<std::time_t>(wall_ns / 1'000'000'000);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%H:%M:%S UTC", &tm);
  return text;
}

}  // namespace

std::string HeldByText(const CameraNow& now) {
  std::string text = "held by " +
                     std::string(now.holder[0] != '\0' ? now.holder : "another station") +
                     " since " + WallClockText(now.held_since_wall_ns);
  if (now.holder_heard_wall_ns != 0)
    text += ", last heard " + WallClockText(now.holder_heard_wall_ns);
  return text;
}

std::string HolderLine(const CameraNow& now, const std::string& vehicle, const std::string& camera,
                       int domain) {
  const std::string what = "camera " + camera + " of " + vehicle;
  switch (now.role) {
    case Role::kWaiting:
      return "waiting for " + vehicle + "'s cameras on domain " + std::to_string(domain);
    case Role::kNoSuchCamera:
      return vehicle + " has no camera '" + camera + "' (its cameras: " + now.cameras + ")";
    case Role::kDriven:
      return what + " is the driver's: it turns with the driving commands, not a station's";
    case Role::kFixed:
      return what + " neither pans, tilts nor zooms";
    case Role::kFree:
      return what + " is free";
    case Role::kHolding:
      return what + " is yours";
    case Role::kRefused:
      return what + " is " + HeldByText(now);
  }
  return what;
}

CameraStation::CameraStation(const StationOptions& options) : options_(options) {
  aim_.Store(CameraAim{});
  participant_ =
      std::make_unique<link::Participant>(options_.link, "haptel-station-" + options_.camera);
  participant_->SetTap(options_.tap);
  status_reader_ = std::make_unique<link::CameraStatusReader>(
      *participant_, link::CameraStatusTopic(options_.vehicle),
      link::CameraMessages::kStatusProfile,
      [this](const msg::CameraStatus& status) { OnStatus(status); });
  video_ = std::make_unique<video::VideoReceiver>(
      *participant_, options_.vehicle, options_.session, options_.decode, options_.camera,
      [this](const msg::VideoFrame& frame, const link::SampleStamps& stamps) {
        OnFrame(frame, stamps);
      });
  writer_ = std::make_unique<link::CameraCommandWriter>(
      *participant_, link::CameraCommandTopic(options_.vehicle, options_.camera),
      link::CameraMessages::kCommandProfile);
  writer_id_ = writer_->id();
  command_.session(options_.session);
  command_.operator_name(options_.operator_name);
  sender_ = std::make_unique<PeriodicThread>(
      PeriodicThread::Options{.name = "station-command", .rate_hz = options_.command_rate_hz},
      [this](int64_t now_ns) { SendTick(now_ns); });
  sender_->Start();
}

CameraStation::~CameraStation() { Release(); }

void CameraStation::OnStatus(const msg::CameraStatus& status) {
  CameraNow now = now_.Load();
  ++now.statuses;
  now.cameras[0] = '\0';
  std::string names;
  const msg::CameraInfo* mine = nullptr;
  for (const msg::CameraInfo& c : status.cameras()) {
    names += std::string(names.empty() ? "" : ", ") + c.name().c_str();
    if (options_.camera == c.name().c_str()) mine = &c;
  }
  std::snprintf(now.cameras, sizeof now.cameras, "%s", names.c_str());
  std::snprintf(now.family, sizeof now.family, "%s", status.family().c_str());
  now.holder[0] = '\0';
  now.held_since_wall_ns = 0;
  now.holder_heard_wall_ns = 0;
  if (mine == nullptr) {
    now.role = Role::kNoSuchCamera;
    now_.Store(now);
    return;
  }
  const msg::CameraInfo& c = *mine;
  now.range = {c.pan_min(), c.pan_max(), c.tilt_min(), c.tilt_max(), c.zoom_max()};
  now.widest_fov_deg = c.fov_deg();
  now.applied = {c.pan(), c.tilt(), c.zoom()};
  now.commands_refused = c.commands_refused();
  const link::WriterId holder{c.holder_writer()};
  if (c.driven()) {
    now.role = Role::kDriven;
  } else if (!now.range.pans() && !now.range.tilts() && !now.range.zooms()) {
    now.role = Role::kFixed;
  } else if (holder.empty()) {
    now.role = Role::kFree;
  } else {
    now.role = holder == writer_id_ ? Role::kHolding : Role::kRefused;
    std::snprintf(now.holder, sizeof now.holder, "%s", c.holder().c_str());
    now.held_since_wall_ns = c.held_since_wall_ns();
    now.holder_heard_wall_ns = c.holder_heard_wall_ns();
    if (now.role == Role::kHolding) now.last_command_seq = c.last_command_seq();
  }
  now_.Store(now);
}

void CameraStation::OnFrame(const msg::VideoFrame& frame, const link::SampleStamps& stamps) {
  PictureAim picture = picture_.Load();
  picture.aim = {frame.pan(), frame.tilt(), frame.zoom()};
  picture.fov_deg = frame.fov_deg();
  ++picture.frames;
  picture_.Store(picture);
  // Every move up to the command this frame carries is now in a picture:
  // each is measured once, from its sending to this arrival.
  const uint64_t carried = frame.command_seq();
  if (carried == 0 || carried <= measured_up_to_) return;
  const uint64_t newest = last_move_seq_.load(std::memory_order_acquire);
  for (uint64_t seq = std::max(measured_up_to_ + 1, carried > kMoves ? carried - kMoves + 1 : 1);
       seq <= carried && seq <= newest; ++seq) {
    const Move& m = moves_[seq % kMoves];
    if (m.seq.load(std::memory_order_acquire) != seq) continue;
    const int64_t sent = m.sent_ns.load(std::memory_order_relaxed);
    latency_.Record(static_cast<double>(stamps.arrived_ns - sent) / 1e3);
  }
  measured_up_to_ = carried;
}

void CameraStation::SubscribeState(const char* family) {
  for (const VehicleFamily f : {VehicleFamily::kRobot, VehicleFamily::kBlimp}) {
    if (std::strcmp(family, ToString(f)) != 0) continue;
    try {
      state_reader_ = link::ForFamily(f, [this]<class Messages>() -> std::shared_ptr<void> {
        return std::make_shared<typename Messages::StateReader>(
            *participant_, link::TopicName(options_.vehicle, "state"), link::Profile::kState,
            [this](const typename Messages::StateMsg& state) {
              vehicle_.Store(Messages::Glance(state));
            });
      });
    } catch (const std::exception&) {
      // DDS refused the reader (a security identity without the state's
      // topic): the station steers its camera without the vehicle's line,
      // and does not ask again.
      state_reader_ = std::make_shared<int>(0);
    }
  }
}

void CameraStation::SendTick(int64_t now_ns) {
  if (released_.load()) return;
  const CameraNow now = now_.Load();
  // The vehicle's state, once its status said its family (not on the
  // status's DDS thread: a reader is made off DDS's own threads).
  if (!state_reader_ && now.family[0] != '\0') SubscribeState(now.family);
  const int64_t dt = last_tick_ns_ != 0 ? now_ns - last_tick_ns_ : 0;
  last_tick_ns_ = now_ns;
  if (now.role == Role::kHolding) held_ns_.fetch_add(dt, std::memory_order_relaxed);
  // Only within the camera's known ranges: a command outside them is
  // malformed for the vehicle.
  if (now.role != Role::kFree && now.role != Role::kHolding && now.role != Role::kRefused) return;
  Send(Clamped(aim_.Load(), now.range), false, now_ns);
}

void CameraStation::Send(const CameraAim& aim, bool release, int64_t now_ns) {
  command_.seq(++seq_);
  command_.sent_ns(now_ns);
  command_.release(release);
  link::CameraMessages::Encode(options_.camera, aim, command_);
  const bool moved = !sent_any_ || aim.pan != last_sent_.pan || aim.tilt != last_sent_.tilt ||
                     aim.zoom != last_sent_.zoom;
  if (moved && !release) {
    Move& m = moves_[seq_ % kMoves];
    m.sent_ns.store(now_ns, std::memory_order_relaxed);
    m.seq.store(seq_, std::memory_order_release);
    last_move_seq_.store(seq_, std::memory_order_release);
  }
  last_sent_ = aim;
  sent_any_ = true;
  if (writer_->Write(command_)) sent_.fetch_add(1, std::memory_order_relaxed);
}

void CameraStation::Release() {
  if (released_.exchange(true)) return;
  if (sender_) sender_->Stop();
  if (!sent_any_ || !writer_) return;
  // Best effort: a few, so one lost does not keep the camera held until
  // the vehicle sees this station silent.
  for (int i = 0; i < 3; ++i) {
    Send(last_sent_, true, MonotonicNs());
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

StationFigures CameraStation::Figures() const {
  StationFigures f;
  f.commands_sent = sent_.load();
  f.held_s = NsToS(held_ns_.load());
  const PictureAim picture = picture_.Load();
  f.picture_aim = picture.aim;
  f.picture_fov_deg = picture.fov_deg;
  f.picture_frames = picture.frames;
  f.command_to_picture_count = latency_.Count();
  f.command_to_picture_ms_p50 = latency_.Percentile(0.50) / 1e3;
  f.command_to_picture_ms_p95 = latency_.Percentile(0.95) / 1e3;
  return f;
}

}  // namespace haptel::station
