#include "haptel/link/security.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <openssl/bio.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>
#include <signal.h>
#include <tinyxml2.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "haptel/config/error.hpp"
#include "haptel/core/child_process.hpp"
#include "haptel/core/log.hpp"

namespace haptel::link {

namespace fs = std::filesystem;

namespace {

constexpr int kMaxDomain = 232;

/// The subject of an identity's certificate: one CN, so the permissions'
/// subject_name matches it whatever order a library prints names in.
std::string Subject(const std::string& identity) { return "CN=haptel-" + identity; }

/// Runs openssl with `arguments` in `dir`; throws with its output on failure.
void OpenSsl(const fs::path& dir, std::vector<std::string> arguments) {
  ChildProcess openssl("/usr/bin/openssl", arguments, ChildProcess::Options{true});
  const int code = openssl.Wait(120.0);
  if (code != 0) {
    std::string line;
    for (const auto& a : arguments) line += " " + a;
    throw std::runtime_error("openssl" + line + " (in " + dir.string() +
                             ") failed: " + openssl.err());
  }
}

void Write(const fs::path& file, const std::string& text) {
  std::ofstream out(file);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + file.string());
}

std::string Governance() {
  return R"(<?xml version="1.0" encoding="UTF-8"?>
<!-- Haptel's link: only participants the CA vouches for join, and everything
     they say is encrypted. Written by `haptel security init`. -->
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains><id_range><min>0</min><max>)" +
         std::to_string(kMaxDomain) + R"(</max></id_range></domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>NONE</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
)";
}

std::string Iso(std::time_t t) {
  char text[32];
  std::tm tm{};
  gmtime_r(&t, &tm);
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S", &tm);
  return text;
}

std::string Topics(const std::vector<std::string>& topics) {
  std::string out;
  for (const auto& t : topics) out += "<topic>" + t + "</topic>";
  return out;
}

std::string Permissions(const std::string& identity, const std::vector<std::string>& publish,
                        const std::vector<std::string>& subscribe, int days) {
  const std::time_t now = std::time(nullptr);
  return R"(<?xml version="1.0" encoding="UTF-8"?>
<!-- What ')" +
         identity + R"(' may do on Haptel's link. Written by `haptel security init`. -->
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name=")" +
         identity + R"(">
      <subject_name>)" +
         Subject(identity) + R"(</subject_name>
      <validity><not_before>)" +
         Iso(now - 3600) + "</not_before><not_after>" + Iso(now + 86400L * days) +
         R"(</not_after></validity>
      <allow_rule>
        <domains><id_range><min>0</min><max>)" +
         std::to_string(kMaxDomain) + R"(</max></id_range></domains>
        <publish><topics>)" +
         Topics(publish) + R"(</topics></publish>
        <subscribe><topics>)" +
         Topics(subscribe) + R"(</topics></subscribe>
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
)";
}

/// A key and a certificate for `identity`, signed by the CA.
void MakeIdentity(const fs::path& dir, const std::string& identity, int days) {
  const std::string key = identity + ".key";
  const std::string csr = (dir / (identity + ".csr")).string();
  // Appended, not `"/" + ...`: GCC 12 -O2 flags that form with a false -Werror=restrict.
  std::string subject = "/";
  subject.append(Subject(identity));
  OpenSsl(dir, {"req", "-new", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1",
                "-nodes", "-keyout", (dir / key).string(), "-out", csr, "-subj", subject});
  OpenSsl(dir, {"x509", "-req", "-in", csr, "-CA", (dir / "ca.pem").string(), "-CAkey",
                (dir / "ca.key").string(), "-CAcreateserial", "-days", std::to_string(days),
                "-sha256", "-out", (dir / (identity + ".pem")).string()});
  fs::remove(csr);
}

/// `document`.xml signed by the CA into `document`.p7s (S/MIME, clear text).
void Sign(const fs::path& dir, const std::string& document) {
  OpenSsl(dir, {"smime", "-sign", "-text", "-in", (dir / (document + ".xml")).string(), "-out",
                (dir / (document + ".p7s")).string(), "-signer", (dir / "ca.pem").string(),
                "-inkey", (dir / "ca.key").string()});
}

struct X509Free {
  void operator()(X509* x) const { X509_free(x); }
};

