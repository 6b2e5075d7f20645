#pragma once
// A child process with its stdout and stderr captured, for end-to-end tests.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace haptel::test {

class Child {
 public:
  explicit Child(std::vector<std::string> argv) {
    int out[2];
    int err[2];
    if (pipe(out) != 0 || pipe(err) != 0) throw std::runtime_error("pipe failed");
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    pid_ = fork();
    if (pid_ == 0) {
      dup2(out[1], 1);
      dup2(err[1], 2);
      close(out[0]);
      close(err[0]);
      execv(args[0], args.data());
      _exit(127);
    }
    close(out[1]);
    close(err[1]);
    out_ = out[0];
    err_ = err[0];
    fcntl(out_, F_SETFL, O_NONBLOCK);
    fcntl(err_, F_SETFL, O_NONBLOCK);
  }
  ~Child() {
    if (!exited_) {
      kill(pid_, SIGKILL);
      Wait(10.0);
    }
    close(out_);
    close(err_);
  }

  pid_t pid() const { return pid_; }
  /// Reads whatever is available into stdout()/stderr().
  void Pump() {
    char buf[4096];
    for (;;) {
      const ssize_t n = read(out_, buf, sizeof buf);
      if (n <= 0) break;
      stdout_.append(buf, static_cast<size_t>(n));
    }
    for (;;) {
      const ssize_t n = read(err_, buf, sizeof buf);
      if (n <= 0) break;
      stderr_.append(buf, static_cast<size_t>(n));
    }
  }
  /// Waits up to timeout_s for the child to exit; returns its exit code, or
  /// -signal, or nullopt-like INT_MIN if it still runs.
  int Wait(double timeout_s) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (!exited_) {
      Pump();
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        exited_ = true;
        code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
        break;
      }
      if (std::chrono::steady_clock::now() > deadline) return kRunning;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    Pump();
    return code_;
  }
  bool exited() const { return exited_; }
  const std::string& out() const { return stdout_; }
  const std::string& err() const { return stderr_; }
  /// The last non-empty line of stdout.
  std::string LastLine() const {
    std::string s = stdout_;
    while (!s.empty() && s.back() == '\n') s.pop_back();
    const auto nl = s.rfind('\n');
    return nl == std::string::npos ? s : s.substr(nl + 1);
  }

  static constexpr int kRunning = -1000;

 private:
  pid_t pid_ = -1;
  int out_ = -1;
  int err_ = -1;
  bool exited_ = false;
  int code_ = 0;
  std::string stdout_;
  std::string stderr_;
};

/// Value of a top-level key in a flat JSON object line (numbers, bools, strings).
inline std::string JsonField(const std::string& json, const std::string& key) {
  const std::string needle = "\"" + key + "\":";
  const auto at = json.find(needle);
  if (at == std::string::npos) return "";
  auto start = at + needle.size();
  if (json[start] == '"') {
    const auto end = json.find('"', start + 1);
    return json.substr(start + 1, end - start - 1);
  }
  const auto end = json.find_first_of(",}", start);
  return json.substr(start, end - start);
}

}  // namespace haptel::test
