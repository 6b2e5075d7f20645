#pragma once
/// @file The channels of a session file (`haptel run --session FILE.mcap`,
/// a study's trials, `haptel record`): their topics, schema names and
/// encodings, for the recorder that writes them and the readers (`haptel
/// replay`, the tests) that look them up. Every channel is `cdr` encoded
/// with an `omgidl` schema, so one OMG IDL decoder reads every message; a
/// channel's schema text is the whole IDL file its type is in.
///
/// - The DDS samples the run sent and received: topic = the DDS topic
///   (`haptel/<vehicle>/command`, `.../state`, `.../video_feedback`,
///   `.../selected`, `.../can_log`, ...), schema = the type's
///   module-qualified name in link/idl/haptel.idl (`haptel::msg::TreadCommand`),
///   message = the CDR bytes as they crossed the link (encapsulation header
///   included). The video's VideoFrame samples are not among them: the
///   video is its own channel, below.
/// - The video: topic `haptel/<vehicle>/video`, `foxglove::CompressedVideo`
///   (H.264) or `foxglove::CompressedImage` (JPEG) of record/idl/foxglove.idl,
///   one frame per message exactly as received, `timestamp` the capture's
///   CLOCK_REALTIME, the MCAP message's `sequence` the frame's
///   VideoFrame.seq (a gap: a frame lost on the link).
/// - The vehicle's pose as the run received it (its state's odometry, never
///   a simulator's truth): topic `haptel/<vehicle>/pose`,
///   `foxglove::PoseInFrame` in frame "world" (the track's or the course's
///   frame, z up), one per state received with a pose; and the predictor's
///   ghost, `haptel/session/ghost_pose`, the same schema: Foxglove's and
///   Lichtblick's 3-D panel draws both.
/// - The operator's side, record/idl/session.idl: the servo ticks, the
///   interface's and the lap's events, the predictor's ghost, the
///   interface's force field (the wall, shared control's guidance).
///
/// Every message's log_time is CLOCK_REALTIME ns at the moment the run
/// had it (sent, received, ticked); publish_time is the sender's stamp
/// where one is known (a video frame's capture), else log_time.
#include <string>
#include <string_view>

namespace haptel::record::session {

// Encodings (the MCAP registry's names).
inline constexpr std::string_view kSchemaEncoding = "omgidl";
inline constexpr std::string_view kMessageEncoding = "cdr";

// The operator side's topics.
inline constexpr std::string_view kServoTopic = "haptel/session/servo";
inline constexpr std::string_view kInterfaceEventsTopic = "haptel/session/interface_events";
inline constexpr std::string_view kLapEventsTopic = "haptel/session/lap_events";
inline constexpr std::string_view kGhostTopic = "haptel/session/ghost";
inline constexpr std::string_view kFieldTopic = "haptel/session/field";
inline constexpr std::string_view kGhostPoseTopic = "haptel/session/ghost_pose";

// Their schemas' names (record/idl/session.idl).
inline constexpr std::string_view kServoTickSchema = "haptel::session::ServoTick";
inline constexpr std::string_view kEventSchema = "haptel::session::Event";
inline constexpr std::string_view kGhostSchema = "haptel::session::Ghost";
inline constexpr std::string_view kFieldSchema = "haptel::session::Field";

// The video (record/idl/foxglove.idl).
inline constexpr std::string_view kCompressedVideoSchema = "foxglove::CompressedVideo";
inline constexpr std::string_view kCompressedImageSchema = "foxglove::CompressedImage";
/// The video's topic for `vehicle` (the DDS video topic's name).
inline std::string VideoTopic(std::string_view vehicle) {
  return "haptel/" + std::string(vehicle) + "/video";
}

// The poses (record/idl/foxglove.idl): the frame they are in.
inline constexpr std::string_view kPoseInFrameSchema = "foxglove::PoseInFrame";
inline constexpr std::string_view kPoseFrame = "world";
/// The pose's topic for `vehicle`.
inline std::string PoseTopic(std::string_view vehicle) {
  return "haptel/" + std::string(vehicle) + "/pose";
}

/// The DDS types' schema names are "haptel::msg::" + the IDL struct's name.
inline constexpr std::string_view kDdsSchemaPrefix = "haptel::msg::";

// Metadata records (MCAP Metadata): "haptel" (version, command_line,
// configuration: the run's options as `haptel run` took them, vehicle,
// track, interfaces, device, started_utc) and, for a study's trial,
// "study" (study, participant, condition, position, trial).
inline constexpr std::string_view kRunMetadata = "haptel";
inline constexpr std::string_view kStudyMetadata = "study";

// Attachments: each configuration file the run loaded, named by its path
// as given, media type "application/yaml" (or "application/xml").

// The channels' channel metadata (MCAP Channel.metadata) carries, for a
// DDS channel, "direction" = "sent" | "received" and "dds_type" = the DDS
// type name; for the video, "vehicle".

/// The IDL files' texts (the schemas' data), compiled in from record/idl/
/// and link/idl/haptel.idl.
std::string_view SessionIdl();
std::string_view FoxgloveIdl();
std::string_view HaptelIdl();

}  // namespace haptel::record::session
