#pragma once
/// @file A full disk without root or a real full disk: this process's file
/// size limit (RLIMIT_FSIZE, the soft one) lowered for a scope, with SIGXFSZ
/// ignored, so that a write that would grow a file past the limit fails with
/// EFBIG ("File too large") — as a write to a full disk fails with ENOSPC,
/// through the same error paths. Both are restored when it goes.
///
/// The limit holds for every thread and every regular file this process
/// writes while it stands: keep the scope to the writing under test.
#include <signal.h>
#include <sys/resource.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

namespace haptel::test {

class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    if (getrlimit(RLIMIT_FSIZE, &saved_) != 0) Throw("getrlimit");
    struct sigaction ignore {};
    ignore.sa_handler = SIG_IGN;
    sigemptyset(&ignore.sa_mask);
    if (sigaction(SIGXFSZ, &ignore, &saved_action_) != 0) Throw("sigaction");
    rlimit lower = saved_;
    lower.rlim_cur = bytes;
    if (setrlimit(RLIMIT_FSIZE, &lower) != 0) Throw("setrlimit");
  }
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &saved_);
    sigaction(SIGXFSZ, &saved_action_, nullptr);
  }
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;

 private:
  [[noreturn]] static void Throw(const char* call) {
    throw std::runtime_error(std::string("FileSizeLimit: ") + call + ": " + std::strerror(errno));
  }
  rlimit saved_{};
  struct sigaction saved_action_ {};
};

}  // namespace haptel::test