/// Loads a PEM certificate; throws ConfigError naming it.
std::unique_ptr<X509, X509Free> LoadCertificate(const fs::path& dir, const fs::path& file) {
  FILE* f = std::fopen(file.c_str(), "r");
  if (f == nullptr) {
    throw ConfigError("security " + dir.string() + ": no " + file.filename().string() +
                      "; make the folder with `haptel security init " + dir.string() + "`");
  }
  std::unique_ptr<X509, X509Free> cert(PEM_read_X509(f, nullptr, nullptr, nullptr));
  std::fclose(f);
  if (!cert)
    throw ConfigError("security " + dir.string() + ": " + file.filename().string() +
                      " is not a PEM certificate");
  return cert;
}

std::string TimeText(const ASN1_TIME* t) {
  std::tm tm{};
  if (ASN1_TIME_to_tm(t, &tm) != 1) return "?";
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M UTC", &tm);
  return text;
}

void CheckValidNow(const fs::path& dir, const fs::path& file) {
  const auto cert = LoadCertificate(dir, file);
  if (X509_cmp_current_time(X509_get0_notBefore(cert.get())) > 0) {
    throw ConfigError("security " + dir.string() + ": certificate " + file.filename().string() +
                      " is not valid before " + TimeText(X509_get0_notBefore(cert.get())) +
                      " (is this host's clock right?)");
  }
  if (X509_cmp_current_time(X509_get0_notAfter(cert.get())) < 0) {
    throw ConfigError("security " + dir.string() + ": certificate " + file.filename().string() +
                      " expired on " + TimeText(X509_get0_notAfter(cert.get())) +
                      "; make new ones with `haptel security init`");
  }
}

/// What to do about a folder whose files no longer serve: init refuses to
/// overwrite it.
std::string RemakeAdvice() {
  return "run `haptel security init` again (into a new folder: it does not overwrite this one)";
}

struct BioFree {
  void operator()(BIO* b) const { BIO_free(b); }
};
struct Pkcs7Free {
  void operator()(PKCS7* p) const { PKCS7_free(p); }
};
struct StoreFree {
  void operator()(X509_STORE* s) const { X509_STORE_free(s); }
};

/// The content of `file`, an S/MIME document the CA `ca` signed, verified
/// as Fast DDS's Access-Permissions plugin verifies it (PKCS7_verify with the
/// CA as the only trusted certificate, text mode). Throws ConfigError naming
/// the file (`what`: "permissions file", "governance").
std::string SignedContent(const fs::path& file, const fs::path& ca, const std::string& what) {
  const std::unique_ptr<BIO, BioFree> in(BIO_new_file(file.c_str(), "r"));
  if (!in) throw ConfigError(what + " " + file.string() + ": cannot be read");
  BIO* content = nullptr;
  const std::unique_ptr<PKCS7, Pkcs7Free> p7(SMIME_read_PKCS7(in.get(), &content));
  const std::unique_ptr<BIO, BioFree> content_owner(content);
  if (!p7)
    throw ConfigError(what + " " + file.string() + " is not an S/MIME signed document; " +
                      RemakeAdvice());
  const std::unique_ptr<X509_STORE, StoreFree> store(X509_STORE_new());
  {
    const std::unique_ptr<BIO, BioFree> ca_in(BIO_new_file(ca.c_str(), "r"));
    X509* cert = ca_in ? PEM_read_bio_X509(ca_in.get(), nullptr, nullptr, nullptr) : nullptr;
    if (cert == nullptr)
      throw ConfigError("security: " + ca.string() + " is not a PEM certificate");
    X509_STORE_add_cert(store.get(), cert);
    X509_free(cert);  // the store holds its own reference
  }
  const std::unique_ptr<BIO, BioFree> out(BIO_new(BIO_s_mem()));
  if (PKCS7_verify(p7.get(), nullptr, store.get(), content, out.get(), PKCS7_TEXT) != 1) {
    throw ConfigError(
        what + " " + file.string() + " is not signed by this folder's CA (" + ca.string() +
        "): made by another `haptel security init`, or changed since; " + RemakeAdvice());
  }
  char* data = nullptr;
  const long size = BIO_get_mem_data(out.get(), &data);
  return std::string(data, static_cast<size_t>(std::max(0L, size)));
}

/// "2026-01-01T00:00:00Z"
std::string IsoUtc(std::time_t t) { return Iso(t) + "Z"; }

std::string Trimmed(const char* text) {
  std::string s = text != nullptr ? text : "";
  const auto space = [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; };
  while (!s.empty() && space(s.back())) s.pop_back();
  size_t at = 0;
  while (at < s.size() && space(s[at])) ++at;
  return s.substr(at);
}

