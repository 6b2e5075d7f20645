#pragma once
/// @file The experimenter's console: a web page served by `haptel study run`
/// on 127.0.0.1 (cpp-httplib; plain HTML, no JavaScript needed). It shows the
/// schedule (each participant's conditions in their order, with the trials'
/// results), the live trial, and the questionnaire forms a participant fills
/// in after each condition; submissions go through SubmitAnswers (checked,
/// in order, never twice).
///
/// Routes: `GET /` the schedule; `GET /questionnaire?participant=P&condition=C&name=Q`
/// a form; `POST /answers` a filled-in form; `POST /start` starts the trial
/// offered; `POST /abort` aborts the trial under way (it is run again);
/// `POST /redo` (participant, position) takes a finished trial back, to be
/// run again;
/// `POST /participants` (id) adds a participant, planned by the design;
/// `POST /finish` ends an open study (one whose file lists no participants);
/// `GET /video.jpg` the vehicle's latest camera picture (the thumbnail);
/// `GET /status.json` the counts, the live trial, the next, what is awaited.
#include <atomic>
#include <filesystem>
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

struct ConsoleOptions {
  std::string host = "127.0.0.1";  ///< only this machine: the page takes answers
  int port = 8470;                 ///< 0: any free port (tests)
  /// Show the vehicle's camera (SetPicture, from the trial's session).
  bool thumbnail = false;
};

/// The live trial as the page shows it, beside its title line.
struct LiveProgress {
  double lap_time_s = 0.0;
  int gates_passed = 0;
  int gates_total = 0;
  int obstacles = 0;
  std::string last_contact;  ///< e.g. "left bumper at 12.3 s"
};

class StudyConsole {
 public:
  /// Opens its own connection to `database` (the study must be planned there
  /// already) and serves from threads of its own. Throws ConsoleError naming
  /// the address when it cannot bind ("port 8470 on 127.0.0.1 is in use").
  StudyConsole(const StudyConfig& config, const std::vector<PlannedTrial>& plan,
               const std::filesystem::path& database, const std::map<std::string, Questionnaire>& questionnaires,
               const ConsoleOptions& options);
  ~StudyConsole();
  StudyConsole(const StudyConsole&) = delete;
  StudyConsole& operator=(const StudyConsole&) = delete;

  int port() const;
  /// e.g. "http://127.0.0.1:8470/"
  std::string url() const;
  /// The line the page shows for the trial under way (empty: none); clears
  /// the progress.
  void SetLive(const std::string& text);
  /// The lap clock, gates and contacts of the trial under way.
  void SetLiveProgress(const LiveProgress& progress);
  /// What the study waits for before the next trial (empty: nothing), e.g.
  /// "participant A's questionnaires after gesture".
  void SetWaiting(const std::string& text);
  /// Offers `next` with a Start button and blocks until the experimenter
  /// presses it (true) or `stop` is set (false). Clears a previous abort.
  bool WaitForStart(const std::string& next, const std::atomic<bool>& stop);
  /// Set by the page's Abort button during a trial.
  const std::atomic<bool>& abort_requested() const;
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
