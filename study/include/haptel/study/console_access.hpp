#pragma once
/// @file Who may use the experimenter's console, checked on every request
/// before its body is read: the Host it was addressed to (a page of another
/// site rebinding its DNS name to this machine is refused), where a
/// state-changing request comes from (Origin, Sec-Fetch-Site), the access
/// token beyond loopback, and how large a body may be. Forms carry a
/// per-console token as well (CheckFormToken), against a cross-site form
/// post from a browser that sends neither Origin nor Sec-Fetch-Site.
#include <httplib.h>

#include <string>
#include <vector>

namespace haptel::study {

struct ConsoleAccess {
  /// Host header values accepted, lower case, with the port ("127.0.0.1:8470").
  std::vector<std::string> hosts;
  bool tls = false;  ///< the page is served over HTTPS
  /// Hidden in every form; a POST without it is refused.
  std::string form_token;
  /// Asked once by the page (then held in a cookie) when the console listens
  /// beyond loopback; empty: not asked.
  std::string access_token;
  /// The largest body of `POST /answers` (the longest form the study's
  /// questionnaires allow, url-encoded) and of any other request.
  size_t max_answers_bytes = 65536;
  /// The largest body of `POST /notes`: a note of kMaxNoteCharacters
  /// (submission.hpp), url-encoded, with its hidden fields.
  size_t max_note_bytes = 32768;
  size_t max_other_bytes = 8192;
};

/// Why a request is refused: status 0 when it is admitted.
struct Refusal {
  int status = 0;
  std::string reason;
  explicit operator bool() const { return status != 0; }
};

/// The cookie that carries the access token.
inline constexpr const char* kAccessCookie = "haptel_console";

/// Checks a request's head (everything but its body): the Host, a
/// state-changing request's Origin and Sec-Fetch-Site, the access cookie
/// (except for the login page), the body's announced length. 403 for a
/// request from elsewhere, 401 without the access token, 411 for a body with
/// no length or a chunked one (but where the route reads its form itself:
/// answers, notes), 413 for a body too
/// large (the reason names both sizes).
Refusal CheckRequest(const ConsoleAccess& access, const httplib::Request& request);

/// A posted form's `csrf` field against the console's form token (403).
Refusal CheckFormToken(const ConsoleAccess& access, const std::string& posted);

/// Whether `token` is the access token (constant time in its length).
bool IsAccessToken(const ConsoleAccess& access, const std::string& token);

/// 32 hexadecimal digits from the system's random source (128 bits).
std::string RandomToken();

/// The Host header values a console bound to `address`:`port` answers to:
/// the address itself, this machine's host name, and for a loopback address
/// `localhost`, `127.0.0.1` and `[::1]`; for a wildcard address (0.0.0.0,
/// ::) every address of this machine's interfaces. `names` are added (the
/// names in the HTTPS certificate). Lower case; the port is left out as
/// well for the scheme's default port.
std::vector<std::string> ConsoleHosts(const std::string& address, int port, bool tls,
                                      const std::vector<std::string>& names);

/// The addresses a browser can open for a console bound to
/// `address`:`port` ("http://NAME:PORT/"). A wildcard address (0.0.0.0, ::)
/// is none: over HTTPS with `names` (the certificate's), those names; else
/// this machine's host name, its interfaces' non-loopback addresses, and
/// 127.0.0.1. Any other address is itself.
std::vector<std::string> ConsoleUrls(const std::string& address, int port, bool tls,
                                     const std::vector<std::string>& names);

/// Whether `address` is a loopback address or `localhost`.
bool IsLoopbackAddress(const std::string& address);

/// The largest url-encoded body of a form whose text fields hold at most
/// `text_characters` characters in all and which has `fields` fields in all:
/// every character may take 4 bytes of UTF-8, each sent as %XX.
size_t FormBytesFor(size_t text_characters, size_t fields);

}  // namespace haptel::study
