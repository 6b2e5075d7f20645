#include "haptel/study/console_access.hpp"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <netinet/in.h>
#include <openssl/rand.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <stdexcept>

#include "haptel/study/submission.hpp"

namespace haptel::study {
namespace {

std::string Lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return text;
}

/// A header's value; several of one name are refused (which would count?).
bool SingleHeader(const httplib::Request& request, const char* name, std::string& value) {
  const size_t count = request.get_header_value_count(name);
  value = count == 1 ? request.get_header_value(name) : "";
  return count <= 1;
}

bool SameText(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char differ = 0;
  for (size_t i = 0; i < a.size(); ++i) differ |= static_cast<unsigned char>(a[i] ^ b[i]);
  return differ == 0;
}

/// The value of cookie `name` in a Cookie header ("a=1; b=2").
std::string CookieValue(const std::string& header, const std::string& name) {
  size_t at = 0;
  while (at < header.size()) {
    size_t end = header.find(';', at);
    if (end == std::string::npos) end = header.size();
    std::string pair = header.substr(at, end - at);
    const size_t first = pair.find_first_not_of(' ');
    pair = first == std::string::npos ? "" : pair.substr(first);
    const size_t equals = pair.find('=');
    if (equals != std::string::npos && pair.compare(0, equals, name) == 0 &&
        equals == name.size()) {
      return pair.substr(equals + 1);
    }
    at = end + 1;
  }
  return "";
}

bool ChangesState(const std::string& method) { return method != "GET" && method != "HEAD"; }

std::string WithPort(const std::string& host, int port) {
  return host + ":" + std::to_string(port);
}

/// This machine's interfaces' IPv4 addresses, and with `v6` its IPv6 ones
/// but link-local (which need a zone in a URL).
std::vector<std::string> InterfaceAddresses(bool v6) {
  std::vector<std::string> addresses;
  ifaddrs* list = nullptr;
  if (getifaddrs(&list) != 0) return addresses;
  for (const ifaddrs* i = list; i != nullptr; i = i->ifa_next) {
    if (i->ifa_addr == nullptr) continue;
    char text[INET6_ADDRSTRLEN] = {};
    if (i->ifa_addr->sa_family == AF_INET) {
      inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(i->ifa_addr)->sin_addr, text,
                sizeof text);
    } else if (i->ifa_addr->sa_family == AF_INET6 && v6) {
      const auto* a = reinterpret_cast<const sockaddr_in6*>(i->ifa_addr);
      if (IN6_IS_ADDR_LINKLOCAL(&a->sin6_addr)) continue;
      inet_ntop(AF_INET6, &a->sin6_addr, text, sizeof text);
    }
    if (text[0] != 0) addresses.emplace_back(text);
  }
  freeifaddrs(list);
  return addresses;
}

}  // namespace

bool IsLoopbackAddress(const std::string& address) {
  const std::string a = Lower(address);
  if (a == "localhost" || a == "::1" || a == "[::1]") return true;
  in_addr v4{};
  return inet_pton(AF_INET, a.c_str(), &v4) == 1 && (ntohl(v4.s_addr) >> 24) == 127;
}

std::vector<std::string> ConsoleHosts(const std::string& address, int port, bool tls,
                                      const std::vector<std::string>& names) {
  std::vector<std::string> hosts;
  auto add = [&](std::string host) {
    host = Lower(host);
    if (host.empty()) return;
    in6_addr v6{};
    if (inet_pton(AF_INET6, host.c_str(), &v6) == 1) host = "[" + host + "]";
    for (const std::string& h :
         {WithPort(host, port), std::string(port == (tls ? 443 : 80) ? host : "")}) {
      if (!h.empty() && std::find(hosts.begin(), hosts.end(), h) == hosts.end()) hosts.push_back(h);
    }
  };
  const bool wildcard = address == "0.0.0.0" || address == "::" || address == "[::]";
  if (!wildcard) add(address);
  if (IsLoopbackAddress(address) || wildcard) {
    add("localhost");
    add("127.0.0.1");
    add("::1");
  }
  if (!IsLoopbackAddress(address)) {
    char name[256] = {};
    if (gethostname(name, sizeof name - 1) == 0) add(name);
  }
  if (wildcard) {
    for (const std::string& a : InterfaceAddresses(true)) add(a);
  }
  for (const std::string& name : names) add(name);
  return hosts;
}

std::vector<std::string> ConsoleUrls(const std::string& address, int port, bool tls,
                                     const std::vector<std::string>& names) {
  std::vector<std::string> urls;
  auto add = [&](const std::string& host) {
    in6_addr v6{};
    const std::string shown = inet_pton(AF_INET6, host.c_str(), &v6) == 1 ? "[" + host + "]" : host;
    const std::string url =
        std::string(tls ? "https://" : "http://") + shown + ":" + std::to_string(port) + "/";
    if (!host.empty() && std::find(urls.begin(), urls.end(), url) == urls.end())
      urls.push_back(url);
  };
  const bool wildcard = address == "0.0.0.0" || address == "::" || address == "[::]";
  if (!wildcard) {
    add(address.size() > 2 && address.front() == '[' ? address.substr(1, address.size() - 2)
                                                     : address);
    return urls;
  }
  if (tls && !names.empty()) {
    // The only names the browser takes the certificate for.
    for (const std::string& name : names) add(name);
    return urls;
  }
  char name[256] = {};
  if (gethostname(name, sizeof name - 1) == 0 && !IsLoopbackAddress(name)) add(name);
  // IPv6 ones only when the console listens on IPv6 (::).
  for (const std::string& a : InterfaceAddresses(address != "0.0.0.0")) {
    if (!IsLoopbackAddress(a)) add(a);
  }
  add("127.0.0.1");
  return urls;
}

