#include "console_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <openssl/err.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <condition_variable>
#include <deque>
#include <functional>
#include <stdexcept>
#include <string_view>
#include <thread>

namespace haptel::study {
namespace {

using Clock = std::chrono::steady_clock;

std::string OpenSslReason() {
  char text[256] = "unknown reason";
  if (const unsigned long code = ERR_get_error(); code != 0)
    ERR_error_string_n(code, text, sizeof text);
  ERR_clear_error();
  return text;
}

/// An address as text, and its port; an IPv4 address reached through an
/// IPv6 socket as IPv4, so that a client is counted once whichever way it came.
std::string AddressText(const sockaddr_storage& address, int& port) {
  char text[INET6_ADDRSTRLEN] = "?";
  port = 0;
  if (address.ss_family == AF_INET) {
    const auto& v4 = reinterpret_cast<const sockaddr_in&>(address);
    inet_ntop(AF_INET, &v4.sin_addr, text, sizeof text);
    port = ntohs(v4.sin_port);
  } else if (address.ss_family == AF_INET6) {
    const auto& v6 = reinterpret_cast<const sockaddr_in6&>(address);
    if (IN6_IS_ADDR_V4MAPPED(&v6.sin6_addr)) {
      inet_ntop(AF_INET, &v6.sin6_addr.s6_addr[12], text, sizeof text);
    } else {
      inet_ntop(AF_INET6, &v6.sin6_addr, text, sizeof text);
    }
    port = ntohs(v6.sin6_port);
  }
  return text;
}

/// The client's address (`peer`) or ours, as text.
std::string SocketAddress(int fd, bool peer, int& port) {
  sockaddr_storage address{};
  socklen_t length = sizeof address;
  port = 0;
  const int got = peer ? getpeername(fd, reinterpret_cast<sockaddr*>(&address), &length)
                       : getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  return got == 0 ? AddressText(address, port) : "?";
}

/// One connection's bytes, plain or through TLS, on a non-blocking socket:
/// every wait ends at the head's deadline (until the request's head has
/// come), the connection's deadline, or after `idle` without progress,
/// whichever comes first (then it reports an error and the exchange ends).
/// It reads at most `budget` bytes in all: past them, an error, whatever the
/// request claims (cpp-httplib 0.11 buffers a header line, or a chunk's size
/// line, whole before it checks its length).
class DeadlineStream final : public httplib::Stream {
 public:
  struct Limits {
    Clock::time_point head_deadline;
    Clock::time_point deadline;
    std::chrono::milliseconds idle;
    size_t budget;
  };
  /// `on_head`: called once, when the request's head has been read.
  DeadlineStream(int fd, SSL* ssl, const Limits& limits, std::function<void()> on_head = {})
      : fd_(fd), ssl_(ssl), limits_(limits), on_head_(std::move(on_head)) {}

  bool is_readable() const override {
    return (ssl_ != nullptr && SSL_pending(ssl_) > 0) || Wait(POLLIN);
  }
  bool is_writable() const override { return Wait(POLLOUT); }

  ssize_t read(char* ptr, size_t size) override {
    if (read_ >= limits_.budget) {
      over_budget_ = true;
      return -1;
    }
    const int n = static_cast<int>(std::min<size_t>({size, limits_.budget - read_, INT_MAX}));
    for (;;) {
      short want = POLLIN;
      if (ssl_ != nullptr) {
        const int got = SSL_read(ssl_, ptr, n);
        if (got > 0) return Took(ptr, got);
        const int error = SSL_get_error(ssl_, got);
        if (error == SSL_ERROR_ZERO_RETURN) return 0;
        if (error == SSL_ERROR_WANT_WRITE) {
          want = POLLOUT;
        } else if (error != SSL_ERROR_WANT_READ) {
          return -1;
        }
      } else {
        const ssize_t got = recv(fd_, ptr, static_cast<size_t>(n), MSG_DONTWAIT);
        if (got > 0) return Took(ptr, got);
        if (got == 0) return 0;
        if (errno == EINTR) continue;
        if (errno != EAGAIN && errno != EWOULDBLOCK) return -1;
      }
      if (!Wait(want)) return -1;
    }
  }

