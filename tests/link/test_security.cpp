// DDS Security on the link: the folder `haptel security init` makes, the
// check at start, and what it does on the wire: commands from a participant
// without certificates, from another CA, or without permission for the
// command topic never reach a vehicle; the operator's do, and no command
// payload crosses the wire in plain text (the fault transport's own capture
// of every packet received).
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/x509.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <thread>

#include "haptel/config/error.hpp"
#include "haptel/core/child_process.hpp"
#include "haptel/link/families.hpp"
#include "haptel/link/security.hpp"
#include "haptel/link/topic.hpp"
#include "test_env.hpp"

using namespace haptel;
namespace fs = std::filesystem;

namespace {

/// One security folder for the whole test program (openssl takes a moment).
const fs::path& Folder() {
  static const fs::path dir = [] {
    const fs::path d = test::ScratchDir("security") / "deployment";
    link::InitSecurity(d, {"robot1"}, 30, {}, {"surveillance"});
    return d;
  }();
  return dir;
}

/// A participant on `domain`, through the fault transport (so intra-process
/// delivery is off and every packet crosses the socket), with `security`
/// as `identity` (none when empty).
LinkConfig Link(int domain, const fs::path& security = {}, const std::string& identity = {}) {
  LinkConfig c;
  c.domain_id = domain;
  c.fault = ParseLinkFault("on");
  c.security = security;
  c.security_identity = identity;
  return c;
}

/// A vehicle's side: counts the commands that reach it. Secured as
/// vehicle-robot1 of the folder, or with `config`.
struct Vehicle {
  explicit Vehicle(int domain) : Vehicle(Link(domain, Folder(), link::VehicleIdentity("robot1"))) {}
  explicit Vehicle(const LinkConfig& config)
      : participant(config, "vehicle"),
        commands(participant, link::TopicName("robot1", "command"), link::Profile::kCommand,
                 [this](const msg::TreadCommand&) { received.fetch_add(1); }) {}
  link::Participant participant;
  std::atomic<int> received{0};
  link::TreadCommandReader commands;
};

/// Commands at 100 Hz from a participant made with `config`, for `seconds`
/// or, when `until` is given, until it holds (at most `seconds`): a secured
/// handshake takes its time on a loaded machine, and best-effort commands
/// sent before it ends are lost.
void Command(const LinkConfig& config, double seconds, const std::string& marker = "",
             const std::function<bool()>& until = nullptr) {
  link::Participant participant(config, "operator");
  link::TreadCommandWriter writer(participant, link::TopicName("robot1", "command"),
                                  link::Profile::kCommand);
  msg::TreadCommand m;
  m.left(0.25f);
  m.operator_name(marker);
  for (int i = 0; i < static_cast<int>(seconds * 100); ++i) {
    if (until && until()) return;
    m.seq(static_cast<uint64_t>(i + 1));
    writer.Write(m);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

/// Signs `xml` with the folder's CA into `p7s` (openssl smime, as init does).
void SignWithCa(const fs::path& xml, const fs::path& p7s) {
  ChildProcess openssl(
      "/usr/bin/openssl",
      {"smime", "-sign", "-text", "-in", xml.string(), "-out", p7s.string(), "-signer",
       (Folder() / "ca.pem").string(), "-inkey", (Folder() / "ca.key").string()},
      ChildProcess::Options{true});
  REQUIRE(openssl.Wait(60.0) == 0);
}

/// A self-signed certificate that expired yesterday, written to `file`.
void WriteExpiredCertificate(const fs::path& file) {
  EVP_PKEY* key = EVP_EC_gen("P-256");
  REQUIRE(key != nullptr);
  X509* cert = X509_new();
  X509_set_version(cert, 2);
  X509_gmtime_adj(X509_getm_notBefore(cert), -2 * 86400L);
  X509_gmtime_adj(X509_getm_notAfter(cert), -1 * 86400L);
  X509_set_pubkey(cert, key);
  X509_NAME* name = X509_get_subject_name(cert);
  X509_NAME_add_entry_by_txt(name, "CN", MBSTRING_ASC,
                             reinterpret_cast<const unsigned char*>("haptel-operator"), -1, -1, 0);
  X509_set_issuer_name(cert, name);
  REQUIRE(X509_sign(cert, key, EVP_sha256()) > 0);
  FILE* out = std::fopen(file.c_str(), "w");
  REQUIRE(out != nullptr);
  PEM_write_X509(out, cert);
  std::fclose(out);
  X509_free(cert);
  EVP_PKEY_free(key);
}

/// A copy of the deployment's operator files in a folder of its own, its
/// permissions re-signed by the CA after `edit` (the text's `of` replaced
/// by `with`), as init signs them.
fs::path OperatorWithPermissions(const std::string& name, const std::string& of,
                                 const std::string& with) {
  const fs::path dir = test::ScratchDir(name);
  for (const char* file : {"ca.pem", "governance.p7s", "operator.pem", "operator.key"}) {
    fs::copy_file(Folder() / file, dir / file, fs::copy_options::overwrite_existing);
  }
  std::ifstream in(Folder() / "operator-permissions.xml");
  std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t at = xml.find(of);
  REQUIRE(at != std::string::npos);
  const size_t end = xml.find('<', at + of.size());  // the element's text ends at the next tag
  xml.replace(at, end - at, with);
  std::ofstream(dir / "operator-permissions.xml") << xml;
  SignWithCa(dir / "operator-permissions.xml", dir / "operator-permissions.p7s");
  return dir;
}

/// Runs `body` with TZ set to `zone` (a POSIX zone string), then restores it.
template <typename Body>
void InZone(const char* zone, Body body) {
  const char* old = std::getenv("TZ");
  const std::string saved = old != nullptr ? old : "";
  ::setenv("TZ", zone, 1);
  ::tzset();
  body();
  if (old != nullptr) {
    ::setenv("TZ", saved.c_str(), 1);
  } else {
    ::unsetenv("TZ");
  }
  ::tzset();
}

std::string CheckMessage(const fs::path& dir, const std::string& identity) {
  try {
    link::CheckSecurity(dir, identity);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "valid";
}

}  // namespace

TEST_CASE(
    "security init: a CA, the identities and signed documents; the check names what is missing or "
    "expired") {
  const fs::path& dir = Folder();
  for (const char* file : {"ca.pem", "governance.p7s", "operator.pem", "operator.key",
                           "operator-permissions.p7s", "vehicle-robot1.pem", "vehicle-robot1.key",
                           "vehicle-robot1-permissions.p7s", "camera-surveillance.pem",
                           "camera-surveillance.key", "camera-surveillance-permissions.p7s"}) {
    CHECK(fs::exists(dir / file));
  }
  CHECK(CheckMessage(dir, "operator") == "valid");
  CHECK(CheckMessage(dir, link::VehicleIdentity("robot1")) == "valid");
  CHECK(CheckMessage(dir, link::CameraIdentity("surveillance")) == "valid");
  CHECK(CheckMessage(dir, link::CameraIdentity("rear")).find("(--cameras)") != std::string::npos);
  CHECK_THAT(link::CameraIdentityProblem("rear/up"), Catch::Contains("letters, digits"));
  CHECK(link::CameraIdentityProblem("rear-1").empty());
  CHECK(CheckMessage(dir, link::VehicleIdentity("blimp9"))
            .find("no vehicle-blimp9.key for identity 'vehicle-blimp9'") != std::string::npos);
  CHECK(CheckMessage(dir / "nowhere", "operator").find("no such folder") != std::string::npos);
  // Nothing is overwritten.
  CHECK_THROWS_WITH(link::InitSecurity(dir, {"robot1"}, 30), Catch::Contains("already holds a CA"));

  // A name no certificate can hold is refused before anything is made, and
  // nothing is left to block the retry with names that fit.
  const fs::path fresh = test::ScratchDir("security-names") / "deployment";
  const std::string long_name(50, 'v');
  CHECK(link::VehicleIdentityProblem(std::string(49, 'v')).empty());
  CHECK_THAT(link::VehicleIdentityProblem(long_name),
             Catch::Contains("at most 49") && Catch::Contains("64"));
  CHECK_THROWS_WITH(link::InitSecurity(fresh, {"robot1", long_name}, 30),
                    Catch::Contains("at most 49"));
  CHECK_FALSE(fs::exists(fresh));
  CHECK(fs::is_empty(fresh.parent_path()));  // no half-made folder beside it either
  link::InitSecurity(fresh, {"robot1", std::string(49, 'v')}, 30);
  CHECK(CheckMessage(fresh, link::VehicleIdentity(std::string(49, 'v'))) == "valid");
  // A folder holding other files is not written into.
  const fs::path busy = test::ScratchDir("security-busy");
  test::WriteFile(busy / "notes.txt", "mine");
  CHECK_THROWS_WITH(link::InitSecurity(busy, {"robot1"}, 30),
                    Catch::Contains("already holds other files"));
  CHECK_FALSE(fs::exists(busy / "ca.pem"));

  // An expired certificate is named with the day it expired.
  const fs::path expired = test::ScratchDir("security-expired");
  for (const char* file :
       {"ca.pem", "governance.p7s", "operator.key", "operator-permissions.p7s"}) {
    fs::copy_file(dir / file, expired / file, fs::copy_options::overwrite_existing);
  }
  WriteExpiredCertificate(expired / "operator.pem");
  const std::string message = CheckMessage(expired, "operator");
  CHECK(message.find("certificate operator.pem expired on") != std::string::npos);
  CHECK(message.find("haptel security init") != std::string::npos);
}

TEST_CASE(
    "permissions out of their validity, or signed by another CA, are named before any participant "
    "exists") {
  SECTION("expired: the file and the day, not DDS's unexplained refusal") {
    const fs::path dir = OperatorWithPermissions("security-expired-permissions", "<not_after>",
                                                 "<not_after>2020-01-01T00:00:00");
    const std::string file = (dir / "operator-permissions.p7s").string();
    InZone("UTC0", [&] {
      CHECK(CheckMessage(dir, "operator") ==
            "permissions file " + file +
                " expired on 2020-01-01T00:00:00Z; run `haptel security init` "
                "again (into a new folder: it does not overwrite this one)");
      // The participant is refused with the same line, before DDS is asked.
      CHECK_THROWS_WITH(
          link::Participant(Link(test::UniqueDomain(63), dir, link::OperatorIdentity()),
                            "operator"),
          Catch::Contains("permissions file " + file + " expired on 2020-01-01T00:00:00Z"));
    });
    // Fast DDS reads the date in local time: an hour east of UTC it ends an hour sooner, and the
    // check says so.
    InZone("XYZ-1", [&] {
      CHECK_THAT(
          CheckMessage(dir, "operator"),
          Catch::Contains(
              "expired on 2019-12-31T23:00:00Z (its <not_after> 2020-01-01T00:00:00, which DDS "
              "reads in this host's local time)"));
    });
  }
  SECTION("not yet valid") {
    const fs::path dir = OperatorWithPermissions("security-future-permissions", "<not_before>",
                                                 "<not_before>2090-06-01T12:00:00");
    InZone("UTC0", [&] {
      CHECK_THAT(CheckMessage(dir, "operator"),
                 Catch::StartsWith(
                     "permissions file " + (dir / "operator-permissions.p7s").string() +
                     " is not valid before 2090-06-01T12:00:00Z (is this host's clock right?)"));
    });
  }
  SECTION("a date that is not one") {
    const fs::path dir =
        OperatorWithPermissions("security-bad-date", "<not_after>", "<not_after>next year");
    CHECK_THAT(
        CheckMessage(dir, "operator"),
        Catch::Contains("<not_after> 'next year' is not a date; expected YYYY-MM-DDThh:mm:ss"));
  }
  SECTION("a grant for another identity") {
    const fs::path dir = OperatorWithPermissions("security-other-subject", "<subject_name>",
                                                 "<subject_name>CN=haptel-someone");
    CHECK_THAT(CheckMessage(dir, "operator"),
               Catch::Contains("grants nothing to identity 'operator'") &&
                   Catch::Contains("CN=haptel-operator"));
  }
  SECTION("a folder made before a topic was added: the topic named, and what to do") {
    // An older version's grant: video_feedback was not among the operator's
    // topics (here the command topic stands twice in its place).
    const fs::path dir = OperatorWithPermissions("security-old-topics", "haptel/*/video_feedback",
                                                 "haptel/*/command");
    CHECK(CheckMessage(dir, "operator") == "permissions file " +
                                               (dir / "operator-permissions.p7s").string() +
                                               " does not let identity 'operator' publish topic "
                                               "'haptel/*/video_feedback', which this version of "
                                               "Haptel uses (the folder was made by an older one); "
                                               "run `haptel security init` again (into a new "
                                               "folder: it does not overwrite this one)");
  }
  SECTION("permissions another CA signed, or changed since they were signed") {
    const fs::path dir = OperatorWithPermissions("security-foreign-permissions", "<not_after>",
                                                 "<not_after>2090-01-01T00:00:00");
    const auto openssl = [](const std::vector<std::string>& arguments) {
      ChildProcess p("/usr/bin/openssl", arguments, ChildProcess::Options{true});
      REQUIRE(p.Wait(60.0) == 0);
    };
    SECTION("another CA") {
      openssl({"req", "-x509", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1",
               "-nodes", "-keyout", (dir / "other-ca.key").string(), "-out",
               (dir / "other-ca.pem").string(), "-days", "30", "-subj", "/CN=haptel-ca"});
      openssl({"smime", "-sign", "-text", "-in", (dir / "operator-permissions.xml").string(),
               "-out", (dir / "operator-permissions.p7s").string(), "-signer",
               (dir / "other-ca.pem").string(), "-inkey", (dir / "other-ca.key").string()});
    }
    SECTION("changed since signing") {
      std::ifstream in(dir / "operator-permissions.p7s");
      std::string p7s((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      in.close();
      const size_t at = p7s.find("2090-01-01");
      REQUIRE(at != std::string::npos);
      p7s.replace(at, 4, "2099");
      std::ofstream(dir / "operator-permissions.p7s") << p7s;
    }
    CHECK_THAT(
        CheckMessage(dir, "operator"),
        Catch::Contains("permissions file " + (dir / "operator-permissions.p7s").string() +
                        " is not signed by this folder's CA (" + (dir / "ca.pem").string() + ")"));
  }
}

TEST_CASE(
    "secured: only the operator's commands reach the vehicle; no certificates, another CA or no "
    "permission: none") {
  const int domain = test::UniqueDomain(61);
  Vehicle vehicle(domain);
  SECTION("a participant without certificates") { Command(Link(domain), 3.0); }
  SECTION("an operator whose certificates come from another CA") {
    const fs::path other = test::ScratchDir("security-other") / "deployment";
    if (!fs::exists(other / "ca.pem")) link::InitSecurity(other, {"robot1"}, 30);
    Command(Link(domain, other, link::OperatorIdentity()), 3.0);
  }
  SECTION("a vehicle's identity trying to command: its grant does not cover the command topic") {
    // Its documents are valid (the check passes), so DDS's access control
    // is what refuses: the participant starts but may not write commands.
    try {
      Command(Link(domain, Folder(), link::VehicleIdentity("robot1")), 3.0);
    } catch (const std::runtime_error& e) {
      CHECK(std::string(e.what()).find("cannot create writer") != std::string::npos);
    }
  }
  CHECK(vehicle.received.load() == 0);
  // The control: the deployment's own operator is heard.
  Command(Link(domain, Folder(), link::OperatorIdentity()), 60.0, "",
          [&] { return vehicle.received.load() > 0; });
  CHECK(vehicle.received.load() > 0);
}

TEST_CASE(
    "secured: a camera station (identity camera-surveillance) steers its camera; its driving "
    "commands and another camera's never reach the vehicle") {
  const int domain = test::UniqueDomain(64);
  Vehicle vehicle(domain);  // vehicle-robot1: reads its driving commands
  std::atomic<int> steered{0};
  std::atomic<int> other_camera{0};
  link::CameraCommandReader surveillance(
      vehicle.participant, link::CameraCommandTopic("robot1", "surveillance"),
      link::Profile::kCommand, [&](const msg::CameraCommand&) { steered.fetch_add(1); });
  link::CameraCommandReader rear(vehicle.participant, link::CameraCommandTopic("robot1", "rear"),
                                 link::Profile::kCommand,
                                 [&](const msg::CameraCommand&) { other_camera.fetch_add(1); });
  const LinkConfig station = Link(domain, Folder(), link::CameraIdentity("surveillance"));
  // Driving: DDS's access control refuses the writer (or, at the least,
  // delivers nothing it writes).
  try {
    Command(station, 3.0);
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()).find("cannot create writer") != std::string::npos);
  }
  link::Participant participant(station, "station");
  const auto steer = [&](const std::string& camera, const std::function<bool()>& until,
                         double seconds) {
    std::unique_ptr<link::CameraCommandWriter> writer;
    try {
      writer = std::make_unique<link::CameraCommandWriter>(
          participant, link::CameraCommandTopic("robot1", camera), link::Profile::kCommand);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    msg::CameraCommand m;
    m.camera(camera);
    m.zoom(2.0f);
    for (int i = 0; i < static_cast<int>(seconds * 100) && !(until && until()); ++i) {
      m.seq(static_cast<uint64_t>(i + 1));
      writer->Write(m);
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return std::string("written");
  };
  const std::string rear_writer = steer("rear", nullptr, 2.0);
  INFO(rear_writer);
  CHECK(
      (rear_writer == "written" || rear_writer.find("cannot create writer") != std::string::npos));
  CHECK(steer(
            "surveillance", [&] { return steered.load() > 0; }, 60.0) == "written");
  CHECK(steered.load() > 0);
  CHECK(other_camera.load() == 0);
  CHECK(vehicle.received.load() == 0);
}

TEST_CASE("secured: no command payload crosses the wire in plain text (without security it does)") {
  const std::string marker = "PLAINTEXT-MARKER-4242";
  const auto payload_seen = [&](bool secured) {
    const int domain = test::UniqueDomain(62);
    Vehicle vehicle(secured ? Link(domain, Folder(), link::VehicleIdentity("robot1"))
                            : Link(domain));
    link::FaultLine* line = vehicle.participant.fault_line();
    REQUIRE(line != nullptr);
    line->CaptureReceived(100000);
    // Commands until some have arrived, then a second more of them: what was
    // captured is what carried them.
    const LinkConfig sender =
        secured ? Link(domain, Folder(), link::OperatorIdentity()) : Link(domain);
    Command(sender, 60.0, marker, [&] { return vehicle.received.load() > 0; });
    CHECK(vehicle.received.load() > 0);
    Command(sender, 1.0, marker);
    int with_marker = 0;
    const auto packets = line->TakeCaptured();
    CHECK(packets.size() > 50);
    for (const auto& p : packets) {
      if (std::search(p.begin(), p.end(), marker.begin(), marker.end()) != p.end()) ++with_marker;
    }
    return with_marker;
  };
  CHECK(payload_seen(false) > 0);
  CHECK(payload_seen(true) == 0);
}

TEST_CASE(
    "security init: DIR/, '.' and an empty folder are filled; a dead run's partial folder is "
    "cleaned (issue 41)") {
  const fs::path root = test::ScratchDir("security-init-paths");
  // "DIR/": it said "filesystem error ... Directory not empty" and left DIR empty.
  const fs::path slash = root / "slash";
  link::InitSecurity(slash.string() + "/", {"robot1"}, 30);
  CHECK(fs::exists(slash / "ca.pem"));
  CHECK(fs::exists(slash / "vehicle-robot1.pem"));
  // An empty folder that exists, named as ".".
  const fs::path here = root / "here";
  fs::create_directory(here);
  const fs::path before = fs::current_path();
  fs::current_path(here);
  std::string error;
  try {
    link::InitSecurity(".", {"robot1"}, 30);
  } catch (const std::exception& e) {
    error = e.what();
  }
  fs::current_path(before);
  CHECK(error.empty());
  CHECK(fs::exists(here / "ca.pem"));
  CHECK(fs::exists(here / "operator.pem"));
  for (const auto& entry : fs::directory_iterator(root)) {
    CHECK(entry.path().filename().string().rfind(".partial-", 0) != 0);  // nothing left beside
  }
  // A kill -9 mid-way left ".partial-PID-NAME" holding ca.key for good: the
  // next run removes those of processes that are gone.
  const pid_t dead = fork();
  if (dead == 0) _exit(0);
  REQUIRE(dead > 0);
  waitpid(dead, nullptr, 0);
  const fs::path stale = root / (".partial-" + std::to_string(dead) + "-other");
  fs::create_directory(stale);
  test::WriteFile(stale / "ca.key", "secret");
  link::InitSecurity(root / "next", {"robot1"}, 30);
  CHECK_FALSE(fs::exists(stale));
  CHECK(fs::exists(root / "next" / "ca.pem"));
}
