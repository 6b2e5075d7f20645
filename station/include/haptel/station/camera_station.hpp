#pragma once
/// @file A camera station's link (thesis 8.2.1: the Surveillance Control
/// Room): one camera of one vehicle steered from another place than the
/// pilot's. It reads the vehicle's cameras (CameraStatus), that camera's
/// video (its own stream, decoded off the DDS thread) and sends only that
/// camera's commands (CameraCommand, on the camera's own topic, at a fixed
/// rate so the vehicle sees the station alive) — never a driving command:
/// it has no writer for one (and with DDS Security its identity,
/// camera-CAMERA, may not have one).
///
/// One station holds a camera at a time (the vehicle's lease, like the
/// driving owner: bound to the station's command writer, freed by its
/// release or its silence). The vehicle's status names the holder, so a
/// station knows whether its commands are obeyed (Role::kHolding) or
/// refused for another's (Role::kRefused: HolderLine says who and since
/// when).
///
/// Threads: DDS's (status, video), the command thread, and the caller's
/// (Aim, Now, the figures): they meet in seqlocks and atomics.
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "haptel/config/link.hpp"
#include "haptel/core/camera_aim.hpp"
#include "haptel/core/histogram.hpp"
#include "haptel/core/periodic_thread.hpp"
#include "haptel/core/seqlock.hpp"
#include "haptel/link/families.hpp"
#include "haptel/link/participant.hpp"
#include "haptel/video/video_receiver.hpp"

namespace haptel::station {

struct StationOptions {
  LinkConfig link;  ///< its security identity is the caller's (link::CameraIdentity)
  std::string vehicle;
  std::string camera;
  uint64_t session = 0;       ///< a label in every command (NewSessionId)
  std::string operator_name;  ///< in every command ("haptel station, eve@lab2 pid 77")
  double command_rate_hz = 20.0;
  /// Decode the pictures (a screen or a recording shows them); false: only counted.
  bool decode = true;
  /// Taps every sample sent and received (a session file's recorder; null: none).
  link::SampleTap* tap = nullptr;
};

/// Whose the camera is, as the vehicle's last status says.
enum class Role {
  kWaiting,       ///< no status from the vehicle yet
  kNoSuchCamera,  ///< the vehicle has no camera of that name
  kDriven,        ///< it is the driver's camera: it turns with the driving command only
  kFixed,         ///< it neither pans, tilts nor zooms
  kFree,          ///< nobody holds it: the next command takes it
  kHolding,       ///< this station holds it: its commands are obeyed
  kRefused,       ///< another station holds it: this one's commands are refused
};
const char* ToString(Role role);

/// The camera as the vehicle's status last said it. Flat (a seqlock's).
struct CameraNow {
  Role role = Role::kWaiting;
  CameraRange range;
  double widest_fov_deg = 60.0;
  CameraAim applied;               ///< where it points now
  uint64_t last_command_seq = 0;   ///< the last of this station's commands applied
  uint64_t commands_refused = 0;   ///< the vehicle's count, every station's
  char holder[64] = "";            ///< the holder's name (kHolding, kRefused)
  int64_t held_since_wall_ns = 0;  ///< since when (CLOCK_REALTIME)
  /// When the vehicle last heard the holder (CLOCK_REALTIME; 0: unknown).
  /// A holder silent for the vehicle's lease (2 s) is named no more.
  int64_t holder_heard_wall_ns = 0;
  char family[16] = "";    ///< the vehicle's family, "robot" or "blimp" ("": not said)
  char cameras[128] = "";  ///< the vehicle's cameras, "pilot, surveillance"
  uint64_t statuses = 0;
};

/// "held by NAME since 03:12:45 UTC, last heard 03:12:50 UTC": who holds
/// the camera and when the vehicle last heard it (Role::kRefused).
std::string HeldByText(const CameraNow& now);
/// One line for the person: who holds the camera, since when and when it
/// was last heard ("camera surveillance of blimp1 is held by haptel
/// station, eve@lab2 pid 77 since 03:12:45 UTC, last heard 03:12:50 UTC"); what the camera is when
/// it cannot be steered; or what is awaited.
std::string HolderLine(const CameraNow& now, const std::string& vehicle, const std::string& camera,
                       int domain);

/// What the station measured (StationFigures at the end).
struct StationFigures {
  uint64_t commands_sent = 0;
  double held_s = 0.0;  ///< time the vehicle's status named this station the holder
  /// From a command that moved the aim being sent to the first picture
  /// that carries it (the frame's command_seq) arriving: p50, p95 (ms),
  /// and how many were measured.
  double command_to_picture_ms_p50 = 0.0;
  double command_to_picture_ms_p95 = 0.0;
  uint64_t command_to_picture_count = 0;
  /// The latest picture's aim as its frame says it (the picture shows it).
  CameraAim picture_aim;
  double picture_fov_deg = 0.0;
  uint64_t picture_frames = 0;
};

class CameraStation {
 public:
  /// Joins the link (throws std::runtime_error when DDS refuses, ConfigError
  /// for a bad security folder), subscribes and starts the command thread;
  /// nothing is sent before the vehicle's status says the camera's ranges.
  explicit CameraStation(const StationOptions& options);
  /// Release(), then leaves the link.
  ~CameraStation();
  CameraStation(const CameraStation&) = delete;
  CameraStation& operator=(const CameraStation&) = delete;