  ssize_t write(const char* ptr, size_t size) override {
    const int n = static_cast<int>(std::min<size_t>(size, INT_MAX));
    for (;;) {
      short want = POLLOUT;
      if (ssl_ != nullptr) {
        const int put = SSL_write(ssl_, ptr, n);
        if (put > 0) return put;
        const int error = SSL_get_error(ssl_, put);
        if (error == SSL_ERROR_WANT_READ) {
          want = POLLIN;
        } else if (error != SSL_ERROR_WANT_WRITE) {
          return -1;
        }
      } else {
        const ssize_t put = send(fd_, ptr, static_cast<size_t>(n), MSG_DONTWAIT | MSG_NOSIGNAL);
        if (put >= 0) return put;
        if (errno == EINTR) continue;
        if (errno != EAGAIN && errno != EWOULDBLOCK) return -1;
      }
      if (!Wait(want)) return -1;
    }
  }

  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    ip = SocketAddress(fd_, true, port);
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    ip = SocketAddress(fd_, false, port);
  }
  socket_t socket() const override { return fd_; }

  /// Whether a wait ended at a deadline or for silence.
  bool timed_out() const { return timed_out_; }
  bool over_budget() const { return over_budget_; }

  /// Waits for `events` on the socket until the deadline that applies, or `idle`.
  bool Wait(short events) const {
    const Clock::time_point until =
        head_done_ ? limits_.deadline : std::min(limits_.head_deadline, limits_.deadline);
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(until - Clock::now());
    const auto wait = std::min(left, limits_.idle);
    if (wait.count() <= 0) {
      timed_out_ = true;
      return false;
    }
    pollfd p{fd_, events, 0};
    int ready;
    do {
      ready = poll(&p, 1, static_cast<int>(wait.count()));
    } while (ready < 0 && errno == EINTR);
    if (ready == 0) timed_out_ = true;
    return ready > 0;
  }

 private:
  /// Counts `got` bytes read, and watches for the head's end: a line feed,
  /// an optional carriage return, a line feed (the blank line).
  ssize_t Took(const char* ptr, ssize_t got) {
    read_ += static_cast<size_t>(got);
    for (ssize_t i = 0; i < got && !head_done_; ++i) {
      const char c = ptr[i];
      if (c == '\n' && (last_ == '\n' || (last_ == '\r' && before_last_ == '\n'))) {
        head_done_ = true;
        if (on_head_) on_head_();
      }
      before_last_ = last_;
      last_ = c;
    }
    return got;
  }

  int fd_;
  SSL* ssl_;
  Limits limits_;
  std::function<void()> on_head_;
  size_t read_ = 0;
  bool head_done_ = false;
  char last_ = 0;
  char before_last_ = 0;
  bool over_budget_ = false;
  mutable bool timed_out_ = false;
};

/// Shuts down the sending side and reads what the client still sends, for a
/// short while, before the socket is closed: closing with unread bytes
/// (the rest of a refused body) resets the connection, and the client may
/// lose the answer that says why.
void LingeringClose(int fd, Clock::time_point deadline) {
  shutdown(fd, SHUT_WR);
  const Clock::time_point until = std::min(deadline, Clock::now() + std::chrono::milliseconds(500));
  char sink[16384];
  size_t drained = 0;
  while (drained < (1u << 20)) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(until - Clock::now()).count();
    if (left <= 0) break;
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, static_cast<int>(left)) <= 0) break;
    const ssize_t got = recv(fd, sink, sizeof sink, MSG_DONTWAIT);
    if (got <= 0) break;
    drained += static_cast<size_t>(got);
  }
  close(fd);
}