/// One end of a grant's validity as Haptel writes it (UTC, no zone) and as
/// Fast DDS reads it (the same digits in this host's local time, std::mktime
/// without daylight saving): the file means the first, DDS enforces the
/// second, and the check refuses when either says no, so DDS never refuses
/// for a date left unnamed.
struct ValidityEnd {
  std::string text;        ///< as written
  std::time_t as_written;  ///< read as UTC
  std::time_t as_dds;      ///< read as Fast DDS reads it
};

ValidityEnd ReadValidityEnd(const fs::path& file, const tinyxml2::XMLElement* element,
                            const char* tag) {
  const tinyxml2::XMLElement* e = element != nullptr ? element->FirstChildElement(tag) : nullptr;
  const std::string text = Trimmed(e != nullptr ? e->GetText() : nullptr);
  std::tm tm{};
  std::istringstream in(text);
  in >> std::get_time(&tm, "%Y-%m-%dT%H:%M:%S");
  if (text.empty() || in.fail()) {
    throw ConfigError("permissions file " + file.string() + ": its validity's <" + tag + "> '" +
                      text + "' is not a date; expected YYYY-MM-DDThh:mm:ss (UTC); " +
                      RemakeAdvice());
  }
  std::tm local = tm;
  local.tm_isdst = 0;
  return {text, timegm(&tm), std::mktime(&local)};
}

/// Wording for the instant `t` at which one end takes effect, and how the
/// file wrote it when DDS reads it otherwise.
std::string When(std::time_t t, const ValidityEnd& end, const char* tag) {
  if (end.as_written == end.as_dds) return IsoUtc(t);
  return IsoUtc(t) + " (its <" + std::string(tag) + "> " + end.text +
         ", which DDS reads in this host's local time)";
}

/// The topics an identity publishes and subscribes to: what `haptel security
/// init` grants, and what the check asks of a folder made by an older
/// version (whose grants may lack a topic added since).
struct GrantedTopics {
  std::vector<std::string> publish;
  std::vector<std::string> subscribe;
};
GrantedTopics TopicsOf(const std::string& identity) {
  if (identity == OperatorIdentity()) {
    // The operator commands, asks for key frames and bitrates
    // (video_feedback) and says who drives (selected, a fleet's); a CAN
    // robot also says how its bus log fares (can_log); a vehicle with
    // several cameras says what they are (cameras) and streams each.
    return {{"haptel/*/command", "haptel/*/video_feedback", "haptel/*/selected"},
            {"haptel/*/state", "haptel/*/video", "haptel/*/selected", "haptel/*/can_log",
             "haptel/*/cameras", "haptel/*/video/*"}};
  }
  const std::string camera_prefix = CameraIdentity("");
  if (identity.rfind(camera_prefix, 0) == 0) {
    // A camera station steers that camera and asks its stream for key
    // frames and bitrates; it reads the vehicles' states, their cameras and
    // that camera's video. No driving topic: DDS refuses it a command writer.
    const std::string camera = identity.substr(camera_prefix.size());
    return {{"haptel/*/camera/" + camera, "haptel/*/video_feedback/" + camera},
            {"haptel/*/state", "haptel/*/cameras", "haptel/*/video/" + camera}};
  }
  const std::string name = identity.substr(VehicleIdentity("").size());
  return {{"haptel/" + name + "/state", "haptel/" + name + "/video", "haptel/" + name + "/can_log",
           "haptel/" + name + "/cameras", "haptel/" + name + "/video/*"},
          {"haptel/" + name + "/command", "haptel/" + name + "/video_feedback",
           "haptel/" + name + "/camera/*", "haptel/" + name + "/video_feedback/*"}};
}

/// The topic names listed under `rule`'s <`direction`><topics>.
std::vector<std::string> ListedTopics(const tinyxml2::XMLElement* rule, const char* direction) {
  std::vector<std::string> out;
  const tinyxml2::XMLElement* list = rule != nullptr ? rule->FirstChildElement(direction) : nullptr;
  list = list != nullptr ? list->FirstChildElement("topics") : nullptr;
  for (const tinyxml2::XMLElement* t = list != nullptr ? list->FirstChildElement("topic") : nullptr;
       t != nullptr; t = t->NextSiblingElement("topic")) {
    out.push_back(Trimmed(t->GetText()));
  }
  return out;
}

