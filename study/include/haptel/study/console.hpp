#pragma once
/// @file The experimenter's console: a web page served by `haptel study run`
/// (cpp-httplib; plain HTML, no JavaScript needed). It shows the schedule
/// (each participant's conditions in their order, with the trials'
/// results), the live trial, and the questionnaire forms a participant fills
/// in after each condition; submissions go through SubmitAnswers (checked,
/// in order, never twice).
///
/// It listens on 127.0.0.1 unless told otherwise, and defends itself as a
/// web application (console_access.hpp): requests addressed to another Host
/// are refused, so are state-changing requests from another site (Origin,
/// Sec-Fetch-Site, a per-console token in every form); bodies are bounded
/// before they are read; every connection has one deadline and one address
/// holds a bounded number of them. Beyond loopback it serves HTTPS with a
/// certificate `haptel security init DIR --console NAME` makes, and the page
/// asks once for an access token.
///
/// Routes: `GET /` the schedule (each trial's device); `GET
/// /questionnaire?participant=P&condition=C&name=Q` a form; `POST /answers` a
/// filled-in form; `POST /start` starts the trial offered (refused, saying
/// what is missing, while its device is not there); `POST /abort` aborts the trial under way (it is
/// run again); `POST /redo` (participant, position) takes a finished trial back, to be run again;
/// `POST /notes` (participant, position, text) one of the experimenter's notes on a trial
/// (SubmitNote; position 0: on the participant as a whole), from the schedule's rows or the trial
/// under way; `POST /participants` (id) adds a participant, planned by the design; `POST /finish`
/// ends an open study (one whose file lists no participants); `GET /video.jpg` the vehicle's latest
/// camera picture (the thumbnail); `GET /status.json` the counts, the live trial (`live_message`:
/// the participant's screen's line), the next and its
/// device
/// (`next_device`, and `device_missing`: what is missing, "" when it is there),
/// what is awaited;
/// `GET|POST /login` the access token's form (beyond loopback).
#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "haptel/config/study.hpp"
#include "haptel/study/questionnaire.hpp"
#include "haptel/study/store.hpp"

namespace haptel::study {

/// The console cannot serve (its port is taken, the address is wrong).
class ConsoleError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// How long and how many connections: the defaults hold a browser's page,
/// its thumbnail and a form, from any link that carries video, with room to
/// spare, while a hundred slow or silent connections wait (slowloris): a
/// connection must send its request's head soon after it opens, and the
/// slowest are cut to make room for new ones, so that a client that sends
/// its request at once (the experimenter's browser) is always served.
struct ConnectionPolicy {
  /// Connections one address may hold at once. A new one past it is still
  /// taken: the address's oldest connection that has not yet sent its
  /// request's head is cut instead (one that has is being answered: then
  /// the new one is answered 503 and closed). A browser opens at most 6 to
  /// one host.
  int max_per_client = 16;
  /// From accept to the end of the request's head (its blank line; the TLS
  /// handshake included): a client that sends nothing, or its head a byte
  /// at a time, is cut here.
  std::chrono::milliseconds head_deadline{3000};
  /// From accept to the last byte of the answer, for the whole exchange: a
  /// client sending its body, or reading the answer, a byte every few
  /// seconds is cut off here.
  std::chrono::milliseconds deadline{10000};
  /// Silence from the client that ends the connection, within the deadlines.
  std::chrono::milliseconds idle{2000};
  /// Worker threads, one per connection being read or answered, at most.
  /// When every one is taken, the oldest connection still without its head
  /// is cut for the new one.
  size_t threads = 128;
  /// Workers are started as connections come and end after this long idle,
  /// so that a burst leaves no threads behind (a trial's servo loop locks
  /// every thread's stack into memory).
  std::chrono::milliseconds worker_linger{5000};

