#include "haptel/core/child_process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <thread>
#include <utility>

namespace haptel {

std::filesystem::path ProgramDirectory() {
  std::error_code ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path(".") : self.parent_path();
}

ChildProcess::ChildProcess(const std::string& program, const std::vector<std::string>& arguments)
    : ChildProcess(program, arguments, Options{}) {}

ChildProcess::ChildProcess(const std::string& program, const std::vector<std::string>& arguments,
                           Options options) {
  if (access(program.c_str(), X_OK) != 0) {
    throw std::runtime_error("cannot start a child process: '" + program +
                             "' is not an executable");
  }
  // Build argv before fork: the child may only make async-signal-safe calls.
  std::vector<std::string> words{program};
  words.insert(words.end(), arguments.begin(), arguments.end());
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  int out[2] = {-1, -1};
  int err[2] = {-1, -1};
  if (options.capture_output && (pipe2(out, O_CLOEXEC) != 0 || pipe2(err, O_CLOEXEC) != 0)) {
    throw std::runtime_error(std::string("cannot start a child process: pipe: ") +
                             std::strerror(errno));
  }
  const pid_t parent = getpid();
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error(std::string("cannot fork: ") + std::strerror(errno));
  if (pid_ == 0) {
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(127);  // the parent died before prctl
    if (options.capture_output) {
      dup2(out[1], STDOUT_FILENO);  // dup2 clears O_CLOEXEC on the copies
      dup2(err[1], STDERR_FILENO);
    }
    execv(program.c_str(), argv.data());
    _exit(127);
  }
  if (options.capture_output) {
    close(out[1]);
    close(err[1]);
    out_fd_ = out[0];
    err_fd_ = err[0];
    fcntl(out_fd_, F_SETFL, O_NONBLOCK);
    fcntl(err_fd_, F_SETFL, O_NONBLOCK);
  }
}

ChildProcess::~ChildProcess() {
  if (!exited_) Terminate();
  if (out_fd_ >= 0) close(out_fd_);
  if (err_fd_ >= 0) close(err_fd_);
}

void ChildProcess::Pump() {
  char buffer[4096];
  for (auto [fd, text] : {std::pair{out_fd_, &stdout_}, std::pair{err_fd_, &stderr_}}) {
    if (fd < 0) continue;
    for (;;) {
      const ssize_t n = read(fd, buffer, sizeof buffer);
      if (n <= 0) break;
      text->append(buffer, static_cast<size_t>(n));
    }
  }
}

int ChildProcess::Wait(double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (Alive()) {
    Pump();
    if (std::chrono::steady_clock::now() > deadline) return kStillRunning;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  Pump();
  return code_;
}

std::string ChildProcess::LastLine() const {
  std::string s = stdout_;
  while (!s.empty() && s.back() == '\n') s.pop_back();
  const auto nl = s.rfind('\n');
  return nl == std::string::npos ? s : s.substr(nl + 1);
}

void ChildProcess::Record(int status) {
  exited_ = true;
  code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
  if (WIFEXITED(status)) {
    exit_description_ = "exited with code " + std::to_string(WEXITSTATUS(status));
  } else if (WIFSIGNALED(status)) {
    exit_description_ = "killed by signal " + std::to_string(WTERMSIG(status)) + " (" +
                        strsignal(WTERMSIG(status)) + ")";
  }
}

bool ChildProcess::Alive() {
  if (exited_) return false;
  int status = 0;
  const pid_t r = waitpid(pid_, &status, WNOHANG);
  if (r == pid_) Record(status);
  return !exited_;
}

std::string ChildProcess::Terminate(double grace_s) {
  if (!Alive()) return exit_description_;
  kill(pid_, SIGTERM);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(grace_s);
  while (std::chrono::steady_clock::now() < deadline) {
    if (!Alive()) return exit_description_;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  kill(pid_, SIGKILL);
  int status = 0;
  if (waitpid(pid_, &status, 0) == pid_) Record(status);
  return exit_description_;
}

}  // namespace haptel
