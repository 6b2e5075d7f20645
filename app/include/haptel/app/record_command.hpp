#pragma once
/// @file `haptel record`: session files (MCAP) made on the side of a run, and
/// repaired.
///
///     haptel record --domain D [--vehicle NAME] FILE.mcap
///     haptel record --recover IN.mcap OUT.mcap

namespace haptel::app {

/// argv[0] is "record". Dispatches on the options to the subcommands below;
/// returns the exit code.
int RecordCommand(int argc, const char* const* argv);

/// `haptel record --domain D [--vehicle NAME] FILE`: what the domain shows,
/// recorded on the side of a run (app/src/record_domain.cpp).
int RecordDomainCommand(int argc, const char* const* argv);

/// `haptel record --recover IN OUT`: a complete file (summary and indexes
/// rebuilt) from one whose recording was killed before it was closed.
int RecordRecoverCommand(int argc, const char* const* argv);

}  // namespace haptel::app
