#pragma once
/// @file The console's HTTP server with a connection policy of its own:
/// cpp-httplib parses the requests and routes them; this class owns each
/// connection from accept to close. It bounds the connections one client
/// address may hold at once, gives every connection one deadline for its
/// request and response (a client that sends a header line every few
/// seconds, or reads the answer byte by byte, is cut off, not waited for),
/// serves one request per connection, and speaks TLS when given a
/// certificate. Internal to the study library.
#include <httplib.h>
#include <openssl/ssl.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <map>
#include <mutex>
#include <set>
#include <string>

#include "haptel/study/console.hpp"

namespace haptel::study {

/// A TLS context from a PEM certificate (chain) and its private key.
/// Throws std::runtime_error naming the file and OpenSSL's reason.
struct SslCtxFree {
  void operator()(SSL_CTX* ctx) const { SSL_CTX_free(ctx); }
};
using TlsContext = std::unique_ptr<SSL_CTX, SslCtxFree>;
TlsContext MakeTlsContext(const std::filesystem::path& certificate, const std::filesystem::path& key);

class ConsoleServer : public httplib::Server {
 public:
  /// `tls`: null for plain HTTP.
  ConsoleServer(const ConnectionPolicy& policy, TlsContext tls);
  ~ConsoleServer() override;

  /// Stops accepting and ends every open connection at once (slow clients
  /// included), so that listen_after_bind() returns promptly.
  void StopAll();
  ConnectionCounters counters() const;
  bool tls() const { return tls_ != nullptr; }

 private:
  bool process_and_close_socket(socket_t sock) override;
  /// Counts `address` in; false when it holds `max_per_client` already.
  bool Admit(const std::string& address, int fd);
  void Release(const std::string& address, int fd);

  const ConnectionPolicy policy_;
  const TlsContext tls_;
  mutable std::mutex mutex_;
  std::map<std::string, int> open_by_address_;
  std::set<int> open_sockets_;
  bool stopping_ = false;
  std::atomic<uint64_t> served_{0};
  std::atomic<uint64_t> refused_busy_{0};
  std::atomic<uint64_t> cut_deadline_{0};
  std::atomic<uint64_t> tls_failed_{0};
};

}  // namespace haptel::study
