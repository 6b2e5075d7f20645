#pragma once
/// @file The skeleton every Haptel program's main() shares: `--help`, one-line
/// errors ("program: message") on stderr, and the exit codes.
///
/// A program's main is `return cli::Main(kProgram, argc, argv, body);`. What
/// escapes `body` becomes one line and an exit code by its type: bad input
/// (InputError: UsageError, ConfigError) is 2, anything else 1. Reading
/// arguments and files goes through ReadInput, so whatever fails there is bad
/// input, whatever its type.
#include <functional>
#include <stdexcept>
#include <string>
#include <utility>

namespace haptel::cli {

inline constexpr int kExitOk = 0;
inline constexpr int kExitFailed = 1;       ///< something failed while running
inline constexpr int kExitBadInput = 2;     ///< bad arguments or configuration: nothing ran
inline constexpr int kExitLost = 3;         ///< the vehicle or the haptic device was lost
inline constexpr int kExitNotRecorded = 4;  ///< results went to a fallback file, not the database
/// The run is in the database, but an output it was asked to keep (the
/// --record MP4, the vehicle's CAN bus log) failed to be written; the
/// message says which and why.
inline constexpr int kExitOutputFailed = 5;

/// The user's input is wrong (exit 2): arguments, files, their combination.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Hardware went away while in use (exit 3): a serial port, a CAN bus. An
/// adapter throws it; its node stops driving the hardware and says so.
class HardwareLost : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Program {
  std::string name;   ///< as the user types it, e.g. "haptel calibrate"
  std::string usage;  ///< printed for --help (stdout, exit 0)
};

/// Whether argv (after argv[0], up to a "--") holds --help or -h.
bool HelpRequested(int argc, const char* const* argv);

/// Prints the usage for --help (exit 0); otherwise runs body and maps what
/// escapes it to one line on stderr and an exit code. A UsageError's line
/// adds "(see NAME --help)".
int Main(const Program& program, int argc, const char* const* argv,
         const std::function<int()>& body);

/// Runs `read` (reading arguments and files): whatever it throws is bad input.
template <class Read>
auto ReadInput(Read&& read) -> decltype(read()) {
  try {
    return std::forward<Read>(read)();
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(e.what());
  }
}

}  // namespace haptel::cli
