#pragma once
/// @file Spawns and supervises a child process: a vehicle node, a device
/// server, a benchmark's other half, or the program under an end-to-end test.
/// The one way Haptel starts processes.
///
/// The child gets SIGTERM if this process dies (PR_SET_PDEATHSIG), so no
/// child outlives its parent on the same host (a remote vehicle relies on its
/// own command watchdog instead). With `capture_output` its stdout and stderr
/// go to pipes that Pump() drains without blocking.
#include <sys/types.h>

#include <filesystem>
#include <string>
#include <vector>

namespace haptel {

/// The folder of the running program, where Haptel's other programs sit
/// (haptel-vehicle, haptel-bench, ...); "." if /proc cannot tell.
std::filesystem::path ProgramDirectory();

class ChildProcess {
 public:
  struct Options {
    bool capture_output = false;  ///< stdout and stderr into out() and err()
  };
  /// What Wait returns while the child still runs.
  static constexpr int kStillRunning = -1000;

  /// Starts `program` with `arguments`. Throws std::runtime_error if it cannot.
  ChildProcess(const std::string& program, const std::vector<std::string>& arguments);
  ChildProcess(const std::string& program, const std::vector<std::string>& arguments,
               Options options);
  /// Terminates the child if it still runs.
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  pid_t pid() const { return pid_; }
  /// Non-blocking: false once the child has exited (reaps it).
  bool Alive();
  /// How the child ended, e.g. "exited with code 0", "killed by signal 9".
  std::string ExitDescription() const { return exit_description_; }
  /// SIGTERM, wait up to `grace_s`, then SIGKILL. Returns the exit description.
  std::string Terminate(double grace_s = 2.0);

  /// Waits up to `timeout_s` for the child to exit (draining its output);
  /// returns its exit code, −signal if a signal ended it, or kStillRunning.
  int Wait(double timeout_s);
  bool exited() const { return exited_; }
  /// Reads whatever captured output is available, without blocking.
  void Pump();
  const std::string& out() const { return stdout_; }
  const std::string& err() const { return stderr_; }
  /// The last non-empty line of the captured stdout.
  std::string LastLine() const;

 private:
  void Record(int status);
  pid_t pid_ = -1;
  bool exited_ = false;
  int code_ = kStillRunning;
  std::string exit_description_ = "running";
  int out_fd_ = -1;
  int err_fd_ = -1;
  std::string stdout_;
  std::string stderr_;
};

}  // namespace haptel
