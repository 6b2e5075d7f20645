#pragma once
/// @file `haptel replay`: a session file (MCAP) played back, described or
/// driven again.
///
///     haptel replay --info FILE.mcap [--json]

namespace haptel::app {

/// argv[0] is "replay". Dispatches on the options to the subcommands below;
/// returns the exit code.
int ReplayCommand(int argc, const char* const* argv);

/// `haptel replay --info FILE.mcap`: channels with their schemas and
/// encodings, message counts, rates, duration, chunk compression, attachments
/// and metadata; says when the file was truncated (read by a scan).
int ReplayInfoCommand(int argc, const char* const* argv);

}  // namespace haptel::app