/// The permissions of `identity` in `file`: signed by the CA, holding a grant
/// for the identity's subject, valid now, and allowing every topic this
/// version uses (a folder made before a topic was added would otherwise be
/// refused by DDS when the topic is created, with no reason given).
void CheckPermissions(const fs::path& file, const fs::path& ca, const std::string& identity,
                      std::time_t now) {
  const std::string xml = SignedContent(file, ca, "permissions file");
  tinyxml2::XMLDocument doc;
  if (doc.Parse(xml.c_str(), xml.size()) != tinyxml2::XML_SUCCESS) {
    throw ConfigError("permissions file " + file.string() + ": its signed XML does not parse (" +
                      std::string(doc.ErrorStr()) + "); " + RemakeAdvice());
  }
  const tinyxml2::XMLElement* permissions =
      doc.FirstChildElement("dds") != nullptr
          ? doc.FirstChildElement("dds")->FirstChildElement("permissions")
          : nullptr;
  const std::string subject = Subject(identity);
  const tinyxml2::XMLElement* grant = nullptr;
  for (const tinyxml2::XMLElement* g =
           permissions != nullptr ? permissions->FirstChildElement("grant") : nullptr;
       g != nullptr && grant == nullptr; g = g->NextSiblingElement("grant")) {
    const tinyxml2::XMLElement* name = g->FirstChildElement("subject_name");
    if (name != nullptr && Trimmed(name->GetText()) == subject) grant = g;
  }
  if (grant == nullptr) {
    throw ConfigError("permissions file " + file.string() + " grants nothing to identity '" +
                      identity + "' (no <grant> with <subject_name>" + subject +
                      "</subject_name>); " + RemakeAdvice());
  }
  const tinyxml2::XMLElement* validity = grant->FirstChildElement("validity");
  const ValidityEnd not_before = ReadValidityEnd(file, validity, "not_before");
  const ValidityEnd not_after = ReadValidityEnd(file, validity, "not_after");
  const std::time_t begins = std::max(not_before.as_written, not_before.as_dds);
  const std::time_t ends = std::min(not_after.as_written, not_after.as_dds);
  if (now < begins) {
    throw ConfigError("permissions file " + file.string() + " is not valid before " +
                      When(begins, not_before, "not_before") + " (is this host's clock right?); " +
                      RemakeAdvice());
  }
  if (now > ends) {
    throw ConfigError("permissions file " + file.string() + " expired on " +
                      When(ends, not_after, "not_after") + "; " + RemakeAdvice());
  }
  const tinyxml2::XMLElement* rule = grant->FirstChildElement("allow_rule");
  const GrantedTopics needed = TopicsOf(identity);
  for (const auto& [direction, topics] :
       {std::pair<const char*, const std::vector<std::string>*>{"publish", &needed.publish},
        {"subscribe", &needed.subscribe}}) {
    const std::vector<std::string> listed = ListedTopics(rule, direction);
    for (const std::string& topic : *topics) {
      if (std::find(listed.begin(), listed.end(), topic) == listed.end()) {
        throw ConfigError("permissions file " + file.string() + " does not let identity '" +
                          identity + "' " + direction + " topic '" + topic +
                          "', which this version of Haptel uses (the folder was " +
                          "made by an older one); " + RemakeAdvice());
      }
    }
  }
}

}  // namespace

std::string OperatorIdentity() { return "operator"; }
std::string VehicleIdentity(const std::string& name) { return "vehicle-" + name; }
std::string CameraIdentity(const std::string& camera) { return "camera-" + camera; }

SecurityFiles SecurityFilesFor(const fs::path& dir, const std::string& identity) {
  return {dir / "ca.pem", dir / "governance.p7s", dir / (identity + ".pem"),
          dir / (identity + ".key"), dir / (identity + "-permissions.p7s")};
}

void CheckSecurity(const fs::path& dir, const std::string& identity) {
  if (!fs::is_directory(dir)) {
    throw ConfigError("security " + dir.string() +
                      ": no such folder; make it with `haptel security init " + dir.string() + "`");
  }
  const SecurityFiles f = SecurityFilesFor(dir, identity);
  for (const fs::path& file : {f.governance, f.private_key, f.permissions}) {
    if (!fs::exists(file)) {
      throw ConfigError("security " + dir.string() + ": no " + file.filename().string() +
                        " for identity '" + identity +
                        "'; `haptel security init` makes one for the operator, each vehicle it is "
                        "given (--vehicles) and each camera's stations (--cameras)");
    }
  }
  CheckValidNow(dir, f.ca);
  CheckValidNow(dir, f.certificate);
  // What DDS would otherwise refuse with no reason given ("DDS refused to
  // create participant"): documents another CA signed, and permissions
  // outside their validity.
  SignedContent(f.governance, f.ca, "governance");
  CheckPermissions(f.permissions, f.ca, identity, std::time(nullptr));
}

