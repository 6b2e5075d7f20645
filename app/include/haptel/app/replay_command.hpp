#pragma once
/// @file `haptel replay`: a session file (MCAP) played back, described or
/// driven again.
///
///     haptel replay FILE.mcap [--speed X] [--from S] [--view window|none] [--mp4 OUT.mp4]
///     haptel replay FILE.mcap --drive [--domain D] [--attach] [--json]
///     haptel replay --info FILE.mcap [--json]

namespace haptel::app {

/// argv[0] is "replay". Dispatches on the options to the subcommands below;
/// returns the exit code.
int ReplayCommand(int argc, const char* const* argv);

/// `haptel replay FILE.mcap`: the operator's view drawn again, in a window,
/// offscreen into an MP4, or read through without drawing (--view none).
int ReplayViewCommand(int argc, const char* const* argv);

/// `haptel replay FILE.mcap --drive`: the recorded commands sent to a
/// vehicle again, its lap timed beside the record's.
int ReplayDriveCommand(int argc, const char* const* argv);

/// `haptel replay --info FILE.mcap`: channels with their schemas and
/// encodings, message counts, rates, duration, chunk compression, attachments
/// and metadata; says when the file was truncated (read by a scan).
int ReplayInfoCommand(int argc, const char* const* argv);

}  // namespace haptel::app
