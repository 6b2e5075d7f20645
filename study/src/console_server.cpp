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
#include <stdexcept>

namespace haptel::study {
namespace {

using Clock = std::chrono::steady_clock;

std::string OpenSslReason() {
  char text[256] = "unknown reason";
  if (const unsigned long code = ERR_get_error(); code != 0) ERR_error_string_n(code, text, sizeof text);
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
/// every wait ends at the connection's deadline, or after `idle` without
/// progress, whichever comes first (then it reports an error and the
/// exchange ends).
class DeadlineStream final : public httplib::Stream {
 public:
  DeadlineStream(int fd, SSL* ssl, Clock::time_point deadline, std::chrono::milliseconds idle)
      : fd_(fd), ssl_(ssl), deadline_(deadline), idle_(idle) {}

  bool is_readable() const override { return (ssl_ != nullptr && SSL_pending(ssl_) > 0) || Wait(POLLIN); }
  bool is_writable() const override { return Wait(POLLOUT); }

  ssize_t read(char* ptr, size_t size) override {
    const int n = static_cast<int>(std::min<size_t>(size, INT_MAX));
    for (;;) {
      short want = POLLIN;
      if (ssl_ != nullptr) {
        const int got = SSL_read(ssl_, ptr, n);
        if (got > 0) return got;
        const int error = SSL_get_error(ssl_, got);
        if (error == SSL_ERROR_ZERO_RETURN) return 0;
        if (error == SSL_ERROR_WANT_WRITE) {
          want = POLLOUT;
        } else if (error != SSL_ERROR_WANT_READ) {
          return -1;
        }
      } else {
        const ssize_t got = recv(fd_, ptr, static_cast<size_t>(n), MSG_DONTWAIT);
        if (got >= 0) return got;
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

  void get_remote_ip_and_port(std::string& ip, int& port) const override { ip = SocketAddress(fd_, true, port); }
  void get_local_ip_and_port(std::string& ip, int& port) const override { ip = SocketAddress(fd_, false, port); }
  socket_t socket() const override { return fd_; }

  /// Whether a wait ended at the deadline or for silence.
  bool timed_out() const { return timed_out_; }

  /// Waits for `events` on the socket until the deadline or `idle`.
  bool Wait(short events) const {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline_ - Clock::now());
    const auto wait = std::min(left, idle_);
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
  int fd_;
  SSL* ssl_;
  Clock::time_point deadline_;
  std::chrono::milliseconds idle_;
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
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(until - Clock::now()).count();
    if (left <= 0) break;
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, static_cast<int>(left)) <= 0) break;
    const ssize_t got = recv(fd, sink, sizeof sink, MSG_DONTWAIT);
    if (got <= 0) break;
    drained += static_cast<size_t>(got);
  }
  close(fd);
}

}  // namespace

void ConnectionPolicy::ValidateOrThrow() const {
  if (max_per_client < 1) throw std::invalid_argument("ConnectionPolicy::max_per_client: expected at least 1");
  if (deadline.count() <= 0) throw std::invalid_argument("ConnectionPolicy::deadline: expected more than 0");
  if (idle.count() <= 0 || idle > deadline) {
    throw std::invalid_argument("ConnectionPolicy::idle: expected more than 0 and at most the deadline");
  }
  if (threads <= static_cast<size_t>(max_per_client)) {
    throw std::invalid_argument(
        "ConnectionPolicy::threads: expected more than max_per_client, so that one address cannot hold them all");
  }
}

TlsContext MakeTlsContext(const std::filesystem::path& certificate, const std::filesystem::path& key) {
  TlsContext ctx(SSL_CTX_new(TLS_server_method()));
  if (!ctx) throw std::runtime_error("cannot make a TLS context: " + OpenSslReason());
  SSL_CTX_set_min_proto_version(ctx.get(), TLS1_2_VERSION);
  SSL_CTX_set_mode(ctx.get(), SSL_MODE_ENABLE_PARTIAL_WRITE | SSL_MODE_ACCEPT_MOVING_WRITE_BUFFER);
  if (SSL_CTX_use_certificate_chain_file(ctx.get(), certificate.c_str()) != 1) {
    throw std::runtime_error(certificate.string() + ": not a usable PEM certificate: " + OpenSslReason());
  }
  if (SSL_CTX_use_PrivateKey_file(ctx.get(), key.c_str(), SSL_FILETYPE_PEM) != 1) {
    throw std::runtime_error(key.string() + ": not a usable PEM private key: " + OpenSslReason());
  }
  if (SSL_CTX_check_private_key(ctx.get()) != 1) {
    throw std::runtime_error(key.string() + ": is not the key of " + certificate.string());
  }
  return ctx;
}

ConsoleServer::ConsoleServer(const ConnectionPolicy& policy, TlsContext tls) : policy_(policy), tls_(std::move(tls)) {
  policy_.ValidateOrThrow();
  const size_t threads = policy_.threads;
  new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
}

ConsoleServer::~ConsoleServer() = default;

bool ConsoleServer::Admit(const std::string& address, int fd) {
  const std::lock_guard<std::mutex> lock(mutex_);
  int& open = open_by_address_[address];
  if (stopping_ || open >= policy_.max_per_client) {
    if (open == 0) open_by_address_.erase(address);
    return false;
  }
  ++open;
  open_sockets_.insert(fd);
  return true;
}

void ConsoleServer::Release(const std::string& address, int fd) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (--open_by_address_[address] <= 0) open_by_address_.erase(address);
  open_sockets_.erase(fd);
}

void ConsoleServer::StopAll() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
    for (const int fd : open_sockets_) shutdown(fd, SHUT_RDWR);
  }
  stop();
}

ConnectionCounters ConsoleServer::counters() const {
  return {served_.load(), refused_busy_.load(), cut_deadline_.load(), tls_failed_.load()};
}

bool ConsoleServer::process_and_close_socket(socket_t sock) {
  const Clock::time_point deadline = Clock::now() + policy_.deadline;
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
    DeadlineStream waits(sock, nullptr, deadline, policy_.idle);
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
    DeadlineStream stream(sock, ssl, deadline, policy_.idle);
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
  Release(address, sock);
  LingeringClose(sock, deadline);
  return ok;
}

}  // namespace haptel::study
