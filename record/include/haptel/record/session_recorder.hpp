#pragma once
/// @file Records a whole run into a session file (MCAP; the channels are
/// listed in session_channels.hpp): the DDS samples the run sends and
/// receives (a link::SampleTap on its participant) and each received
/// state's pose (foxglove::PoseInFrame), the video as received, the servo
/// loop's ticks (a haptics::ServoTap), the interface's and the lap's
/// events, the predictor's ghost (and its pose) and the interface's force
/// field, beside the run's metadata and configuration files.
///
/// Nothing a producer does waits: each producer has its own wait-free
/// single-producer ring (a byte ring per DDS channel and the video, a
/// value ring per servo arm and for the session thread's records), and the
/// recorder's own thread drains them into the file, flushing a complete
/// chunk every second (a run killed loses at most the last second). A full
/// ring refuses the message and counts it as dropped; the report says how
/// many per channel (the aim: none).
#include <array>
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "haptel/core/spsc_ring.hpp"
#include "haptel/haptics/servo_tap.hpp"
#include "haptel/haptics/types.hpp"
#include "haptel/link/sample_tap.hpp"

namespace haptel::mcap {
class Writer;
}

namespace haptel::record {

/// One file's options.
struct SessionFileOptions {
  std::filesystem::path file;
  /// Metadata "haptel" (session_channels.hpp: version, command_line, ...).
  std::map<std::string, std::string> run_metadata;
  /// Metadata "study" (participant, condition, position, ...); empty: none.
  std::map<std::string, std::string> study_metadata;
  /// Configuration files attached as they are on disk now.
  std::vector<std::filesystem::path> attachments;
  size_t channel_ring_bytes = size_t{1} << 20;  ///< per DDS channel
  size_t video_ring_bytes = size_t{32} << 20;   ///< a few seconds of key frames
  size_t servo_ring_ticks = size_t{1} << 14;    ///< per arm: 16 s at 1 kHz
  double flush_period_s = 1.0;
};

/// A channel's figures in the report.
struct SessionChannelCount {
  std::string topic;
  std::string schema;
  uint64_t messages = 0;  ///< written to the file
  uint64_t bytes = 0;     ///< their payloads' bytes
  uint64_t dropped = 0;   ///< refused by a full ring (or too large for it)
};

/// What became of the file (SessionRecorder::Close).
struct SessionFileReport {
  std::filesystem::path file;
  bool saved = false;  ///< complete and closed; false: `error` says why
  std::string error;
  uint64_t bytes = 0;    ///< the file's size
  uint64_t dropped = 0;  ///< over every channel
  /// The recorder's own thread's CPU time, s, over `duration_s` of wall
  /// time (opened to closed): its share of a core is their ratio.
  double thread_cpu_s = 0.0;
  double duration_s = 0.0;
  std::vector<SessionChannelCount> channels;
  /// The channel's messages by topic (0: none), summed over its channels.
  uint64_t Messages(const std::string& topic) const;
};

/// The report as JSON: {"file","saved","error","bytes","dropped",
/// "channels":[{"topic","schema","messages","bytes","dropped"}, ...]}, or
/// null without a file.
std::string SessionFileJson(const SessionFileReport& report);
/// One line for a program's summary ("session file F: N messages in C
/// channels, B MB, D dropped" or "session file F NOT saved: why").
std::string SessionFileLine(const SessionFileReport& report);

/// An interface's or a lap's event (record/idl/session.idl's Event).
struct SessionEvent {
  int64_t t_ns = 0;
  double t_s = 0.0;
  char kind[32] = {};
  int32_t index = -1;
  uint8_t side = 255;  ///< 255: none
  double value = 0.0;
  char text[128] = {};
  /// Fills kind and text (truncated to fit).
  static SessionEvent Make(int64_t t_ns, double t_s, const char* kind, int32_t index = -1,
                           uint8_t side = 255, double value = 0.0, const char* text = "");
};

/// The predictor's ghost (session.idl's Ghost).
struct SessionGhost {
  int64_t t_ns = 0;
  bool valid = false;
  double x = 0.0, y = 0.0, z = 0.0, heading = 0.0;
  double reported_x = 0.0, reported_y = 0.0, reported_z = 0.0;
  double delay_s = 0.0;
};

class SessionRecorder final : public link::SampleTap, public haptics::ServoTap {
 public:
  /// Creates the file (and its folder), writes the metadata and the
  /// attachments, and starts the recorder's thread. Throws
  /// std::runtime_error naming the file (or the attachment) when it cannot.
  explicit SessionRecorder(SessionFileOptions options);
  /// Closes the file if Close was not called.
  ~SessionRecorder() override;
  SessionRecorder(const SessionRecorder&) = delete;
  SessionRecorder& operator=(const SessionRecorder&) = delete;