  /// Where the camera is to point from the next command on (any thread).
  void Aim(const CameraAim& aim) { aim_.Store(aim); }
  /// The camera as the vehicle said it last (any thread).
  CameraNow Now() const { return now_.Load(); }
  /// The vehicle as its last state says (any thread; seq 0: none yet).
  /// Subscribed once the vehicle's status says its family, through the
  /// family table (link::ForFamily): the station needs no vehicle file.
  link::VehicleGlance Vehicle() const { return vehicle_.Load(); }
  /// Stops the commands and frees the camera at once (a few release
  /// commands: they are best effort). Idempotent.
  void Release();

  const video::VideoReceiver& video() const { return *video_; }
  StationFigures Figures() const;
  const link::WriterId& writer() const { return writer_id_; }

 private:
  void OnStatus(const msg::CameraStatus& status);
  void OnFrame(const msg::VideoFrame& frame, const link::SampleStamps& stamps);
  void SendTick(int64_t now_ns);
  /// Command thread: reads the vehicle's state, of `family`'s type.
  void SubscribeState(const char* family);
  void Send(const CameraAim& aim, bool release, int64_t now_ns);

  StationOptions options_;
  Seqlock<CameraAim> aim_;
  Seqlock<CameraNow> now_;
  link::WriterId writer_id_;
  std::atomic<bool> released_{false};

  // Command thread's.
  msg::CameraCommand command_;
  uint64_t seq_ = 0;
  CameraAim last_sent_{};
  bool sent_any_ = false;
  std::atomic<uint64_t> sent_{0};
  std::atomic<int64_t> held_ns_{0};
  int64_t last_tick_ns_ = 0;
  /// The commands that moved the aim, by seq (a ring), with their send
  /// times: the frames that carry them close the latency.
  static constexpr size_t kMoves = 256;
  struct Move {
    std::atomic<uint64_t> seq{0};
    std::atomic<int64_t> sent_ns{0};
  };
  std::array<Move, kMoves> moves_;
  std::atomic<uint64_t> last_move_seq_{0};

  // DDS thread's (video): the latency histogram and the latest frame's aim.
  uint64_t measured_up_to_ = 0;      ///< moves up to this seq are measured
  Histogram latency_{100.0, 20000};  // 0.1 ms bins to 2 s; wait-free, read by Figures
  struct PictureAim {
    CameraAim aim;
    double fov_deg = 0.0;
    uint64_t frames = 0;
  };
  Seqlock<PictureAim> picture_;
  Seqlock<link::VehicleGlance> vehicle_;  ///< written by the state's DDS thread

  // Declared last: destroyed first, so no DDS callback outlives the rest.
  std::unique_ptr<link::Participant> participant_;
  std::unique_ptr<link::CameraStatusReader> status_reader_;
  std::unique_ptr<video::VideoReceiver> video_;
  std::unique_ptr<link::CameraCommandWriter> writer_;
  /// The vehicle's state reader, of its family's type (made by the command
  /// thread once the family is known; a shared_ptr<void> keeps its deleter).
  std::shared_ptr<void> state_reader_;
  std::unique_ptr<PeriodicThread> sender_;
};

}  // namespace haptel::station