/// Whether the end of a request's head (a blank line) waits unread on a
/// plain socket: a peek, nothing taken from the connection's worker.
bool HeadWaiting(int fd) {
  char peek[8192];
  const ssize_t got = recv(fd, peek, sizeof peek, MSG_PEEK | MSG_DONTWAIT);
  if (got <= 0) return false;
  const std::string_view bytes(peek, static_cast<size_t>(got));
  // Its worker reads the head a byte at a time, so the rest may start at the blank line.
  return bytes.find("\n\r\n") != std::string_view::npos ||
         bytes.find("\n\n") != std::string_view::npos || bytes.rfind("\r\n", 0) == 0 ||
         bytes.rfind("\n", 0) == 0;
}

}  // namespace

void ConnectionPolicy::ValidateOrThrow() const {
  if (max_per_client < 1)
    throw std::invalid_argument("ConnectionPolicy::max_per_client: expected at least 1");
  if (deadline.count() <= 0)
    throw std::invalid_argument("ConnectionPolicy::deadline: expected more than 0");
  if (head_deadline.count() <= 0 || head_deadline > deadline) {
    throw std::invalid_argument(
        "ConnectionPolicy::head_deadline: expected more than 0 and at most the deadline");
  }
  if (idle.count() <= 0 || idle > deadline) {
    throw std::invalid_argument(
        "ConnectionPolicy::idle: expected more than 0 and at most the deadline");
  }
  if (threads <= static_cast<size_t>(max_per_client)) {
    throw std::invalid_argument(
        "ConnectionPolicy::threads: expected more than max_per_client, so that one address cannot "
        "hold them all");
  }
  if (worker_linger.count() <= 0)
    throw std::invalid_argument("ConnectionPolicy::worker_linger: expected more than 0");
}

TlsContext MakeTlsContext(const std::filesystem::path& certificate,
                          const std::filesystem::path& key) {
  TlsContext ctx(SSL_CTX_new(TLS_server_method()));
  if (!ctx) throw std::runtime_error("cannot make a TLS context: " + OpenSslReason());
  SSL_CTX_set_min_proto_version(ctx.get(), TLS1_2_VERSION);
  SSL_CTX_set_mode(ctx.get(), SSL_MODE_ENABLE_PARTIAL_WRITE | SSL_MODE_ACCEPT_MOVING_WRITE_BUFFER);
  if (SSL_CTX_use_certificate_chain_file(ctx.get(), certificate.c_str()) != 1) {
    throw std::runtime_error(certificate.string() +
                             ": not a usable PEM certificate: " + OpenSslReason());
  }
  if (SSL_CTX_use_PrivateKey_file(ctx.get(), key.c_str(), SSL_FILETYPE_PEM) != 1) {
    throw std::runtime_error(key.string() + ": not a usable PEM private key: " + OpenSslReason());
  }
  if (SSL_CTX_check_private_key(ctx.get()) != 1) {
    throw std::runtime_error(key.string() + ": is not the key of " + certificate.string());
  }
  return ctx;
}

/// The workers' queue: before a connection waits for a worker, the server
/// makes room for it (ConsoleServer::MakeRoom). Its workers are started as
/// connections come, up to `max`, and end after `linger` idle: a study's
/// trial locks the process's memory for its servo loop (mlockall), and with
/// it every thread's whole stack, 8 MB each. A fixed pool of 128 idle
/// workers made a people study 1 GB more resident from its first trial on.
class ConsoleServer::Queue final : public httplib::TaskQueue {
 public:
  Queue(ConsoleServer& server, size_t max, std::chrono::milliseconds linger)
      : server_(server), max_(max), linger_(linger) {}
  ~Queue() override { shutdown(); }

