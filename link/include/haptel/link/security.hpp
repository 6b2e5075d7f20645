#pragma once
/// @file DDS Security for the link (Fast DDS's builtin plugins: PKI-DH
/// authentication, Access-Permissions, AES-GCM-GMAC encryption): the folder
/// `haptel security init` makes, the check a process runs on it at start,
/// and the participant properties that turn it on.
///
/// One folder holds one deployment: a CA that signs every identity and the
/// documents, the signed governance (everything authenticated and
/// encrypted: discovery, liveliness, metadata and data), and per identity a
/// certificate, its key and signed permissions. The operator may publish
/// commands and read states and video of any vehicle; vehicle NAME may
/// publish only its own state, video and cameras and read only its own
/// commands (the driving one and its cameras'); camera station CAMERA
/// (`haptel station --camera CAMERA`) may publish only the camera command
/// of a camera of that name (haptel/*/camera/CAMERA) and read the states,
/// the cameras' status and that camera's video: never a driving command,
/// which DDS itself refuses it. Anything else is denied.
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "haptel/config/link.hpp"

namespace haptel::link {

/// The identity of the operator's side (every `haptel run`).
std::string OperatorIdentity();
/// The identity of vehicle `name` ("vehicle-robot1").
std::string VehicleIdentity(const std::string& name);
/// The identity of the camera stations that steer cameras named `camera`
/// ("camera-surveillance"), on any vehicle.
std::string CameraIdentity(const std::string& camera);

/// The files of `identity` in security folder `dir`.
struct SecurityFiles {
  std::filesystem::path ca;           ///< ca.pem: identity and permissions CA
  std::filesystem::path governance;   ///< governance.p7s (S/MIME, signed by the CA)
  std::filesystem::path certificate;  ///< IDENTITY.pem
  std::filesystem::path private_key;  ///< IDENTITY.key
  std::filesystem::path permissions;  ///< IDENTITY-permissions.p7s
};
SecurityFiles SecurityFilesFor(const std::filesystem::path& dir, const std::string& identity);

/// At start, before any participant exists: every file of `identity` is
/// there; the CA's and the identity's certificates are valid now; the
/// governance and the identity's permissions are signed by the folder's CA
/// (verified as Fast DDS verifies them); the permissions hold a grant for
/// the identity, valid now (its <validity> read both as written, UTC, and
/// as Fast DDS reads it, local time: either saying no refuses). Throws
/// ConfigError naming the folder or the file, the date, and what to do (a
/// missing identity: `haptel security init` with it; an expired or not yet
/// valid certificate or permissions file: when, e.g. "permissions file
/// DIR/operator-permissions.p7s expired on 2026-01-01T00:00:00Z; run
/// `haptel security init` again (into a new folder ...)") — instead of DDS's
/// unexplained "refused to create participant".
void CheckSecurity(const std::filesystem::path& dir, const std::string& identity);

/// The Fast DDS participant properties for `identity` in `dir`.
std::vector<std::pair<std::string, std::string>> SecurityProperties(
    const std::filesystem::path& dir, const std::string& identity);

/// What a vehicle name lacks for a certificate, as the "expected …" part of
/// an error ("" when it fits): its identity's common name
/// "haptel-vehicle-NAME" holds at most 64 characters (X.520), so the name at
/// most 49.
std::string VehicleIdentityProblem(const std::string& name);
/// The same for a camera's name (its identity "haptel-camera-NAME"); also
/// "" only for letters, digits, '-' and '_' (it is part of topic names).
std::string CameraIdentityProblem(const std::string& camera);

/// Why `dir` cannot be made by InitSecurity, "" when it can: a file, a
/// folder holding a CA (ca.pem) or any other file. Nothing is changed.
std::string InitFolderProblem(const std::filesystem::path& dir);

/// `haptel security init DIR`: creates the CA, the operator's identity,
/// one for each of `vehicles` and one for the stations of each of
/// `cameras` (CameraIdentity), the governance and each identity's
/// permissions, all signed, with the `openssl` program; valid for `days`.
/// Refuses a folder that already holds a CA (nothing is overwritten), one
/// that holds other files, and names a certificate cannot hold
/// (std::invalid_argument), before anything is made. The folder is built
/// beside `dir` and renamed into place when complete: a step that fails
/// leaves nothing behind to block a retry. Throws std::runtime_error with
/// openssl's message when a step fails.
///
/// `dir` may end in a separator, or be "." or any existing empty folder,
/// which is filled (ca.pem last). Folders ".partial-PID-NAME" beside it left
/// by a `security init` that was killed (its process gone) are removed, and
/// said: they hold a CA's private key.
///
/// With `console_names`, also the experimenter's console's HTTPS key and
/// certificate (console.key, console.pem), signed by the same CA, for those
/// host names and addresses (AddConsoleCertificate).
void InitSecurity(const std::filesystem::path& dir, const std::vector<std::string>& vehicles,
                  int days, const std::vector<std::string>& console_names = {},
                  const std::vector<std::string>& cameras = {});

/// `haptel security console DIR --names NAME,...`: the console's HTTPS key
/// and certificate (console.key, console.pem) in an existing folder, signed
/// by its CA, for `names` (the host names and addresses the experimenter's
/// browser uses; they become the certificate's subject alternative names).
/// Throws std::runtime_error when DIR holds no CA or already a console
/// certificate (nothing is changed), std::invalid_argument for a name that
/// is neither a host name nor an address.
void AddConsoleCertificate(const std::filesystem::path& dir, const std::vector<std::string>& names,
                           int days);

/// What a console name lacks ("" when it is a host name or an IP address).
std::string ConsoleNameProblem(const std::string& name);

/// Where `config`'s link reaches beyond this host: the first of its
/// interfaces, peers and discovery server whose address is not loopback
/// (127.0.0.0/8), named ("interface 10.0.0.2", "discovery server
/// 10.0.0.9:11811"); "" when every one is loopback: DDS then sends nothing
/// beyond the host (its UDP is held to the interfaces; shared memory never
/// leaves it).
std::string LinkBeyondHost(const LinkConfig& config);

/// The one line a run starting on `config` says when its link reaches
/// beyond the host without DDS Security: who drives a vehicle is then
/// bound to DDS's writer identity, which nobody claims by mistake but an
/// attacker on the network can forge. "" when the link stays on the host,
/// is secured (`config.security`), or `insecure` (--insecure) silences it.
std::string InsecureLinkWarning(const LinkConfig& config, bool insecure);

}  // namespace haptel::link
