#pragma once
/// @file Which process on which host: how a vehicle names the process that
/// publishes its states, so that a run can tell its own vehicle from another
/// answering under the same name; and how a process that commands a vehicle
/// (a run, a camera station) names itself to the others.
#include <cstdint>
#include <string>

namespace haptel {

/// This host's name (gethostname), at most 63 characters; "?" if unknown.
std::string HostName();

/// Who runs this process ($USER, else the password database's name; "?").
std::string UserName();

/// A random session id, never 0: names one run's (or one station's)
/// commands. A label, not a credential.
uint64_t NewSessionId();

/// "PROGRAM, user@host pid N" (at most 63 characters): what another
/// operator is told of this process ("haptel run, ana@lab1 pid 4242").
std::string ProcessOperatorName(const std::string& program);

}  // namespace haptel