  void enqueue(std::function<void()> fn) override {
    server_.MakeRoom();
    std::vector<std::thread> ended;
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      jobs_.push_back(std::move(fn));
      ended = TakeEnded();
      // Each idle worker takes one queued job; a job beyond them starts a
      // worker while there is room for one (else it waits its turn).
      if (jobs_.size() > idle_ && workers_.size() < max_) {
        std::thread worker([this] { Work(); });
        workers_.emplace(worker.get_id(), std::move(worker));
        server_.workers_.store(workers_.size());
      } else {
        ready_.notify_one();
      }
    }
    for (std::thread& t : ended) t.join();
  }

  void shutdown() override {
    std::map<std::thread::id, std::thread> all;
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
      all.swap(workers_);
      ended_.clear();
      server_.workers_.store(0);
    }
    ready_.notify_all();
    for (auto& [id, t] : all) t.join();  // after the jobs queued (as httplib's pool)
  }

  /// The server waits for connections: the workers that ended are joined.
  void on_idle() override {
    std::vector<std::thread> ended;
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      ended = TakeEnded();
    }
    for (std::thread& t : ended) t.join();
  }

 private:
  void Work() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      ++idle_;
      const bool woken =
          ready_.wait_for(lock, linger_, [this] { return !jobs_.empty() || stopping_; });
      --idle_;
      if (jobs_.empty()) {
        if (stopping_ || !woken) break;
        continue;
      }
      std::function<void()> job = std::move(jobs_.front());
      jobs_.pop_front();
      lock.unlock();
      job();
      lock.lock();
    }
    // Idle for `linger`: joined by the next enqueue (or shutdown).
    if (!stopping_) {
      ended_.push_back(std::this_thread::get_id());
      server_.workers_.store(workers_.size() - ended_.size());
    }
  }

  /// The workers that ended, out of `workers_`, to be joined. Under `mutex_`.
  std::vector<std::thread> TakeEnded() {
    std::vector<std::thread> ended;
    for (const std::thread::id id : ended_) {
      if (const auto it = workers_.find(id); it != workers_.end()) {
        ended.push_back(std::move(it->second));
        workers_.erase(it);
      }
    }
    ended_.clear();
    return ended;
  }

  ConsoleServer& server_;
  const size_t max_;
  const std::chrono::milliseconds linger_;
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<std::function<void()>> jobs_;
  std::map<std::thread::id, std::thread> workers_;  ///< started, not yet joined
  std::vector<std::thread::id> ended_;              ///< of `workers_`, ended idle
  size_t idle_ = 0;
  bool stopping_ = false;
};

ConsoleServer::ConsoleServer(const ConnectionPolicy& policy, TlsContext tls)
    : policy_(policy), tls_(std::move(tls)) {
  policy_.ValidateOrThrow();
  new_task_queue = [this] { return new Queue(*this, policy_.threads, policy_.worker_linger); };
}

ConsoleServer::~ConsoleServer() = default;

bool ConsoleServer::CutOldest(const std::string& address) {
  auto oldest = open_.end();
  for (auto it = open_.begin(); it != open_.end(); ++it) {
    const Connection& c = it->second;
    if (c.head_done || c.cut || (!address.empty() && c.address != address)) continue;
    // Its whole head has come, its worker has not read it yet (a loaded
    // machine): a prompt client, not one to cut.
    if (!tls_ && HeadWaiting(it->first)) continue;
    if (oldest == open_.end() || c.accepted < oldest->second.accepted) oldest = it;
  }
  if (oldest == open_.end()) return false;
  // Its worker sees the socket end and releases it; the descriptor stays
  // open (and ours) until then, so this cannot reach another connection.
  shutdown(oldest->first, SHUT_RDWR);
  oldest->second.cut = true;
  ++cut_for_room_;
  return true;
}

void ConsoleServer::MakeRoom() {
  const std::lock_guard<std::mutex> lock(mutex_);
  size_t busy = waiting_;
  for (const auto& [fd, c] : open_) busy += c.cut ? 0 : 1;
  if (busy >= policy_.threads) CutOldest("");
  ++waiting_;
}

bool ConsoleServer::Admit(const std::string& address, int fd) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (stopping_) return false;
  int held = 0;
  for (const auto& [other, c] : open_) held += c.address == address && !c.cut ? 1 : 0;
  if (held >= policy_.max_per_client && !CutOldest(address)) return false;
  open_[fd] = Connection{address, Clock::now(), false, false};
  return true;
}

void ConsoleServer::Release(int fd) {
  const std::lock_guard<std::mutex> lock(mutex_);
  open_.erase(fd);
}