  // link::SampleTap: the DDS samples (a VideoFrame becomes the video channel).
  int OnTopic(const std::string& topic, const std::string& type_name,
              link::TapDirection direction) override;
  bool WantsBytes(int channel) const override;
  void OnSample(int channel, int64_t now_ns, const void* sample, const uint8_t* cdr,
                size_t size) override;
  /// A channel of a type of the caller's own (`schema`, described by the OMG
  /// IDL `idl`, `cdr` encoded), fed by one producer thread through OnSample
  /// with its CDR bytes (`sample` unused): the operator's view
  /// (view/view_record.hpp). Set-up only; -1 when no channel can be had (as
  /// OnTopic).
  int AddOwnChannel(const std::string& topic, const std::string& schema, const std::string& idl);

  // haptics::ServoTap: from each arm's servo thread.
  void Push(const haptics::ServoSample& sample) noexcept override;

  // The session thread's records (one producer: that thread). Wait-free.
  void InterfaceEvent(const SessionEvent& event);
  void LapEvent(const SessionEvent& event);
  void Ghost(const SessionGhost& ghost);
  /// The interface's force field for `side` (recorded when it changed).
  void Field(int64_t t_ns, uint8_t side, const haptics::ForceField& field);

  /// Stops the thread, drains every ring and closes the file (summary,
  /// indexes, footer). Never throws: a failure is in the report. Call once
  /// the producers have stopped (later calls return the same report).
  SessionFileReport Close();

  const std::filesystem::path& file() const { return options_.file; }

 private:
  struct ByteChannel;
  struct Pending;
  /// Which state a byte channel's samples are, to derive a pose from.
  enum class PoseSource : uint8_t { kNone, kRobot, kBlimp };
  int AddByteChannel(const std::string& topic, const std::string& schema, const std::string& idl,
                     std::map<std::string, std::string> metadata, bool video, PoseSource pose);
  void WritePose(ByteChannel& channel, int64_t mono_ns, const uint8_t* data, size_t size);
  void Run();
  void Drain();
  void DrainBytes(ByteChannel& channel);
  void DrainSessionRings();
  void WriteMessage(uint16_t channel, uint32_t sequence, int64_t mono_ns, int64_t publish_wall_ns,
                    const uint8_t* data, size_t size, SessionChannelCount& count);
  uint16_t McapChannel(const std::string& topic, const std::string& schema, const std::string& idl,
                       std::map<std::string, std::string> metadata);
  uint64_t LogTime(int64_t mono_ns) const;
  void Fail(const std::string& what);

  /// A session-side record kind's channel and count.
  struct SideChannel {
    uint16_t id = 0;
    SessionChannelCount count;
    std::atomic<uint64_t> dropped{0};
  };
  struct FieldRecord {
    int64_t t_ns;
    uint8_t side;
    haptics::ForceField field;
  };
  struct EventRecord {
    bool lap;
    SessionEvent event;
  };

  SessionFileOptions options_;
  int64_t wall_minus_mono_ns_ = 0;
  std::unique_ptr<mcap::Writer> writer_;
  std::mutex writer_mutex_;  ///< the MCAP writer and the channel table: set-up vs the thread
  std::map<std::string, uint16_t> schemas_;

  static constexpr int kMaxByteChannels = 64;
  std::array<std::unique_ptr<ByteChannel>, kMaxByteChannels> byte_channels_;
  std::atomic<int> byte_channel_count_{0};

  std::array<std::unique_ptr<SpscRing<haptics::ServoSample>>, 2> servo_rings_;
  SpscRing<EventRecord> events_;
  SpscRing<SessionGhost> ghosts_;
  SpscRing<FieldRecord> fields_;
  SideChannel servo_, interface_events_, lap_events_, ghost_, field_, ghost_pose_;

  std::vector<uint8_t> scratch_;
  std::atomic<bool> stop_{false};
  std::string error_;  ///< the first failure (the thread's, until Close joins it)
  int64_t opened_ns_ = 0;
  std::atomic<double> thread_cpu_s_{0.0};  ///< the thread's, as it ended
  bool closed_ = false;
  SessionFileReport report_;
  std::thread thread_;
};

}  // namespace haptel::record