size_t FormBytesFor(size_t text_characters, size_t fields) {
  // Each field: its name and the separators (bounded by 96 bytes encoded),
  // a short value (a rating, a choice: 64); text: 4 bytes a character, %XX.
  return text_characters * 4 * 3 + fields * (96 + 64);
}

std::string RandomToken() {
  unsigned char bytes[16];
  if (RAND_bytes(bytes, sizeof bytes) != 1)
    throw std::runtime_error("no random bytes for the console's token");
  static const char kHex[] = "0123456789abcdef";
  std::string token;
  for (const unsigned char b : bytes) {
    token += kHex[b >> 4];
    token += kHex[b & 15];
  }
  return token;
}

bool IsAccessToken(const ConsoleAccess& access, const std::string& token) {
  return !access.access_token.empty() && SameText(token, access.access_token);
}

Refusal CheckRequest(const ConsoleAccess& access, const httplib::Request& request) {
  std::string host;
  if (!SingleHeader(request, "Host", host) || host.empty()) {
    return {403, "refused: the request names no single Host"};
  }
  if (std::find(access.hosts.begin(), access.hosts.end(), Lower(host)) == access.hosts.end()) {
    return {403, "refused: this console does not answer to Host '" + host.substr(0, 80) +
                     "' (a page of another site reached this machine by its name)"};
  }
  if (ChangesState(request.method)) {
    std::string origin;
    std::string site;
    if (!SingleHeader(request, "Origin", origin) ||
        !SingleHeader(request, "Sec-Fetch-Site", site)) {
      return {403, "refused: more than one Origin or Sec-Fetch-Site"};
    }
    const std::string own = std::string(access.tls ? "https://" : "http://") + Lower(host);
    if (!origin.empty() && Lower(origin) != own) {
      return {403, "refused: a form of another site (" + origin.substr(0, 80) +
                       ") cannot change the study"};
    }
    if (!site.empty() && site != "same-origin" && site != "none") {
      return {403,
              "refused: the browser says this request comes from another site (Sec-Fetch-Site: " +
                  site.substr(0, 40) + ")"};
    }
  }
  if (!access.access_token.empty() && request.path != "/login") {
    std::string cookies;
    for (size_t i = 0; i < request.get_header_value_count("Cookie"); ++i) {
      cookies += (cookies.empty() ? "" : "; ") + request.get_header_value("Cookie", i);
    }
    if (!IsAccessToken(access, CookieValue(cookies, kAccessCookie))) {
      return {401,
              "the console asks for its access token (printed where `haptel study run` started)"};
    }
  }
  // A body the library would read whole (a chunked one, or one with no
  // length, read until the client closes: cpp-httplib 0.11 bounds neither)
  // is taken only where the route reads its form itself, up to its limit.
  const bool reads_its_form =
      request.method == "POST" && (request.path == "/answers" || request.path == "/notes");
  if (!reads_its_form && ChangesState(request.method) &&
      (request.has_header("Transfer-Encoding") || !request.has_header("Content-Length"))) {
    return {
        411,
        "refused: a form here comes with a Content-Length (as a browser sends it), not chunked or "
        "unbounded"};
  }
  if (request.has_header("Content-Length")) {
    const size_t limit = request.path == "/answers" ? access.max_answers_bytes
                         : request.path == "/notes" ? access.max_note_bytes
                                                    : access.max_other_bytes;
    const std::string text = request.get_header_value("Content-Length");
    const bool number = !text.empty() && text.size() <= 18 &&
                        text.find_first_not_of("0123456789") == std::string::npos;
    if (!number)
      return {400, "refused: Content-Length '" + text.substr(0, 40) + "' is not a length"};
    const size_t length = std::stoull(text);
    if (length > limit) {
      return {413,
              "refused: the form is " + std::to_string(length) +
                  " bytes; this console takes at most " + std::to_string(limit) +
                  " here (the longest answers this study's questionnaires allow, or a note of " +
                  std::to_string(kMaxNoteCharacters) + " characters)"};
    }
  }
  return {};
}

Refusal CheckFormToken(const ConsoleAccess& access, const std::string& posted) {
  if (posted.empty() || !SameText(posted, access.form_token)) {
    return {403,
            "refused: the form is not one this console served (it came from another page, or the "
            "console "
            "was restarted since it was loaded): reload the schedule and try again"};
  }
  return {};
}

}  // namespace haptel::study
