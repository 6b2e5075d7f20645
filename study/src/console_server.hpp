#pragma once
/// @file The console's HTTP server with a connection policy of its own:
/// cpp-httplib parses the requests and routes them; this class owns each
/// connection from accept to close. A connection must send its request's
/// head within a short deadline, and its whole exchange within a longer one
/// (a client that sends a header line every few seconds, or reads the
/// answer byte by byte, is cut off, not waited for); it reads no more bytes
/// than the largest request the console takes; when an address holds its
/// share of connections, or every worker is taken, the oldest connection
/// still without its head is cut to make room for the new one (slow and
/// silent clients cannot keep a prompt one out); one request per
/// connection; TLS when given a certificate. Internal to the study library.
#include <httplib.h>
#include <openssl/ssl.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <thread>

#include "haptel/study/console.hpp"

namespace haptel::study {

/// A TLS context from a PEM certificate (chain) and its private key.
/// Throws std::runtime_error naming the file and OpenSSL's reason.
struct SslCtxFree {
  void operator()(SSL_CTX* ctx) const { SSL_CTX_free(ctx); }
};
using TlsContext = std::unique_ptr<SSL_CTX, SslCtxFree>;
TlsContext MakeTlsContext(const std::filesystem::path& certificate,
                          const std::filesystem::path& key);

class ConsoleServer : public httplib::Server {
 public:
  /// `tls`: null for plain HTTP.
  ConsoleServer(const ConnectionPolicy& policy, TlsContext tls);
  ~ConsoleServer() override;

  /// Stops accepting and ends every open connection (slow clients included)
  /// so that listen_after_bind() returns promptly; a request already being
  /// answered gets up to 2 s to write its answer first (the Finish that
  /// ended the study is answered, not cut).
  void StopAll();
  ConnectionCounters counters() const;
  bool tls() const { return tls_ != nullptr; }

  /// The connection on `fd` has sent its request's head: it is no longer
  /// one to cut for room. (Called by the connection's stream.)
  void HeadDone(int fd);

 private:
  class Queue;
  struct Connection {
    std::string address;
    std::chrono::steady_clock::time_point accepted;
    bool head_done = false;
    bool cut = false;  ///< shut down to make room; its worker ends it
  };

  bool process_and_close_socket(socket_t sock) override;
  /// Counts `fd` in; false when `address` holds `max_per_client` that all
  /// have their heads (then nothing is cut).
  bool Admit(const std::string& address, int fd);
  void Release(int fd);
  /// A connection is about to wait for a worker: when every worker is
  /// taken, the oldest connection without its head is cut.
  void MakeRoom();
  /// Cuts the oldest connection without its head, of `address` (or of any
  /// address when empty). Under `mutex_`. False when there is none.
  bool CutOldest(const std::string& address);

  const ConnectionPolicy policy_;
  const TlsContext tls_;
  mutable std::mutex mutex_;
  std::map<int, Connection> open_;  ///< by socket, from Admit to Release
  size_t waiting_ = 0;              ///< accepted, not yet taken by a worker
  bool stopping_ = false;
  std::atomic<uint64_t> served_{0};
  std::atomic<uint64_t> refused_busy_{0};
  std::atomic<uint64_t> cut_deadline_{0};
  std::atomic<uint64_t> cut_for_room_{0};
  std::atomic<uint64_t> tls_failed_{0};
  std::atomic<size_t> workers_{0};  ///< the Queue's worker threads now
};

}  // namespace haptel::study
