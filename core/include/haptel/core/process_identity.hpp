#pragma once
/// @file Which process on which host: how a vehicle names the process that
/// publishes its states, so that a run can tell its own vehicle from another
/// answering under the same name.
#include <string>

namespace haptel {

/// This host's name (gethostname), at most 63 characters; "?" if unknown.
std::string HostName();

}  // namespace haptel