void ConsoleServer::HeadDone(int fd) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (const auto it = open_.find(fd); it != open_.end()) it->second.head_done = true;
}

void ConsoleServer::StopAll() {
  // A request being answered (its head read) may be the one that ended the
  // study (Finish): its answer is written before its socket is cut, within
  // a grace; connections still without their head are cut at once.
  constexpr auto kGrace = std::chrono::seconds(2);
  const Clock::time_point until = Clock::now() + kGrace;
  for (;;) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
      bool answering = false;
      const bool late = Clock::now() >= until;
      for (const auto& [fd, c] : open_) {
        if (c.head_done && !late) {
          answering = true;
        } else if (!c.cut) {
          shutdown(fd, SHUT_RDWR);
        }
      }
      if (!answering) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  stop();
}

ConnectionCounters ConsoleServer::counters() const {
  ConnectionCounters c;
  c.served = served_.load();
  c.refused_busy = refused_busy_.load();
  c.cut_deadline = cut_deadline_.load();
  c.cut_for_room = cut_for_room_.load();
  c.tls_failed = tls_failed_.load();
  c.workers = workers_.load();
  return c;
}

bool ConsoleServer::process_and_close_socket(socket_t sock) {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (waiting_ > 0) --waiting_;
  }
  const Clock::time_point now = Clock::now();
  // The head, the largest body taken (a chunked one with its chunks' sizes),
  // and room: no request the console takes is larger.
  const size_t payload = std::min<size_t>(payload_max_length_, size_t{1} << 40);
  const DeadlineStream::Limits limits{now + policy_.head_deadline, now + policy_.deadline,
                                      policy_.idle, 2 * payload + (64u << 10)};
  int port = 0;
  const std::string address = SocketAddress(sock, true, port);
  fcntl(sock, F_SETFL, fcntl(sock, F_GETFL) | O_NONBLOCK);
  if (!Admit(address, sock)) {
    ++refused_busy_;
    if (!tls_) {
      static const char kBusy[] =
          "HTTP/1.1 503 Service Unavailable\r\nContent-Type: text/plain\r\nConnection: close\r\n"
          "Content-Length: 58\r\n\r\ntoo many connections from your address at once; try again\n";
      (void)!send(sock, kBusy, sizeof kBusy - 1, MSG_DONTWAIT | MSG_NOSIGNAL);
    }
    LingeringClose(sock, Clock::now());
    return false;
  }
  SSL* ssl = nullptr;
  bool handshake = true;
  if (tls_) {
    ssl = SSL_new(tls_.get());
    DeadlineStream waits(sock, nullptr, limits);
    handshake = ssl != nullptr && SSL_set_fd(ssl, sock) == 1;
    while (handshake) {
      const int r = SSL_accept(ssl);
      if (r == 1) break;
      const int error = SSL_get_error(ssl, r);
      if (error == SSL_ERROR_WANT_READ) {
        handshake = waits.Wait(POLLIN);
      } else if (error == SSL_ERROR_WANT_WRITE) {
        handshake = waits.Wait(POLLOUT);
      } else {
        handshake = false;
      }
    }
    ERR_clear_error();
    if (!handshake) {
      ++tls_failed_;
      if (waits.timed_out()) ++cut_deadline_;
    }
  }
  bool ok = false;
  if (handshake) {
    ++served_;
    DeadlineStream stream(sock, ssl, limits, [this, sock] { HeadDone(sock); });
    bool closed = false;
    // One request per connection: a kept-alive connection would hold a
    // worker for as long as the browser likes.
    ok = process_request(stream, /*close_connection=*/true, closed, nullptr);
    if (stream.timed_out()) ++cut_deadline_;
  }
  if (ssl != nullptr) {
    if (handshake) SSL_shutdown(ssl);  // one non-blocking close_notify; no wait for the client's
    SSL_free(ssl);
    ERR_clear_error();
  }
  Release(sock);
  LingeringClose(sock, limits.deadline);
  return ok;
}

}  // namespace haptel::study