std::vector<std::pair<std::string, std::string>> SecurityProperties(const fs::path& dir,
                                                                    const std::string& identity) {
  const SecurityFiles f = SecurityFilesFor(fs::absolute(dir), identity);
  const auto file = [](const fs::path& p) {
    return "file://" + p.string();
  };  // file:// then an absolute path
  return {
      {"dds.sec.auth.plugin", "builtin.PKI-DH"},
      {"dds.sec.auth.builtin.PKI-DH.identity_ca", file(f.ca)},
      {"dds.sec.auth.builtin.PKI-DH.identity_certificate", file(f.certificate)},
      {"dds.sec.auth.builtin.PKI-DH.private_key", file(f.private_key)},
      {"dds.sec.access.plugin", "builtin.Access-Permissions"},
      {"dds.sec.access.builtin.Access-Permissions.permissions_ca", file(f.ca)},
      {"dds.sec.access.builtin.Access-Permissions.governance", file(f.governance)},
      {"dds.sec.access.builtin.Access-Permissions.permissions", file(f.permissions)},
      {"dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC"},
  };
}

std::string VehicleIdentityProblem(const std::string& name) {
  constexpr size_t kMaxCommonName = 64;  // X.520 ub-common-name
  const size_t most =
      kMaxCommonName - Subject(VehicleIdentity("")).size() + std::string("CN=").size();
  if (name.size() <= most) return "";
  return "a name of at most " + std::to_string(most) +
         " characters for a certificate (its common name 'haptel-" + VehicleIdentity("NAME") +
         "' holds at most " + std::to_string(kMaxCommonName) + "); '" + name + "' has " +
         std::to_string(name.size());
}

std::string CameraIdentityProblem(const std::string& camera) {
  constexpr size_t kMaxCommonName = 64;  // X.520 ub-common-name
  const size_t most =
      kMaxCommonName - Subject(CameraIdentity("")).size() + std::string("CN=").size();
  if (camera.empty() || camera.find_first_not_of(
                            "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_") !=
                            std::string::npos) {
    return "a camera's name of letters, digits, '-' and '_' (it is part of topic names); '" +
           camera + "' is not";
  }
  if (camera.size() <= most) return "";
  return "a camera's name of at most " + std::to_string(most) +
         " characters for a certificate (its common name 'haptel-" + CameraIdentity("NAME") +
         "' holds at most " + std::to_string(kMaxCommonName) + "); '" + camera + "' has " +
         std::to_string(camera.size());
}

std::string ConsoleNameProblem(const std::string& name) {
  in6_addr address{};
  if (inet_pton(AF_INET, name.c_str(), &address) == 1 ||
      inet_pton(AF_INET6, name.c_str(), &address) == 1)
    return "";
  const bool fits =
      !name.empty() && name.size() <= 253 && name.front() != '-' && name.front() != '.' &&
      name.find("..") == std::string::npos &&
      name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789.-") ==
          std::string::npos;
  return fits ? "" : "a host name (letters, digits, '-' and '.') or an IPv4 or IPv6 address";
}