  /// Throws std::invalid_argument naming the field that is out of range.
  void ValidateOrThrow() const;
};

/// What the connection policy did (in `GET /status.json` as `connections`).
struct ConnectionCounters {
  uint64_t served = 0;        ///< connections that reached the request parser
  uint64_t refused_busy = 0;  ///< over `max_per_client`, none to cut: 503 and closed
  uint64_t cut_deadline = 0;  ///< ended at a deadline or after `idle`
  uint64_t cut_for_room = 0;  ///< cut before its head to make room (`max_per_client`, `threads`)
  uint64_t tls_failed = 0;    ///< TLS handshakes that did not complete
  size_t workers = 0;  ///< worker threads now (idle ones end, ConnectionPolicy::worker_linger)
  uint64_t refused_requests = 0;  ///< refused by the access checks (403, 401, 413)
};

struct ConsoleOptions {
  /// The address to listen on. Beyond loopback the page asks for an access
  /// token, and HTTPS is required unless `plain_http` says otherwise.
  std::string host = "127.0.0.1";
  int port = 8470;  ///< 0: any free port (tests)
  /// Show the vehicle's camera (SetPicture, from the trial's session).
  bool thumbnail = false;
  /// HTTPS: a PEM certificate (chain) and its key. Empty: plain HTTP.
  std::filesystem::path tls_certificate;
  std::filesystem::path tls_key;
  /// Beyond loopback without HTTPS: the access token crosses the network in
  /// clear. Only for a network the experimenter trusts.
  bool plain_http = false;
  /// Further names the page is reached by (the certificate's names).
  std::vector<std::string> names;
  /// Given: the access token (tests); empty: a random one beyond loopback.
  std::string access_token;
  ConnectionPolicy connections;
};

/// The console's HTTPS certificate in a security folder.
struct ConsoleCertificate {
  std::filesystem::path certificate;  ///< DIR/console.pem
  std::filesystem::path key;          ///< DIR/console.key
  std::vector<std::string> names;     ///< its subject alternative names (DNS names, addresses)
};

/// DIR/console.pem and DIR/console.key, with the names the certificate is
/// for. Throws ConsoleError naming the file and how to make it (`haptel
/// security init DIR --console NAME`) when one is missing, unreadable, or
/// the certificate is not valid now.
ConsoleCertificate FindConsoleCertificate(const std::filesystem::path& dir);

/// The live trial as the page shows it, beside its title line.
struct LiveProgress {
  double lap_time_s = 0.0;
  int gates_passed = 0;
  int gates_total = 0;
  int obstacles = 0;
  std::string last_contact;  ///< e.g. "left bumper at 12.3 s"
  /// The line the participant's screen shows them now (view::Overlay's
  /// message, e.g. "Not engaged - bring the hand back to neutral (zero
  /// command) to drive"): why the vehicle does not move; empty: none.
  std::string message;
};

/// The input device a trial is driven with, as the console shows and checks
/// it before the experimenter may start the trial.
struct TrialDevice {
  std::string name;            ///< the device file's name ("mouse"); empty: none to show
  std::filesystem::path file;  ///< its file
  /// "" when the device is there to be opened now, else what is missing
  /// (haptics::DeviceUnavailable: "no display...", "no joystick..."). Asked
  /// when the page is drawn and when Start is pressed. Empty: always there.
  std::function<std::string()> unavailable;
};

class StudyConsole {
 public:
  /// Opens its own connection to `database` (the study must be planned there
  /// already) and serves from threads of its own. Throws ConsoleError naming
  /// the address when it cannot bind ("port 8470 on 127.0.0.1 is in use").
  StudyConsole(const StudyConfig& config, const std::vector<PlannedTrial>& plan,
               const std::filesystem::path& database,
               const std::map<std::string, Questionnaire>& questionnaires,
               const ConsoleOptions& options);
  ~StudyConsole();
  StudyConsole(const StudyConsole&) = delete;
  StudyConsole& operator=(const StudyConsole&) = delete;

  int port() const;
  /// The addresses the experimenter's browser can open (ConsoleUrls): e.g.
  /// "http://127.0.0.1:8470/"; bound to every interface (0.0.0.0), the
  /// host's name and addresses, and 127.0.0.1, never "0.0.0.0".
  std::vector<std::string> urls() const;
  /// The first of urls().
  std::string url() const;
  /// Whether the study was planned in the database before this console
  /// opened it (false: the console planned it).
  bool resumed() const;
  /// What the page asks for beyond loopback (empty on loopback).
  const std::string& access_token() const;
  ConnectionCounters connection_counters() const;
  /// The line the page shows for the trial under way (empty: none); clears
  /// the progress. `participant` and `position` name it for the page's note
  /// form (position 0: their practice lap; no participant: no form).
  void SetLive(const std::string& text, const std::string& participant = "", int position = 0);
  /// The lap clock, gates and contacts of the trial under way.
  void SetLiveProgress(const LiveProgress& progress);
  /// What the study waits for before the next trial (empty: nothing), e.g.
  /// "participant A's questionnaires after gesture".
  void SetWaiting(const std::string& text);
  /// Offers `next` with a Start button and blocks until the experimenter
  /// presses it (true) or `stop` is set (false). Clears a previous abort.
  /// The page names the device the trial is driven with (`device`), and a
  /// Start while its `unavailable` says something is missing is refused,
  /// that line on the page.
  bool WaitForStart(const std::string& next, const std::atomic<bool>& stop,
                    const TrialDevice& device = {});
  /// Set by the page's Abort button during a trial.
  const std::atomic<bool>& abort_requested() const;
  /// Whether Abort was pressed, and clears it: the trial is ended once, and
  /// the trial run again is not aborted by the same press.
  bool TakeAbort();
  /// Blocks while nothing is left to run in an open study, until the
  /// experimenter adds a participant (true) or presses Finish, or `stop` is
  /// set (false).
  bool WaitForMore(const std::atomic<bool>& stop);
  /// The trial's latest camera picture (JPEG) for the thumbnail, and how many
  /// frames the session has received; ignored without `thumbnail`.
  void SetPicture(std::vector<uint8_t> jpeg, uint64_t frames);
  /// Frames the trial's session had received at the last picture (0 without one).
  uint64_t video_frames() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace haptel::study
