#pragma once
/// @file Spawns and supervises a child process (a vehicle node, a device server).
///
/// The child gets SIGTERM if this process dies (PR_SET_PDEATHSIG), so no
/// child outlives its parent on the same host (a remote vehicle relies on its
/// own command watchdog instead).
#include <string>
#include <sys/types.h>
#include <vector>

namespace haptel {

class ChildProcess {
 public:
  /// Starts `program` with `arguments`. Throws std::runtime_error if it cannot.
  ChildProcess(const std::string& program, const std::vector<std::string>& arguments);
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

 private:
  void Record(int status);
  pid_t pid_ = -1;
  bool exited_ = false;
  std::string exit_description_ = "running";
};

}  // namespace haptel