namespace {

/// The console's HTTPS key and certificate (console.key, console.pem),
/// signed by the CA in `dir`, for `names` (subject alternative names).
void MakeConsoleFiles(const fs::path& dir, const std::vector<std::string>& names, int days) {
  std::string alternative = "subjectAltName=";
  for (size_t i = 0; i < names.size(); ++i) {
    in6_addr address{};
    const bool ip = inet_pton(AF_INET, names[i].c_str(), &address) == 1 ||
                    inet_pton(AF_INET6, names[i].c_str(), &address) == 1;
    if (i > 0) alternative += ',';
    alternative += ip ? "IP:" : "DNS:";
    alternative += names[i];
  }
  const fs::path extensions = dir / "console.ext";
  Write(extensions, alternative + "\nextendedKeyUsage=serverAuth\nbasicConstraints=CA:FALSE\n");
  const std::string csr = (dir / "console.csr").string();
  std::string subject = "/CN=haptel-console";
  OpenSsl(dir,
          {"req", "-new", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes",
           "-keyout", (dir / "console.key").string(), "-out", csr, "-subj", subject});
  fs::permissions(dir / "console.key", fs::perms::owner_read | fs::perms::owner_write);
  OpenSsl(dir,
          {"x509", "-req", "-in", csr, "-CA", (dir / "ca.pem").string(), "-CAkey",
           (dir / "ca.key").string(), "-CAcreateserial", "-days", std::to_string(days), "-sha256",
           "-extfile", extensions.string(), "-out", (dir / "console.pem").string()});
  fs::remove(csr);
  fs::remove(extensions);
}

void CheckConsoleNames(const std::vector<std::string>& names) {
  for (const std::string& name : names) {
    if (const std::string problem = ConsoleNameProblem(name); !problem.empty()) {
      throw std::invalid_argument("console name '" + name + "': expected " + problem);
    }
  }
}

}  // namespace

void AddConsoleCertificate(const fs::path& dir, const std::vector<std::string>& names, int days) {
  if (!fs::exists(dir / "ca.pem") || !fs::exists(dir / "ca.key")) {
    throw std::runtime_error(dir.string() +
                             " holds no CA (ca.pem, ca.key); make the folder with `haptel security "
                             "init " +
                             dir.string() + " --console NAME,...`");
  }
  if (fs::exists(dir / "console.pem")) {
    throw std::runtime_error(dir.string() +
                             " already holds the console's certificate (console.pem); nothing was "
                             "changed");
  }
  if (names.empty())
    throw std::invalid_argument("the console's certificate needs at least one name");
  CheckConsoleNames(names);
  MakeConsoleFiles(dir, names, days);
}

namespace {

/// Makes every file of a security folder in `dir` (which exists, empty).
void MakeSecurityFiles(const fs::path& dir, const std::vector<std::string>& vehicles,
                       const std::vector<std::string>& cameras,
                       const std::vector<std::string>& console_names, int days) {
  OpenSsl(dir, {"req", "-x509", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1",
                "-nodes", "-keyout", (dir / "ca.key").string(), "-out", (dir / "ca.pem").string(),
                "-days", std::to_string(days), "-sha256", "-subj", "/CN=haptel-ca"});
  fs::permissions(dir / "ca.key", fs::perms::owner_read | fs::perms::owner_write);
  Write(dir / "governance.xml", Governance());
  Sign(dir, "governance");
  const std::string op = OperatorIdentity();
  MakeIdentity(dir, op, days);
  Write(dir / (op + "-permissions.xml"),
        Permissions(op, TopicsOf(op).publish, TopicsOf(op).subscribe, days));
  Sign(dir, op + "-permissions");
  std::vector<std::string> identities;
  for (const std::string& name : vehicles) identities.push_back(VehicleIdentity(name));
  for (const std::string& camera : cameras) identities.push_back(CameraIdentity(camera));
  for (const std::string& id : identities) {
    MakeIdentity(dir, id, days);
    Write(dir / (id + "-permissions.xml"),
          Permissions(id, TopicsOf(id).publish, TopicsOf(id).subscribe, days));
    Sign(dir, id + "-permissions");
  }
  if (!console_names.empty()) MakeConsoleFiles(dir, console_names, days);
}

constexpr const char* kPartialPrefix = ".partial-";

/// Removes the folders ".partial-PID-NAME" in `parent` whose process is gone
/// (a `security init` killed mid-way: they hold a CA's private key), saying
/// each; those of a process still running are left to it.
void RemoveStalePartials(const fs::path& parent) {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(parent, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(kPartialPrefix, 0) != 0 || !entry.is_directory()) continue;
    const std::string rest = name.substr(std::char_traits<char>::length(kPartialPrefix));
    const size_t dash = rest.find('-');
    if (dash == 0 || dash == std::string::npos || rest.find_first_not_of("0123456789") != dash)
      continue;
    const long pid = std::stol(rest.substr(0, dash));
    if (pid <= 0 || pid == getpid() || kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH)
      continue;
    std::error_code removed;
    fs::remove_all(entry.path(), removed);
    if (removed) {
      log::Warn(
          "security init: " + entry.path().string() + " is left by process " + std::to_string(pid) +
          " (gone) and holds a CA's private key; it could not be removed: " + removed.message());
    } else {
      log::Info("security init: removed " + entry.path().string() + ", left by process " +
                std::to_string(pid) + " (killed while it made a CA)");
    }
  }
}

}  // namespace

