// `haptel study run FILE`: the planned trials, one session each, recorded as
// they finish; a second start resumes at the first unfinished one.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "haptel/config/device.hpp"
#include "haptel/config/error.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/json.hpp"
#include "haptel/core/stop_signals.hpp"
#include "haptel/haptics/device_drivers.hpp"
#include "haptel/mediator/run_command.hpp"
#include "haptel/mediator/third_person_view.hpp"
#include "haptel/study/console.hpp"
#include "haptel/study/plan.hpp"
#include "haptel/study/store.hpp"
#include "haptel/study/study_command.hpp"
#include "haptel/study/study_sessions.hpp"
#include "haptel/view/view.hpp"

namespace haptel::study {
namespace {

constexpr const char* kRunUsage =
    "usage: haptel study run FILE [options]   run an A/B study (config/studies/*.yaml)\n"
    "\n"
    "Runs the planned trials in order, each a session like `haptel run`, and records each\n"
    "as it finishes; run the same command again after a stop to resume at the first\n"
    "unfinished trial.\n"
    "options:\n"
    "  --database FILE   SQLite file (overrides the study's and the run configuration's)\n"
    "  --domain N        DDS domain id of the trials' vehicles (overrides the run "
    "configuration's)\n"
    "  --json            end with one JSON line: the trials and per-condition totals\n"
    "  --simulated-time  each trial in simulated time (`haptel run --simulated-time`): every\n"
    "                    part on one clock in this process, as fast as the CPU allows, the same\n"
    "                    lap for the same seed; synthetic studies only. The summary and the\n"
    "                    JSON's speedup say how much faster than real time the trials ran\n"
    "  --console         serve the experimenter's console (schedule, live trial) on 127.0.0.1;\n"
    "                    a person study always does: its trials start from it, its\n"
    "                    questionnaires are filled in there after each condition\n"
    "  --port N          the console's port (default 8470)\n"
    "  --bind ADDR       the console's address (default 127.0.0.1); beyond this machine\n"
    "                    (e.g. 0.0.0.0 for every interface) the page asks once for an access\n"
    "                    token, printed here, and HTTPS is required:\n"
    "  --tls DIR         serve HTTPS with DIR/console.pem and DIR/console.key (made by\n"
    "                    `haptel security init DIR --console NAME,...`)\n"
    "  --plain-http      beyond this machine without HTTPS (the token crosses the network in\n"
    "                    clear; only on a network you trust)\n"
    "  --verbose         the sessions' own progress lines\n";

const StudyCondition& ConditionNamed(const StudyConfig& config, const std::string& name) {
  for (const StudyCondition& c : config.conditions) {
    if (c.name == name) return c;
  }
  throw std::runtime_error("condition '" + name + "' is not in " + config.file.string());
}

const StudyParticipant* ParticipantNamed(const StudyConfig& config, const std::string& id) {
  for (const StudyParticipant& p : config.participants) {
    if (p.id == id) return &p;
  }
  return nullptr;
}

}  // namespace

mediator::SessionSetup TrialSetup(const StudyConfig& config, const PlannedTrial& trial,
                                  const std::filesystem::path& database, const std::string& domain,
                                  bool verbose, int experience, bool simulated_time) {
  const StudyCondition& condition = ConditionNamed(config, trial.condition);
  const bool synthetic = config.operators == "synthetic";
  const std::string cap = std::to_string(config.trial_cap_s);
  std::vector<std::string> words = {"run",
                                    "--config",
                                    config.run.string(),
                                    "--track",
                                    config.track.string(),
                                    "--interface",
                                    condition.interface,
                                    "--operator",
                                    synthetic ? "auto" : "person",
                                    "--lap-limit",
                                    cap,
                                    "--database",
                                    database.string()};
  if (synthetic) words.insert(words.end(), {"--view", "none"});
  if (simulated_time) words.push_back("--simulated-time");
  if (!domain.empty()) words.insert(words.end(), {"--domain", domain});
  if (condition.predict) words.insert(words.end(), {"--predict", "on"});
  if (!config.link_profile.empty())
    words.insert(words.end(), {"--link-profile", config.link_profile});
  if (!config.link_fault.empty()) words.insert(words.end(), {"--link-fault", config.link_fault});
  if (!verbose) words.push_back("--quiet");
  std::vector<const char*> argv;
  for (const std::string& w : words) argv.push_back(w.c_str());
  mediator::SessionSetup setup = mediator::RunSetupFromArgs(
      mediator::ParseRunArgs(static_cast<int>(argv.size()), argv.data()));
  if (synthetic) {
    const StudyParticipant* p = ParticipantNamed(config, trial.participant);
    if (p == nullptr)
      throw std::runtime_error("participant '" + trial.participant + "' is not in the study file");
    setup.driver = config.profiles.at(p->profile);
    setup.driver_experience = experience;
  }
  return setup;
}

namespace {

/// The console's thumbnail shows the session's camera pictures.
void ShowPictures(mediator::SessionSetup& setup, StudyConsole& console) {
  setup.on_picture = [page = &console](std::vector<uint8_t> jpeg, uint64_t frames) {
    page->SetPicture(std::move(jpeg), frames);
  };
}

}  // namespace

void MakePracticeLap(mediator::SessionSetup& setup, const std::string& participant) {
  setup.direct_view = true;
  // The keyboard alone: no other interface's wheel, lever or hands over the
  // picture, no F1-F6 in the hint; the window says whose practice it is.
  setup.single_interface = true;
  setup.title = "Haptel - practice lap - " + participant;
  // The thesis's practice gave a direct view of the robot as well as its
  // camera: a simulated robot's chase camera here (a real robot is in the
  // room to be seen).
  setup.third_person = mediator::ThirdPersonProblem(setup.vehicle).empty();
}

mediator::SessionSetup PracticeSetup(const StudyConfig& config,
                                     const std::filesystem::path& database,
                                     const std::string& domain, bool verbose,
                                     const std::string& participant) {
  const std::string cap = std::to_string(config.trial_cap_s);
  std::vector<std::string> words = {"run",
                                    "--config",
                                    config.run.string(),
                                    "--track",
                                    config.track.string(),
                                    "--interface",
                                    "keyboard",
                                    "--operator",
                                    "person",
                                    "--view",
                                    "window",
                                    "--lap-limit",
                                    cap,
                                    "--database",
                                    database.string()};
  if (!domain.empty()) words.insert(words.end(), {"--domain", domain});
  if (!verbose) words.push_back("--quiet");
  std::vector<const char*> argv;
  for (const std::string& w : words) argv.push_back(w.c_str());
  mediator::SessionSetup setup = mediator::RunSetupFromArgs(
      mediator::ParseRunArgs(static_cast<int>(argv.size()), argv.data()));
  MakePracticeLap(setup, participant);
  return setup;
}

namespace {

/// Waits until every participant has answered every questionnaire of each
/// condition they have finished (all its planned trials), and
/// `next_participant` (when given) their background before their first
/// trial, showing what is awaited on the console. False if `stop` came first.
bool AwaitQuestionnaires(const StudyStore& store, const StudyConfig& config, StudyConsole& console,
                         const std::atomic<bool>& stop, const std::string& next_participant = "") {
  while (!stop.load()) {
    std::string pending;
    // The next participant's background, before their first trial (and
    // their practice lap).
    if (!next_participant.empty() && !config.demographics.empty() &&
        store.TrialsDone(next_participant) == 0 &&
        !store.Answered(next_participant, "", config.demographics)) {
      pending = next_participant + ": " + config.demographics + " before their first trial";
    }
    const std::vector<PlannedTrial> plan = store.Plan();
    const std::vector<TrialRow> trials = store.Trials();
    for (const PlannedTrial& t : plan) {
      int planned = 0;
      int done = 0;
      for (const PlannedTrial& u : plan)
        planned += u.participant == t.participant && u.condition == t.condition;
      for (const TrialRow& u : trials)
        done += u.participant == t.participant && u.condition == t.condition;
      if (done < planned) continue;
      for (const std::string& q : config.questionnaires) {
        if (!store.Answered(t.participant, t.condition, q) &&
            pending.find(t.participant + ": " + q + " after " + t.condition) == std::string::npos) {
          pending +=
              (pending.empty() ? "" : "; ") + t.participant + ": " + q + " after " + t.condition;
        }
      }
    }
    console.SetWaiting(pending.empty() ? "" : "questionnaires (" + pending + ")");
    if (pending.empty()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  return false;
}

std::string Seconds(double s) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.2f", s);
  return buffer;
}

/// What of a recorded run's other outputs failed ("" when none did), as
/// `haptel run` exits kExitOutputFailed for: its --record MP4 (a study
/// passes none today) and its vehicle's CAN bus log.
std::string OutputFailure(const mediator::SessionResult& result) {
  std::string what;
  if (!result.view_record_error.empty())
    what = "the operator's view recording: " + result.view_record_error;
  if (!result.can_log.error.empty()) {
    what += (what.empty() ? "" : "; ") + std::string("the vehicle's CAN bus log: ") +
            result.can_log.error;
  }
  return what;
}

}  // namespace

int StudyRunCommand(int argc, const char* const* argv) {
  // First: a signal while the files are read ends the study before its next trial.
  const std::atomic<bool>& interrupted = InstallStopSignals();
  return cli::Main({"haptel study run", kRunUsage}, argc, argv, [&] {
    bool json = false;
    bool verbose = false;
    bool simulated_time = false;
    StudyConfig config;
    std::vector<PlannedTrial> plan;
    std::filesystem::path database;
    std::string domain;
    ConsoleOptions console_options;
    bool want_console = false;
    std::map<std::string, Questionnaire> questionnaires;
    std::string simulated_device;  ///< the run's haptic device, when it is the simulated one
    cli::ReadInput([&] {
      const Args args(argc, argv, {"database", "domain", "port", "bind", "tls"},
                      {"json", "verbose", "console", "plain-http", "simulated-time"});
      console_options.port = args.Int("port", 1, 65535).value_or(console_options.port);
      console_options.host = args.Value("bind").value_or(console_options.host);
      console_options.plain_http = args.Flag("plain-http");
      if (const auto tls = args.Value("tls")) {
        const ConsoleCertificate certificate = FindConsoleCertificate(*tls);
        console_options.tls_certificate = certificate.certificate;
        console_options.tls_key = certificate.key;
        console_options.names = certificate.names;
      }
      want_console = args.Flag("console") || args.Value("port").has_value() ||
                     args.Value("bind").has_value() || args.Value("tls").has_value();
      if (const auto d = args.Int("domain", 0, 232)) domain = std::to_string(*d);
      if (args.positional().size() != 2 || args.positional()[0] != "run") {
        throw UsageError(args.positional().size() < 2
                             ? "missing the study file"
                             : "unexpected argument '" + args.positional()[2] + "'");
      }
      json = args.Flag("json");
      verbose = args.Flag("verbose");
      config = LoadStudy(args.positional()[1]);
      simulated_time = args.Flag("simulated-time");
      if (simulated_time && want_console) {
        // The console's threads keep their deadlines on the process's clock,
        // which a simulated-time trial takes over.
        throw UsageError(
            "option --simulated-time: the console runs in real time beside the trials; run a "
            "simulated-time study without --console, --port, --bind and --tls");
      }
      if (simulated_time && config.operators != "synthetic") {
        throw UsageError("option --simulated-time: study '" + config.file.string() +
                         "' is driven by people (key "
                         "'operators: " +
                         config.operators +
                         "'), in real time; expected a study with "
                         "'operators: synthetic'");
      }
      // The practice lap is driven with the keys, read in the view's window.
      if (config.operators == "person" && config.practice && !view::View::DisplayAvailable()) {
        throw ConfigError(
            config.file.string() +
            ": key 'practice': expected false when there is no display (DISPLAY is not set or "
            "its X server is not running): the practice lap is driven with the keyboard in the "
            "view's window");
      }
      if (config.operators == "synthetic" && !config.questionnaires.empty()) {
        throw ConfigError(
            config.file.string() +
            ": key 'questionnaires': expected [] for simulated drivers (they do not answer "
            "questionnaires yet)");
      }
      for (const std::string& name : config.questionnaires) {
        questionnaires[name] = FindQuestionnaire(config.questionnaires_dir, name);
      }
      if (!config.demographics.empty()) {
        questionnaires[config.demographics] =
            FindQuestionnaire(config.questionnaires_dir, config.demographics);
      }
      plan = PlanTrials(config);
      const RunConfig run_config = LoadRun(config.run);
      const DeviceConfig device = LoadDevice(run_config.device);
      if (haptics::DriverOf(device).simulated)
        simulated_device = run_config.device.lexically_normal().string();
      database = args.Value("database")
                     .value_or(!config.database.empty() ? config.database.string()
                                                        : run_config.database.string());
      // Each condition's session as its trials will ask for it, checked now:
      // one a trial cannot start (e.g. --simulated-time with a vehicle that
      // does not step in this process) is refused before the study is
      // started and its plan written.
      std::set<std::string> conditions_checked;
      for (const PlannedTrial& t : plan) {
        if (conditions_checked.insert(t.condition).second) {
          TrialSetup(config, t, database, domain, verbose, 0, simulated_time);
        }
      }
      // The console's thumbnail: the trial's camera, through its session.
      console_options.thumbnail = true;
    });
    // The database before anything runs, as for `haptel run`.
    auto recorder = cli::ReadInput([&] { return std::make_unique<record::Recorder>(database); });
    // People are started, aborted and asked from the console: its port first,
    // so a port in use stops the study before its plan is written.
    const bool person = config.operators == "person";
    std::unique_ptr<StudyConsole> console;
    if (want_console || person) {
      console = cli::ReadInput([&] {
        return std::make_unique<StudyConsole>(config, plan, database, questionnaires,
                                              console_options);
      });
      std::string urls;
      for (const std::string& url : console->urls()) urls += (urls.empty() ? "" : " or ") + url;
      std::fprintf(stderr, "[study] console: %s\n", urls.c_str());
      if (!console->access_token().empty()) {
        std::fprintf(stderr, "[study] console access token (the page asks for it once): %s\n",
                     console->access_token().c_str());
      }
    }
    StudyStore store = cli::ReadInput([&] { return StudyStore(*recorder, config, plan); });
    // People hold the haptic conditions' controls with a real device: the
    // simulated one has no arms a person can move (its trials end at the cap).
    if (person && !simulated_device.empty()) {
      std::fprintf(
          stderr,
          "[study] note: the run's device '%s' is simulated: nobody can move its arms, so the "
          "haptic conditions' trials end at the cap; for people name a run file whose device is a "
          "real one (e.g. devices/udp.yaml, the exoskeleton's arms)\n",
          simulated_device.c_str());
    }
    const size_t done_before = store.Trials().size();
    // The console plans a new study before this store opens it: ask the one that planned.
    const bool resumed = console ? console->resumed() : store.resumed();
    store.Event(
        resumed ? "resumed" : "started", "", 0,
        std::to_string(done_before) + " of " + std::to_string(plan.size()) + " trials done");
    std::fprintf(stderr, "[study] %s: %s, %zu trials (%zu done), %s order, database %s\n",
                 config.name.c_str(), resumed ? "resuming" : "starting", plan.size(), done_before,
                 ToString(config.order).c_str(), database.c_str());

    int exit_code = cli::kExitOk;
    std::string stopped;
    double simulated_s = 0.0;  ///< --simulated-time: the trials run now, simulated seconds
    double wall_s = 0.0;       ///< and their wall-clock seconds
    int outputs_failed = 0;    ///< trials run now whose CAN log or recording failed (kept)
    std::filesystem::path unsaved_file;  ///< the run the database did not take, kept in this file
    // A run the database did not take (a full disk...) ends the study: the
    // next would fail the same way. Said whole: what the lap did, why it was
    // not saved, and where its results are; the event is best effort, the
    // database having just failed.
    auto not_saved = [&](const mediator::RecordedRun& run, const std::string& what,
                         const std::string& participant, int position,
                         const std::string& condition) {
      unsaved_file = run.unsaved;
      stopped = what + " not saved (participant " + participant +
                (position > 0 ? ", position " + std::to_string(position) + ", " + condition
                              : std::string()) +
                "): outcome " + mediator::ToString(run.result.outcome) + " (" + run.result.message +
                "), but the database failed: " + run.save_error + "; " +
                (run.unsaved.empty() ? std::string("and no file could take its results (see above)")
                                     : "its results are in " + run.unsaved.string());
      std::fprintf(stderr, "[study]   NOT SAVED: %s\n", stopped.c_str());
      try {
        store.Event("not saved", participant, position, stopped);
      } catch (const std::exception&) {
      }
      exit_code = cli::kExitNotRecorded;
    };
    /// Trials (participant, position) run again once after their vehicle was lost.
    std::set<std::pair<std::string, int>> lost_reruns;
    // A session that stops on a signal, or on the console's Abort.
    auto run_watched = [&](const mediator::SessionSetup& setup,
                           const record::Recorder::AlsoSave& also,
                           const record::TrialOfRun& trial) {
      std::atomic<bool> trial_stop{false};
      std::atomic<bool> trial_over{false};
      std::thread watch([&] {
        while (!trial_over.load()) {
          if (interrupted.load() || (console && console->abort_requested().load()))
            trial_stop.store(true);
          std::this_thread::sleep_for(std::chrono::milliseconds(20));
        }
      });
      mediator::RecordedRun run;
      try {
        run = mediator::RunAndRecord(setup, *recorder, trial_stop, also, trial);
      } catch (...) {
        trial_over.store(true);
        watch.join();
        throw;
      }
      trial_over.store(true);
      watch.join();
      if (console) console->SetLive("");
      return run;
    };
    // An open study (no participants in its file) goes on while the
    // experimenter adds participants, until they press Finish.
    const bool open_study = person && config.participants.empty();
    for (;;) {
      const std::optional<PlannedTrial> trial = store.NextTrial();
      if (!trial && open_study && !interrupted.load()) {
        if (!AwaitQuestionnaires(store, config, *console, interrupted)) continue;
        if (console->WaitForMore(interrupted)) continue;
      }
      if (!trial) break;
      if (interrupted.load()) {
        stopped = "interrupted";
        exit_code = cli::kExitFailed;
        break;
      }
      if (person) {
        // The questionnaires of the conditions already driven come first;
        // then the experimenter starts the trial.
        if (!AwaitQuestionnaires(store, config, *console, interrupted, trial->participant))
          continue;
        if (config.practice && store.TrialsDone(trial->participant) == 0 &&
            !store.Practised(trial->participant)) {
          const std::string who = "participant " + trial->participant;
          if (!console->WaitForStart(
                  "practice lap for " + who + ": the keyboard, the camera's view", interrupted)) {
            continue;
          }
          mediator::SessionSetup practice = cli::ReadInput(
              [&] { return PracticeSetup(config, database, domain, verbose, trial->participant); });
          ShowPictures(practice, *console);
          // The console says what the participant sees, the chase camera too.
          console->SetLive("practice lap: " + who + " (keyboard" +
                               (practice.third_person ? ", camera and third-person view" : "") +
                               "; Abort ends it)",
                           trial->participant, 0);
          std::fprintf(stderr, "[study] practice lap: %s ...\n", who.c_str());
          const mediator::RecordedRun run =
              run_watched(practice, {}, {config.name, trial->participant, 0, "practice lap", 1});
          if (run.run_id == 0) {
            not_saved(run, "practice lap", trial->participant, 0, "");
            break;
          }
          if (interrupted.load()) continue;
          const record::RunRecord& r = run.result.record;
          // Aborted: not practised. Recorded as such, and offered again (the
          // experimenter may start it once more, or let it run to its end).
          if (console->TakeAbort()) {
            store.Event(
                "practice interrupted", trial->participant, 0,
                "run " + std::to_string(run.run_id) + ": aborted from the console; offered again");
            std::fprintf(stderr,
                         "[study]   practice aborted from the console: offered again (run %lld)\n",
                         static_cast<long long>(run.run_id));
            continue;
          }
          store.Event("practice", trial->participant, 0,
                      "run " + std::to_string(run.run_id) + ": " +
                          mediator::ToString(run.result.outcome) +
                          (r.completed ? ", lap " + Seconds(r.lap_time_s) + " s" : ""));
          std::fprintf(stderr, "[study]   practice: %s (run %lld)\n",
                       mediator::ToString(run.result.outcome).c_str(),
                       static_cast<long long>(run.run_id));
          continue;  // the trial is offered next
        }
        if (!console->WaitForStart("participant " + trial->participant + ", " + trial->condition +
                                       " (position " + std::to_string(trial->position) + ")",
                                   interrupted)) {
          continue;  // interrupted: the loop's first check ends the study
        }
      }
      const int experience = store.TrialsDone(trial->participant) + (config.practice ? 1 : 0);
      mediator::SessionSetup setup = cli::ReadInput([&] {
        return TrialSetup(config, *trial, database, domain, verbose, experience, simulated_time);
      });
      const size_t planned = store.Plan().size();
      const size_t number = store.Trials().size() + 1;
      if (console) {
        console->SetLive("trial " + std::to_string(number) + " of " + std::to_string(planned) +
                             ": participant " + trial->participant + ", " + trial->condition +
                             " (position " + std::to_string(trial->position) + ")",
                         trial->participant, trial->position);
        StudyConsole* page = console.get();
        setup.on_live = [page](const view::Overlay& o) {
          page->SetLiveProgress(
              {o.lap_time_s, o.gates_passed, o.gates_total, o.obstacles_touched, o.last_contact});
        };
        ShowPictures(setup, *page);
      }
      std::fprintf(stderr, "[study] trial %zu/%zu: participant %s, position %d, %s ...\n", number,
                   planned, trial->participant.c_str(), trial->position, trial->condition.c_str());
      const int64_t trial_start_ns = RealMonotonicNs();
      const mediator::RecordedRun run = run_watched(
          setup, store.TrialWriter(*trial, config.trial_cap_s),
          {config.name, trial->participant, trial->position, trial->condition, trial->repetition});
      const record::RunRecord& r = run.result.record;
      // The speed-up over real time: simulated seconds against the trial's
      // whole wall-clock time (set-up, lap, recording and picture).
      simulated_s += run.result.simulated_s;
      wall_s += NsToS(RealMonotonicNs() - trial_start_ns);
      if (run.run_id == 0) {
        not_saved(run, "trial", trial->participant, trial->position, trial->condition);
        break;
      }
      // Taken, not only read: the trial run again is not aborted by the same press.
      if (console && console->TakeAbort() && !interrupted.load()) {
        store.Event("aborted", trial->participant, trial->position,
                    "from the console; the trial is run again");
        std::fprintf(stderr, "[study]   aborted from the console: the trial is run again\n");
        continue;
      }
      if (run.run_id != 0 && FinishesTrial(mediator::ToString(run.result.outcome))) {
        std::fprintf(stderr, "[study]   %s: lap %s s%s, %d obstacles, %d slips (run %lld)\n",
                     mediator::ToString(run.result.outcome).c_str(), Seconds(r.lap_time_s).c_str(),
                     r.completed ? "" : (" (scored " + Seconds(config.trial_cap_s) + " s)").c_str(),
                     r.obstacles_touched, run.result.operator_slips,
                     static_cast<long long>(run.run_id));
        // The lap is recorded, so the trial stands; what else it should
        // have written is lost, which the experimenter must hear of.
        if (const std::string failure = OutputFailure(run.result); !failure.empty()) {
          ++outputs_failed;
          std::fprintf(stderr, "[study]   output failed: participant %s, position %d, %s: %s\n",
                       trial->participant.c_str(), trial->position, trial->condition.c_str(),
                       failure.c_str());
          store.Event("output failed", trial->participant, trial->position,
                      "run " + std::to_string(run.run_id) + ": " + failure);
        }
        // Nobody watches a synthetic study to redo a spoiled trial: a flagged
        // one runs again once, now, by itself; both are kept (the first as
        // superseded), the report counts the second. People's flagged trials
        // are the experimenter's to redo, from the console.
        if (!person && store.RedoFlaggedOnce(*trial)) {
          std::fprintf(stderr, "[study]   flagged (%s): run again once\n", TrialFlags(r).c_str());
        }
        continue;
      }
      // A vehicle that answered, then went silent for the vehicle time-out
      // (one pause on a loaded host), spoils the trial, not the study: a
      // synthetic trial is run again once, with a vehicle of its own, as a
      // flagged one is ('redo': the next row is its attempt 2). Lost again,
      // the vehicle stays lost, and the study stops as before.
      if (!person && run.result.outcome == mediator::Outcome::kVehicleLost &&
          lost_reruns.insert({trial->participant, trial->position}).second) {
        store.Event("redo", trial->participant, trial->position,
                    "run " + std::to_string(run.run_id) + ": " + run.result.message +
                        ": run again once by itself");
        std::fprintf(stderr, "[study]   flagged (%s): run again once (run %lld)\n",
                     run.result.message.c_str(), static_cast<long long>(run.run_id));
        continue;
      }
      // Not a finished trial: the run is recorded, the trial is not.
      store.Event("trial not finished", trial->participant, trial->position,
                  mediator::ToString(run.result.outcome) + ": " + run.result.message);
      stopped = mediator::ToString(run.result.outcome) + ": " + run.result.message;
      exit_code = mediator::ExitCode(run.result.outcome);
      if (exit_code == cli::kExitOk) exit_code = cli::kExitFailed;
      break;
    }

    if (person && !open_study && exit_code == cli::kExitOk && !store.NextTrial()) {
      AwaitQuestionnaires(store, config, *console, interrupted);  // the last condition's
    }
    // A lost output is the exit code only of a study that otherwise ended
    // well: a trial not recorded, an interruption or a failure says more.
    if (exit_code == cli::kExitOk && outputs_failed > 0) exit_code = cli::kExitOutputFailed;
    plan = store.Plan();  // with the participants added in the console
    const std::vector<TrialRow> trials = store.Trials();
    const bool finished = trials.size() == plan.size() && !interrupted.load();
    if (finished) store.Event("finished", "", 0, std::to_string(trials.size()) + " trials");
    // The schedule as it stands: participants × conditions, scored lap times.
    std::printf("study %s: %zu of %zu trials%s\n", config.name.c_str(), trials.size(), plan.size(),
                finished ? ", finished" : (", stopped: " + stopped).c_str());
    std::printf("  %-12s", "participant");
    for (const StudyCondition& c : config.conditions) std::printf(" %16s", c.name.c_str());
    std::printf("\n");
    std::vector<std::string> participants;
    for (const PlannedTrial& t : plan) {
      if (std::find(participants.begin(), participants.end(), t.participant) ==
          participants.end()) {
        participants.push_back(t.participant);
      }
    }
    std::map<std::string, double> totals;
    std::map<std::string, int> counts;
    for (const std::string& p : participants) {
      std::printf("  %-12s", p.c_str());
      for (const StudyCondition& c : config.conditions) {
        std::string cell = "-";
        for (const TrialRow& t : trials) {
          if (t.participant != p || t.condition != c.name) continue;
          cell = Seconds(t.lap_time_s) + (t.completed ? "" : "*") + " (" +
                 std::to_string(t.position) + ")";
          totals[c.name] += t.lap_time_s;
          counts[c.name] += 1;
        }
        std::printf(" %16s", cell.c_str());
      }
      std::printf("\n");
    }
    std::printf("  %-12s", "total");
    for (const StudyCondition& c : config.conditions)
      std::printf(" %16s", Seconds(totals[c.name]).c_str());
    std::printf(
        "\n  (lap time s as scored, on the lap's clock from the start line, position in brackets; "
        "* unfinished, scored at the %s s cap, also on the lap's clock)\n",
        Seconds(config.trial_cap_s).c_str());
    const double speedup = simulated_time && wall_s > 0.0 ? simulated_s / wall_s : 0.0;
    if (speedup > 0.0) {
      std::printf(
          "  simulated time: %.1f s simulated in %.1f s wall-clock over the trials run now, %.1fx "
          "real "
          "time\n",
          simulated_s, wall_s, speedup);
    }
    if (outputs_failed > 0) {
      std::printf(
          "  outputs failed: %d trial%s run now lost %s CAN bus log or view recording (the laps "
          "are "
          "recorded; the [study] lines above say which and why)\n",
          outputs_failed, outputs_failed == 1 ? "" : "s", outputs_failed == 1 ? "its" : "their");
    }
    std::printf("  report: haptel study report %s --study %s\n", database.c_str(),
                config.name.c_str());
    if (json) {
      std::string out =
          "{\"study\":" + JsonString(config.name) +
          ",\"database\":" + JsonString(database.string()) +
          ",\"finished\":" + (finished ? "true" : "false") +
          ",\"trials_planned\":" + std::to_string(plan.size()) +
          ",\"trials_done\":" + std::to_string(trials.size()) +
          ",\"trials_done_before\":" + std::to_string(done_before) +
          ",\"stopped\":" + JsonString(stopped) +
          ",\"unsaved_file\":" + JsonString(unsaved_file.string()) +
          ",\"speedup\":" + (speedup > 0.0 ? JsonNumber(speedup) : std::string("null")) +
          ",\"outputs_failed\":" + std::to_string(outputs_failed) + ",\"conditions\":[";
      for (size_t i = 0; i < config.conditions.size(); ++i) {
        const std::string& name = config.conditions[i].name;
        if (i > 0) out += ",";
        out += "{\"name\":" + JsonString(name) + ",\"trials\":" + std::to_string(counts[name]) +
               ",\"total_lap_time_s\":" + JsonNumber(totals[name]) + "}";
      }
      out += "],\"trials\":[";
      for (size_t i = 0; i < trials.size(); ++i) {
        const TrialRow& t = trials[i];
        if (i > 0) out += ",";
        out += "{\"participant\":" + JsonString(t.participant) +
               ",\"position\":" + std::to_string(t.position) +
               ",\"condition\":" + JsonString(t.condition) +
               ",\"lap_time_s\":" + JsonNumber(t.lap_time_s) + ",\"approach_s\":" +
               (std::isfinite(t.approach_s) ? JsonNumber(t.approach_s) : std::string("null")) +
               ",\"completed\":" + (t.completed ? "true" : "false") +
               ",\"obstacles\":" + std::to_string(t.obstacles) +
               ",\"run_id\":" + std::to_string(t.run_id) + "}";
      }
      out += "]}";
      std::printf("%s\n", out.c_str());
    }
    std::fflush(stdout);
    return exit_code;
  });
}

}  // namespace haptel::study
