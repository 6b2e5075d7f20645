#pragma once
/// @file Where tests find binaries and scratch space, and a DDS domain of
/// their own so tests running in parallel never hear each other.
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>

namespace haptel::test {

/// build/bin, from HAPTEL_BIN_DIR (set by ctest).
inline std::filesystem::path BinDir() {
  const char* dir = std::getenv("HAPTEL_BIN_DIR");
  return dir != nullptr ? std::filesystem::path(dir) : std::filesystem::path("build/bin");
}

/// A fresh folder for this process's scratch files.
inline std::filesystem::path ScratchDir(const std::string& name) {
  const char* base = std::getenv("HAPTEL_TEST_TMP");
  const std::filesystem::path root =
      base != nullptr ? base : std::filesystem::temp_directory_path();
  const auto dir = root / (name + "-" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

/// Overwrites the whole page in the middle of an SQLite file (of at least 8
/// pages of `page_size` bytes, SQLite's default) with garbage, as a failing
/// disk or a stray write would: the header and the schema on page 1 stay
/// intact, so the file opens as before and only reading that page finds it.
inline void DamageMiddlePage(const std::filesystem::path& file, size_t page_size = 4096) {
  const auto size = static_cast<size_t>(std::filesystem::file_size(file));
  if (size < 8 * page_size)
    throw std::runtime_error("test file " + file.string() + " is too small to damage");
  std::fstream io(file, std::ios::binary | std::ios::in | std::ios::out);
  io.seekp(static_cast<std::streamoff>(size / page_size / 2 * page_size));
  io << std::string(page_size, '\x5a');
  io.flush();
  if (!io.good()) throw std::runtime_error("cannot damage test file " + file.string());
}

/// Writes `text` to `file` (its folder must exist) and returns the path.
/// A full disk without root, for a CAN bus log: the vehicle writes
/// `<can_dir>/<name>-<UTC second>.log`, so each name it may take from 5 s
/// ago to 5 min from now is made a link to /dev/full, where every write
/// fails with ENOSPC.
inline void CanLogsOnFullDisk(const std::filesystem::path& can_dir, const std::string& name) {
  std::filesystem::create_directories(can_dir);
  const time_t now = time(nullptr);
  for (time_t t = now - 5; t < now + 300; ++t) {
    tm utc{};
    gmtime_r(&t, &utc);
    char stamp[32];
    std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &utc);
    std::filesystem::create_symlink("/dev/full", can_dir / (name + "-" + stamp + ".log"));
  }
}

inline std::filesystem::path WriteFile(const std::filesystem::path& file, const std::string& text) {
  std::ofstream out(file);
  out << text;
  if (!out.good()) throw std::runtime_error("cannot write test file " + file.string());
  return file;
}

/// The message of the `E` that `f` throws, or "(no exception)" when it
/// throws none (so a check on the message fails, naming why).
template <typename E, typename F>
std::string WhatOf(F&& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  return "(no exception)";
}

/// A DDS domain id (1..230) no other test process holds: each is claimed by
/// an exclusive lock on a file of its own under the temporary directory,
/// kept until this process ends, so test programs running side by side
/// (ctest -j) never hear each other. The same salt gives the same domain
/// within a process; different salts, different domains.
inline int UniqueDomain(int salt = 0) {
  static std::mutex mutex;
  static std::map<int, int> claimed;  // salt -> domain
  const std::lock_guard<std::mutex> lock(mutex);
  if (const auto it = claimed.find(salt); it != claimed.end()) return it->second;
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "haptel-test-domains";
  std::filesystem::create_directories(dir);
  std::filesystem::permissions(dir, std::filesystem::perms::all,
                               std::filesystem::perm_options::add);
  for (int k = 0; k < 230; ++k) {
    const int domain = 1 + static_cast<int>((getpid() * 7 + salt + k) % 230);
    bool mine = false;
    for (const auto& [s, d] : claimed) mine = mine || d == domain;
    if (mine) continue;
    const int fd =
        ::open((dir / std::to_string(domain)).c_str(), O_CREAT | O_RDONLY | O_CLOEXEC, 0666);
    if (fd < 0) continue;
    if (::flock(fd, LOCK_EX | LOCK_NB) == 0) {  // held (fd kept open) until the process ends
      claimed[salt] = domain;
      return domain;
    }
    ::close(fd);
  }
  throw std::runtime_error("UniqueDomain: every DDS domain 1..230 is held by another test process");
}

/// Polls `condition` every 10 ms until it holds or `timeout_s` passes.
/// Generous timeouts only: this bounds a wait, it asserts no timing.
template <typename Condition>
bool WaitFor(Condition condition, double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < deadline) {
    if (condition()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return condition();
}

/// A point in time after which a busy loop in a test gives up (and fails)
/// instead of spinning forever on a fault. Bounds a wait; asserts no timing.
class Deadline {
 public:
  explicit Deadline(double timeout_s)
      : at_(std::chrono::steady_clock::now() +
            std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                std::chrono::duration<double>(timeout_s))) {}
  bool passed() const { return std::chrono::steady_clock::now() >= at_; }

 private:
  std::chrono::steady_clock::time_point at_;
};

/// How long a test waits for one of its threads to end once it should.
inline constexpr double kJoinTimeout_s = 60.0;

/// A test's own thread, joined with a deadline. A body still running when
/// the deadline passes is a hang (a deadlock, a lost wake-up, a loop whose
/// exit never comes): the test cannot go on, since the body uses the test's
/// stack, so Join names the thread and the test on stderr and aborts; Catch
/// reports the abort as the running test's failure. Without this, a fault
/// hangs the test until ctest's timeout, which names nothing.
/// Keep Catch's assertions on the test's thread; count in the body instead.
class Thread {
 public:
  template <typename Body>
  Thread(std::string name, Body body)
      : name_(std::move(name)), thread_([this, body = std::move(body)]() mutable {
          body();
          const std::lock_guard<std::mutex> lock(mutex_);
          done_ = true;
          ended_.notify_all();
        }) {}
  Thread(const Thread&) = delete;
  Thread& operator=(const Thread&) = delete;
  ~Thread() { Join(); }

  /// Waits up to `timeout_s` for the body to return, then joins it.
  void Join(double timeout_s = kJoinTimeout_s) {
    if (!thread_.joinable()) return;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      if (!ended_.wait_for(lock, std::chrono::duration<double>(timeout_s),
                           [this] { return done_; })) {
        std::fprintf(stderr,
                     "test: thread '%s' still runs %.0f s after the test began to join it "
                     "(a hang%s): aborting\n",
                     name_.c_str(), timeout_s,
                     std::uncaught_exceptions() > 0 ? ", while an assertion unwinds the test" : "");
        std::abort();
      }
    }
    thread_.join();
  }

 private:
  std::string name_;
  std::mutex mutex_;
  std::condition_variable ended_;
  bool done_ = false;
  std::thread thread_;  // last: starts once the members above exist
};

}  // namespace haptel::test