std::string InitFolderProblem(const fs::path& dir) {
  std::error_code ec;
  if (!fs::exists(dir, ec)) return "";
  if (!fs::is_directory(dir, ec))
    return dir.string() + " is a file; expected a new or empty folder";
  if (fs::exists(dir / "ca.pem", ec)) {
    return dir.string() +
           " already holds a CA (ca.pem): nothing was changed; remove the folder or choose another";
  }
  if (!fs::is_empty(dir, ec)) {
    return dir.string() +
           " already holds other files: nothing was changed; expected a new or empty folder";
  }
  return "";
}

void InitSecurity(const fs::path& given, const std::vector<std::string>& vehicles, int days,
                  const std::vector<std::string>& console_names,
                  const std::vector<std::string>& cameras) {
  // "DIR/" and "." name the folder itself: without a trailing separator its
  // name is the last part (the partial folder is built beside it, not in it).
  fs::path dir = fs::absolute(given).lexically_normal();
  if (dir.filename().empty() && dir.has_parent_path() && dir != dir.root_path())
    dir = dir.parent_path();
  if (fs::exists(dir / "ca.pem")) {
    throw std::runtime_error(given.string() +
                             " already holds a CA (ca.pem); remove the folder or choose another");
  }
  if (const std::string problem = InitFolderProblem(given); !problem.empty())
    throw std::runtime_error(problem);
  for (const std::string& name : vehicles) {
    if (const std::string problem = VehicleIdentityProblem(name); !problem.empty()) {
      throw std::invalid_argument("vehicle '" + name + "': expected " + problem);
    }
  }
  for (const std::string& camera : cameras) {
    if (const std::string problem = CameraIdentityProblem(camera); !problem.empty()) {
      throw std::invalid_argument("camera '" + camera + "': expected " + problem);
    }
  }
  CheckConsoleNames(console_names);
  const fs::path parent = dir.parent_path();
  fs::create_directories(parent);
  RemoveStalePartials(parent);
  const fs::path partial =
      parent / (kPartialPrefix + std::to_string(getpid()) + "-" + dir.filename().string());
  fs::remove_all(partial);
  fs::create_directory(partial);
  try {
    MakeSecurityFiles(partial, vehicles, cameras, console_names, days);
    if (!fs::exists(dir)) {
      fs::rename(partial, dir);  // whole or not at all
    } else {
      // An empty folder that exists (perhaps the working directory, which
      // must stay the folder it is): filled file by file, ca.pem last, since
      // a folder with ca.pem is one that holds a CA.
      for (const auto& entry : fs::directory_iterator(partial)) {
        if (entry.path().filename() != "ca.pem")
          fs::rename(entry.path(), dir / entry.path().filename());
      }
      fs::rename(partial / "ca.pem", dir / "ca.pem");
      fs::remove(partial);
    }
  } catch (...) {
    std::error_code ignored;
    fs::remove_all(partial, ignored);
    throw;
  }
}

namespace {
/// A dotted IPv4 address in 127.0.0.0/8.
bool IsLoopback(const std::string& address) {
  in_addr a{};
  return inet_pton(AF_INET, address.c_str(), &a) == 1 && (ntohl(a.s_addr) >> 24) == 127;
}
}  // namespace

std::string LinkBeyondHost(const LinkConfig& config) {
  for (const std::string& a : config.interfaces) {
    if (!IsLoopback(a)) return "interface " + a;
  }
  for (const std::string& a : config.peers) {
    if (!IsLoopback(a)) return "peer " + a;
  }
  const std::string& server = config.discovery_server;
  if (!server.empty() && !IsLoopback(server.substr(0, server.find(':'))))
    return "discovery server " + server;
  return "";
}

std::string InsecureLinkWarning(const LinkConfig& config, bool insecure) {
  if (insecure || !config.security.empty()) return "";
  const std::string beyond = LinkBeyondHost(config);
  if (beyond.empty()) return "";
  return "the link reaches beyond this host (" + beyond +
         ") without DDS Security: a vehicle obeys one run's DDS writer at a time, which guards "
         "against "
         "mistakes, not attackers (anyone on the network can join the domain and forge a writer); "
         "--security DIR (haptel security init) keeps them off, --insecure silences this";
}

}  // namespace haptel::link
