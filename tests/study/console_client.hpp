#pragma once
// The experimenter's console as a browser uses it, for the tests: every
// form posted carries the console's form token, read from its pages as a
// browser has it. Raw connections (from a chosen loopback address) for the
// tests that play a slow or hostile client.
#include <arpa/inet.h>
#include <httplib.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <regex>
#include <string>

#include "haptel/testing/loopback.hpp"

namespace haptel::test {

/// The form token in a console page ("" when the page has no form).
inline std::string FormToken(const std::string& page) {
  static const std::regex kToken("name=\"csrf\" value=\"([0-9a-f]+)\"");
  std::smatch match;
  return std::regex_search(page, match, kToken) ? match[1].str() : "";
}

class ConsoleClient {
 public:
  ConsoleClient(const std::string& host, int port) : client_(host, port) {
    client_.set_read_timeout(20, 0);
  }

  httplib::Result Get(const std::string& path) { return client_.Get(path); }
  /// A form post as the page sends it: with the form token.
  httplib::Result Post(const std::string& path, httplib::Params params = {}) {
    params.emplace("csrf", token());
    return client_.Post(path, params);
  }
  /// The token every page's forms carry (the login page always has a form).
  std::string token() {
    if (token_.empty()) {
      if (const auto page = client_.Get("/login")) token_ = FormToken(page->body);
    }
    return token_;
  }
  httplib::Client& raw() { return client_; }

 private:
  httplib::Client client_;
  std::string token_;
};

using haptel::testing::ConnectFrom;

inline bool SendAll(int fd, const std::string& bytes) {
  size_t sent = 0;
  while (sent < bytes.size()) {
    const ssize_t n = send(fd, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
    if (n <= 0) return false;
    sent += static_cast<size_t>(n);
  }
  return true;
}

/// Everything the server sends until it closes (or 20 s pass).
inline std::string ReadUntilClosed(int fd) {
  std::string got;
  char buffer[4096];
  for (;;) {
    const ssize_t n = recv(fd, buffer, sizeof buffer, 0);
    if (n <= 0) break;
    got.append(buffer, static_cast<size_t>(n));
  }
  return got;
}

}  // namespace haptel::test
