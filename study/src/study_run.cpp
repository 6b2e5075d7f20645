// `haptel study run FILE` below its command line (app/src/study_run_command.cpp):
// the planned trials, one session each, recorded as they finish; a second
// start resumes at the first unfinished one.
#include "haptel/study/study_run.hpp"

#include <malloc.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "haptel/config/device.hpp"
#include "haptel/config/error.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/command_line.hpp"
#include "haptel/core/json.hpp"
#include "haptel/haptics/device_drivers.hpp"
#include "haptel/mediator/run_setup.hpp"
#include "haptel/mediator/third_person_view.hpp"
#include "haptel/study/camera_setup.hpp"
#include "haptel/study/console.hpp"
#include "haptel/study/plan.hpp"
#include "haptel/study/store.hpp"
#include "haptel/study/study_sessions.hpp"
#include "haptel/view/view.hpp"

namespace haptel::study {
namespace {

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

std::filesystem::path TrialSessionFile(const StudyConfig& config, const PlannedTrial& trial,
                                       const std::filesystem::path& database) {
  const std::filesystem::path folder =
      std::filesystem::absolute(database).parent_path() / "sessions" / config.name;
  // Stamped: a trial run again (a redo) keeps the first attempt's file.
  const std::time_t seconds = static_cast<std::time_t>(WallNs() / 1000000000);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char stamp[24];
  std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &utc);
  return folder / (trial.participant + "-" + std::to_string(trial.position) + "-" +
                   trial.condition + "-" + stamp + ".mcap");
}

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
  // The condition's device (the run file's when it names none).
  if (!condition.device.empty()) words.insert(words.end(), {"--device", condition.device.string()});
  // A person drives in the view's window (the mouse device reads its
  // pointer); without a display the trial's device says what is missing.
  if (synthetic) {
    words.insert(words.end(), {"--view", "none"});
  } else if (view::View::DisplayAvailable()) {
    words.insert(words.end(), {"--view", "window"});
  }
  if (simulated_time) words.push_back("--simulated-time");
  if (!domain.empty()) words.insert(words.end(), {"--domain", domain});
  if (condition.predict) words.insert(words.end(), {"--predict", "on"});
  // Its camera set-up: which of the vehicle's cameras stream.
  if (!condition.cameras.empty()) {
    std::string list;
    for (const std::string& c : condition.cameras) list += (list.empty() ? "" : ",") + c;
    words.insert(words.end(), {"--cameras", list});
  }
  if (!config.link_profile.empty())
    words.insert(words.end(), {"--link-profile", config.link_profile});
  if (!config.link_fault.empty()) words.insert(words.end(), {"--link-fault", config.link_fault});
  if (!config.reality.empty()) words.insert(words.end(), {"--reality", config.reality.string()});
  if (!verbose) words.push_back("--quiet");
  if (config.sessions)
    words.insert(words.end(), {"--session", TrialSessionFile(config, trial, database).string()});
  std::vector<const char*> argv;
  for (const std::string& w : words) argv.push_back(w.c_str());
  mediator::SessionSetup setup = mediator::RunSetupFromArgs(
      mediator::ParseRunArgs(static_cast<int>(argv.size()), argv.data()));
  if (config.sessions) {
    setup.session_file.run_metadata["command_line"] =
        cli::CommandLine(static_cast<int>(argv.size()), argv.data());
    setup.session_file.study_metadata = {{"study", config.name},
                                         {"participant", trial.participant},
                                         {"condition", trial.condition},
                                         {"position", std::to_string(trial.position)},
                                         {"repetition", std::to_string(trial.repetition)},
                                         {"device", condition.device.string()},
                                         {"cameras", CameraNames(setup.vehicle)},
                                         {"station", condition.station}};
  }
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

bool PersonCanDrive(const mediator::SessionSetup& trial) {
  const bool manual = !trial.interfaces.empty() &&
                      trial.interfaces[static_cast<size_t>(trial.start_interface)].manual();
  return manual || !haptics::DriverOf(trial.device).simulated;
}

TrialDevice DeviceOf(const StudyCondition& condition) {
  if (condition.device.empty()) return {};
  const DeviceConfig device = LoadDevice(condition.device);
  return {condition.device_name, condition.device,
          [device] { return haptics::DeviceUnavailable(device); }};
}

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
  if (!config.reality.empty()) words.insert(words.end(), {"--reality", config.reality.string()});
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

/// The study file and its run configuration, as the options ask for them,
/// checked before anything is written: its questionnaires, its plan, its
/// database, and each condition's session.
struct StudyRunPlan {
  StudyConfig config;
  std::vector<PlannedTrial> plan;
  std::map<std::string, Questionnaire> questionnaires;
  std::filesystem::path database;
  /// The conditions a person cannot drive: a hand interface on a simulated
  /// device (nobody can move its arms), each "NAME (DEVICE FILE)".
  std::vector<std::string> undrivable;
  ConsoleOptions console_options;
};

StudyRunPlan PlanStudyRun(const StudyRunOptions& options) {
  StudyRunPlan p;
  p.config = LoadStudy(options.file);
  const StudyConfig& config = p.config;
  if (options.simulated_time && options.console) {
    // The console's threads keep their deadlines on the process's clock,
    // which a simulated-time trial takes over.
    throw UsageError(
        "option --simulated-time: the console runs in real time beside the trials; run a "
        "simulated-time study without --console, --port, --bind and --tls");
  }
  if (options.simulated_time && config.operators != "synthetic") {
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
    throw ConfigError(config.file.string() +
                      ": key 'questionnaires': expected [] for simulated drivers (they do not "
                      "answer questionnaires yet)");
  }
  for (const std::string& name : config.questionnaires) {
    p.questionnaires[name] = FindQuestionnaire(config.questionnaires_dir, name);
  }
  if (!config.demographics.empty()) {
    p.questionnaires[config.demographics] =
        FindQuestionnaire(config.questionnaires_dir, config.demographics);
  }
  p.plan = PlanTrials(config);
  const RunConfig run_config = LoadRun(config.run);
  p.database = options.database.value_or(!config.database.empty() ? config.database.string()
                                                                  : run_config.database.string());
  // Each condition's session as its trials will ask for it, checked now:
  // one a trial cannot start (e.g. --simulated-time with a vehicle that
  // does not step in this process) is refused before the study is
  // started and its plan written.
  // Every condition, also of an open study (its participants come later).
  for (size_t i = 0; i < config.conditions.size(); ++i) {
    const StudyCondition& c = config.conditions[i];
    // Simulated drivers move the simulated device's arms, and no other's.
    if (config.operators == "synthetic" && !c.device.empty() &&
        !haptics::DriverOf(LoadDevice(c.device)).simulated) {
      throw ConfigError(config.file.string() + ": key 'conditions[" + std::to_string(i) +
                        "].device': expected a simulated device for simulated drivers (they move "
                        "its arms), got '" +
                        c.device_name + "' (" + c.device.string() + ")");
    }
    // Its first planned trial (a simulated driver's profile is its
    // participant's), else one of an open person study's participants to come.
    PlannedTrial first{"", 1, c.name, 1, c.device_name};
    for (const PlannedTrial& t : p.plan) {
      if (t.condition == c.name) {
        first = t;
        break;
      }
    }
    const mediator::SessionSetup setup = TrialSetup(config, first, p.database, options.domain,
                                                    options.verbose, 0, options.simulated_time);
    if (config.operators == "person" && !PersonCanDrive(setup))
      p.undrivable.push_back(c.name + " (" + setup.run.device.lexically_normal().string() + ")");
  }
  p.console_options = options.console_options;
  // The console's thumbnail: the trial's camera, through its session.
  p.console_options.thumbnail = true;
  return p;
}

/// What the trials run now came to, for the summary and the exit code.
struct StudyRunTally {
  int exit_code = cli::kExitOk;
  std::string stopped;                 ///< why the study stopped ("" when it did not)
  size_t done_before = 0;              ///< trials done before this start
  double simulated_s = 0.0;            ///< --simulated-time: the trials run now, simulated seconds
  double wall_s = 0.0;                 ///< and their wall-clock seconds
  int outputs_failed = 0;              ///< trials run now whose CAN log or recording failed (kept)
  std::filesystem::path unsaved_file;  ///< the run the database did not take, kept in this file
};

/// The study under way: its database, console and tables, and the trials
/// run one by one, as the loop's steps.
class StudyRun {
 public:
  StudyRun(const StudyRunOptions& options, const StudyRunPlan& plan,
           const std::atomic<bool>& interrupted)
      : options_(options), plan_(plan), interrupted_(interrupted) {}

  /// The database, the console (people are started, aborted and asked
  /// from it) and the study's tables; says what is resumed.
  void Open();
  /// Every trial left, in order, until the plan is done, the experimenter
  /// finishes an open study, or one stops the study.
  void RunTrials();
  StudyStore& store() { return *store_; }
  const StudyRunTally& tally() const { return tally_; }

 private:
  /// What the trial loop does after a step.
  enum class Then {
    kRunTrial,  ///< on to the trial's session
    kOffer,     ///< back to the loop's top: the next trial offered (maybe the same one)
    kStop,      ///< the study ends
  };
  Then PrepareForPerson(const PlannedTrial& trial);
  Then RunPracticeLap(const PlannedTrial& trial);
  Then RunTrial(const PlannedTrial& trial);
  /// What a finished trial's run leaves to tell: its outputs lost, a redo.
  void AfterFinishedTrial(const PlannedTrial& trial, const mediator::RecordedRun& run);
  /// A session that stops on a signal, or on the console's Abort.
  mediator::RecordedRun RunWatched(const mediator::SessionSetup& setup,
                                   const record::Recorder::AlsoSave& also,
                                   const record::TrialOfRun& trial);
  void WatchForStop(std::atomic<bool>& stop, const std::atomic<bool>& over) const;
  void NotSaved(const mediator::RecordedRun& run, const std::string& what,
                const std::string& participant, int position, const std::string& condition);

  const StudyRunOptions& options_;
  const StudyRunPlan& plan_;
  const StudyConfig& config_ = plan_.config;
  const std::atomic<bool>& interrupted_;
  const bool person_ = plan_.config.operators == "person";
  std::unique_ptr<record::Recorder> recorder_;
  std::unique_ptr<StudyConsole> console_;
  std::unique_ptr<StudyStore> store_;
  StudyRunTally tally_;
  /// Trials (participant, position) run again once after their vehicle was lost.
  std::set<std::pair<std::string, int>> lost_reruns_;
};

void StudyRun::Open() {
  // The database before anything runs, as for `haptel run`.
  recorder_ = cli::ReadInput([&] { return std::make_unique<record::Recorder>(plan_.database); });
  // People are started, aborted and asked from the console: its port first,
  // so a port in use stops the study before its plan is written.
  if (options_.console || person_) {
    console_ = cli::ReadInput([&] {
      return std::make_unique<StudyConsole>(config_, plan_.plan, plan_.database,
                                            plan_.questionnaires, plan_.console_options);
    });
    std::string urls;
    for (const std::string& url : console_->urls()) urls += (urls.empty() ? "" : " or ") + url;
    std::fprintf(stderr, "[study] console: %s\n", urls.c_str());
    if (!console_->access_token().empty()) {
      std::fprintf(stderr, "[study] console access token (the page asks for it once): %s\n",
                   console_->access_token().c_str());
    }
  }
  store_ =
      cli::ReadInput([&] { return std::make_unique<StudyStore>(*recorder_, config_, plan_.plan); });
  // People hold the haptic conditions' controls with a device they can
  // move: the simulated one has no arms a person can move (its trials end
  // at the cap).
  if (!plan_.undrivable.empty()) {
    std::string which;
    for (const std::string& c : plan_.undrivable) which += (which.empty() ? "" : ", ") + c;
    std::fprintf(stderr,
                 "[study] note: condition%s %s %s driven with a simulated device: nobody can move "
                 "its arms, so %s trials end at the cap; name a person's device per condition "
                 "(device: ../devices/mouse.yaml, the mouse; devices/sdl-ff.yaml, a "
                 "force-feedback joystick; devices/udp.yaml, the arms)\n",
                 plan_.undrivable.size() == 1 ? "" : "s", which.c_str(),
                 plan_.undrivable.size() == 1 ? "is" : "are",
                 plan_.undrivable.size() == 1 ? "its" : "their");
  }
  tally_.done_before = store_->Trials().size();
  // The console plans a new study before this store opens it: ask the one that planned.
  const bool resumed = console_ ? console_->resumed() : store_->resumed();
  store_->Event(resumed ? "resumed" : "started", "", 0,
                std::to_string(tally_.done_before) + " of " + std::to_string(plan_.plan.size()) +
                    " trials done");
  std::fprintf(stderr, "[study] %s: %s, %zu trials (%zu done), %s order, database %s\n",
               config_.name.c_str(), resumed ? "resuming" : "starting", plan_.plan.size(),
               tally_.done_before, ToString(config_.order).c_str(), plan_.database.c_str());
}

void StudyRun::RunTrials() {
  // An open study (no participants in its file) goes on while the
  // experimenter adds participants, until they press Finish.
  const bool open_study = person_ && config_.participants.empty();
  for (;;) {
    const std::optional<PlannedTrial> trial = store_->NextTrial();
    if (!trial && open_study && !interrupted_.load()) {
      if (!AwaitQuestionnaires(*store_, config_, *console_, interrupted_)) continue;
      if (console_->WaitForMore(interrupted_)) continue;
    }
    if (!trial) break;
    if (interrupted_.load()) {
      tally_.stopped = "interrupted";
      tally_.exit_code = cli::kExitFailed;
      break;
    }
    Then then = person_ ? PrepareForPerson(*trial) : Then::kRunTrial;
    if (then == Then::kRunTrial) then = RunTrial(*trial);
    if (then == Then::kStop) break;
  }
  if (person_ && !open_study && tally_.exit_code == cli::kExitOk && !store_->NextTrial()) {
    AwaitQuestionnaires(*store_, config_, *console_, interrupted_);  // the last condition's
  }
  // A lost output is the exit code only of a study that otherwise ended
  // well: a trial not recorded, an interruption or a failure says more.
  if (tally_.exit_code == cli::kExitOk && tally_.outputs_failed > 0)
    tally_.exit_code = cli::kExitOutputFailed;
}

/// The questionnaires of the conditions already driven come first; then
/// the practice lap of a participant's first trial; then the experimenter
/// starts the trial.
StudyRun::Then StudyRun::PrepareForPerson(const PlannedTrial& trial) {
  if (!AwaitQuestionnaires(*store_, config_, *console_, interrupted_, trial.participant))
    return Then::kOffer;
  if (config_.practice && store_->TrialsDone(trial.participant) == 0 &&
      !store_->Practised(trial.participant)) {
    return RunPracticeLap(trial);
  }
  const StudyCondition& condition = ConditionNamed(config_, trial.condition);
  TrialDevice device = DeviceOf(condition);
  // A condition with a station: not started until a second person is at it.
  std::unique_ptr<StationWatch> station;
  if (!condition.station.empty()) {
    // The trial's link and vehicle name, as its run file says and --domain overrides.
    const RunConfig run = LoadRun(config_.run);
    LinkConfig link = run.link;
    if (!options_.domain.empty()) link.domain_id = std::stoi(options_.domain);
    station = std::make_unique<StationWatch>(link, LoadVehicle(run.vehicle).name, condition.station,
                                             condition.name);
    device.unavailable = [station = station.get(), own = device.unavailable] {
      const std::string missing = own ? own() : std::string();
      return missing.empty() ? station->Missing() : missing;
    };
  }
  if (!console_->WaitForStart(
          WithCameraSetup("participant " + trial.participant + ", " + trial.condition +
                              " (position " + std::to_string(trial.position) + ")",
                          condition),
          interrupted_, device)) {
    return Then::kOffer;  // interrupted: the loop's first check ends the study
  }
  return Then::kRunTrial;
}

StudyRun::Then StudyRun::RunPracticeLap(const PlannedTrial& trial) {
  const std::string who = "participant " + trial.participant;
  if (!console_->WaitForStart("practice lap for " + who + ": the keyboard, the camera's view",
                              interrupted_)) {
    return Then::kOffer;
  }
  mediator::SessionSetup practice = cli::ReadInput([&] {
    return PracticeSetup(config_, plan_.database, options_.domain, options_.verbose,
                         trial.participant);
  });
  ShowPictures(practice, *console_);
  // The console says what the participant sees, the chase camera too.
  console_->SetLive("practice lap: " + who + " (keyboard" +
                        (practice.third_person ? ", camera and third-person view" : "") +
                        "; Abort ends it)",
                    trial.participant, 0);
  std::fprintf(stderr, "[study] practice lap: %s ...\n", who.c_str());
  const mediator::RecordedRun run =
      RunWatched(practice, {}, {config_.name, trial.participant, 0, "practice lap", 1});
  if (run.run_id == 0) {
    NotSaved(run, "practice lap", trial.participant, 0, "");
    return Then::kStop;
  }
  if (interrupted_.load()) return Then::kOffer;
  const record::RunRecord& r = run.result.record;
  // Aborted: not practised. Recorded as such, and offered again (the
  // experimenter may start it once more, or let it run to its end).
  if (console_->TakeAbort()) {
    store_->Event(
        "practice interrupted", trial.participant, 0,
        "run " + std::to_string(run.run_id) + ": aborted from the console; offered again");
    std::fprintf(stderr, "[study]   practice aborted from the console: offered again (run %lld)\n",
                 static_cast<long long>(run.run_id));
    return Then::kOffer;
  }
  store_->Event("practice", trial.participant, 0,
                "run " + std::to_string(run.run_id) + ": " +
                    mediator::ToString(run.result.outcome) +
                    (r.completed ? ", lap " + Seconds(r.lap_time_s) + " s" : ""));
  std::fprintf(stderr, "[study]   practice: %s (run %lld)\n",
               mediator::ToString(run.result.outcome).c_str(), static_cast<long long>(run.run_id));
  return Then::kOffer;  // the trial is offered next
}

StudyRun::Then StudyRun::RunTrial(const PlannedTrial& trial) {
  const int experience = store_->TrialsDone(trial.participant) + (config_.practice ? 1 : 0);
  mediator::SessionSetup setup = cli::ReadInput([&] {
    return TrialSetup(config_, trial, plan_.database, options_.domain, options_.verbose, experience,
                      options_.simulated_time);
  });
  const size_t planned = store_->Plan().size();
  const size_t number = store_->Trials().size() + 1;
  if (console_) {
    console_->SetLive("trial " + std::to_string(number) + " of " + std::to_string(planned) +
                          ": participant " + trial.participant + ", " + trial.condition +
                          " (position " + std::to_string(trial.position) + ")",
                      trial.participant, trial.position);
    StudyConsole* page = console_.get();
    setup.on_live = [page](const view::Overlay& o) {
      page->SetLiveProgress({o.lap_time_s, o.gates_passed, o.gates_total, o.obstacles_touched,
                             o.last_contact, o.message});
    };
    ShowPictures(setup, *page);
  }
  std::fprintf(stderr, "[study] trial %zu/%zu: participant %s, position %d, %s ...\n", number,
               planned, trial.participant.c_str(), trial.position, trial.condition.c_str());
  const int64_t trial_start_ns = RealMonotonicNs();
  const mediator::RecordedRun run = RunWatched(
      setup, store_->TrialWriter(trial, config_.trial_cap_s),
      {config_.name, trial.participant, trial.position, trial.condition, trial.repetition});
  // The speed-up over real time: simulated seconds against the trial's
  // whole wall-clock time (set-up, lap, recording and picture).
  tally_.simulated_s += run.result.simulated_s;
  tally_.wall_s += NsToS(RealMonotonicNs() - trial_start_ns);
  if (run.run_id == 0) {
    NotSaved(run, "trial", trial.participant, trial.position, trial.condition);
    return Then::kStop;
  }
  // Taken, not only read: the trial run again is not aborted by the same press.
  if (console_ && console_->TakeAbort() && !interrupted_.load()) {
    store_->Event("aborted", trial.participant, trial.position,
                  "from the console; the trial is run again");
    std::fprintf(stderr, "[study]   aborted from the console: the trial is run again\n");
    return Then::kOffer;
  }
  if (FinishesTrial(mediator::ToString(run.result.outcome))) {
    AfterFinishedTrial(trial, run);
    return Then::kOffer;
  }
  // A person's trial whose vehicle answered, then went silent for the
  // vehicle time-out (a pause on a loaded host, a link that dropped), is
  // spoiled, not the study: its run is recorded, the trial is not, and the
  // console offers it again, with a vehicle of its own, for the
  // experimenter to start (as after an Abort).
  if (person_ && run.result.outcome == mediator::Outcome::kVehicleLost) {
    store_->Event("vehicle lost", trial.participant, trial.position,
                  "run " + std::to_string(run.run_id) + ": " + run.result.message +
                      ": the trial is offered again");
    std::fprintf(stderr, "[study]   %s: the trial is offered again (run %lld)\n",
                 run.result.message.c_str(), static_cast<long long>(run.run_id));
    return Then::kOffer;
  }
  // A vehicle that answered, then went silent for the vehicle time-out
  // (one pause on a loaded host), spoils the trial, not the study: a
  // synthetic trial is run again once, with a vehicle of its own, as a
  // flagged one is ('redo': the next row is its attempt 2). Lost again,
  // the vehicle stays lost, and the study stops as before.
  if (!person_ && run.result.outcome == mediator::Outcome::kVehicleLost &&
      lost_reruns_.insert({trial.participant, trial.position}).second) {
    store_->Event("redo", trial.participant, trial.position,
                  "run " + std::to_string(run.run_id) + ": " + run.result.message +
                      ": run again once by itself");
    std::fprintf(stderr, "[study]   flagged (%s): run again once (run %lld)\n",
                 run.result.message.c_str(), static_cast<long long>(run.run_id));
    return Then::kOffer;
  }
  // Not a finished trial: the run is recorded, the trial is not.
  store_->Event("trial not finished", trial.participant, trial.position,
                mediator::ToString(run.result.outcome) + ": " + run.result.message);
  tally_.stopped = mediator::ToString(run.result.outcome) + ": " + run.result.message;
  tally_.exit_code = mediator::ExitCode(run.result.outcome);
  if (tally_.exit_code == cli::kExitOk) tally_.exit_code = cli::kExitFailed;
  return Then::kStop;
}

void StudyRun::AfterFinishedTrial(const PlannedTrial& trial, const mediator::RecordedRun& run) {
  const record::RunRecord& r = run.result.record;
  std::fprintf(stderr, "[study]   %s: lap %s s%s, %d obstacles, %d slips (run %lld)\n",
               mediator::ToString(run.result.outcome).c_str(), Seconds(r.lap_time_s).c_str(),
               r.completed ? "" : (" (scored " + Seconds(config_.trial_cap_s) + " s)").c_str(),
               r.obstacles_touched, run.result.operator_slips, static_cast<long long>(run.run_id));
  // The lap is recorded, so the trial stands; what else it should
  // have written is lost, which the experimenter must hear of.
  if (const std::string failure = OutputFailure(run.result); !failure.empty()) {
    ++tally_.outputs_failed;
    std::fprintf(stderr, "[study]   output failed: participant %s, position %d, %s: %s\n",
                 trial.participant.c_str(), trial.position, trial.condition.c_str(),
                 failure.c_str());
    store_->Event("output failed", trial.participant, trial.position,
                  "run " + std::to_string(run.run_id) + ": " + failure);
  }
  // Nobody watches a synthetic study to redo a spoiled trial: a flagged
  // one runs again once, now, by itself; both are kept (the first as
  // superseded), the report counts the second. People's flagged trials
  // are the experimenter's to redo, from the console.
  if (!person_ && store_->RedoFlaggedOnce(trial)) {
    std::fprintf(stderr, "[study]   flagged (%s): run again once\n", TrialFlags(r).c_str());
  }
}

mediator::RecordedRun StudyRun::RunWatched(const mediator::SessionSetup& setup,
                                           const record::Recorder::AlsoSave& also,
                                           const record::TrialOfRun& trial) {
  std::atomic<bool> trial_stop{false};
  std::atomic<bool> trial_over{false};
  std::thread watch(&StudyRun::WatchForStop, this, std::ref(trial_stop), std::cref(trial_over));
  mediator::RecordedRun run;
  try {
    run = mediator::RunAndRecord(setup, *recorder_, trial_stop, also, trial);
  } catch (...) {
    trial_over.store(true);
    watch.join();
    throw;
  }
  trial_over.store(true);
  watch.join();
  if (console_) console_->SetLive("");
  // The trial's threads are gone (its DDS participant, physics, view,
  // decoder), their heaps freed but kept by the allocator's arenas: given
  // back, so that a study's memory does not grow by each trial's.
  malloc_trim(0);
  return run;
}

/// Sets `stop` on a signal or the console's Abort, until `over`.
void StudyRun::WatchForStop(std::atomic<bool>& stop, const std::atomic<bool>& over) const {
  while (!over.load()) {
    if (interrupted_.load() || (console_ && console_->abort_requested().load())) stop.store(true);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

// A run the database did not take (a full disk...) ends the study: the
// next would fail the same way. Said whole: what the lap did, why it was
// not saved, and where its results are; the event is best effort, the
// database having just failed.
void StudyRun::NotSaved(const mediator::RecordedRun& run, const std::string& what,
                        const std::string& participant, int position,
                        const std::string& condition) {
  tally_.unsaved_file = run.unsaved;
  tally_.stopped =
      what + " not saved (participant " + participant +
      (position > 0 ? ", position " + std::to_string(position) + ", " + condition : std::string()) +
      "): outcome " + mediator::ToString(run.result.outcome) + " (" + run.result.message +
      "), but the database failed: " + run.save_error + "; " +
      (run.unsaved.empty() ? std::string("and no file could take its results (see above)")
                           : "its results are in " + run.unsaved.string());
  std::fprintf(stderr, "[study]   NOT SAVED: %s\n", tally_.stopped.c_str());
  try {
    store_->Event("not saved", participant, position, tally_.stopped);
  } catch (const std::exception&) {
  }
  tally_.exit_code = cli::kExitNotRecorded;
}

/// Each condition's scored lap times (and how many), over the trials.
struct ConditionTotals {
  std::map<std::string, double> lap_time_s;
  std::map<std::string, int> trials;
};

/// The schedule as it stands: participants × conditions, scored lap times;
/// returns each condition's totals.
ConditionTotals PrintSchedule(const StudyConfig& config, const std::vector<PlannedTrial>& plan,
                              const std::vector<TrialRow>& trials) {
  std::printf("  %-12s", "participant");
  for (const StudyCondition& c : config.conditions) std::printf(" %16s", c.name.c_str());
  std::printf("\n");
  std::vector<std::string> participants;
  for (const PlannedTrial& t : plan) {
    if (std::find(participants.begin(), participants.end(), t.participant) == participants.end()) {
      participants.push_back(t.participant);
    }
  }
  ConditionTotals totals;
  for (const std::string& p : participants) {
    std::printf("  %-12s", p.c_str());
    for (const StudyCondition& c : config.conditions) {
      std::string cell = "-";
      for (const TrialRow& t : trials) {
        if (t.participant != p || t.condition != c.name) continue;
        cell = Seconds(t.lap_time_s) + (t.completed ? "" : "*") + " (" +
               std::to_string(t.position) + ")";
        totals.lap_time_s[c.name] += t.lap_time_s;
        totals.trials[c.name] += 1;
      }
      std::printf(" %16s", cell.c_str());
    }
    std::printf("\n");
  }
  std::printf("  %-12s", "total");
  for (const StudyCondition& c : config.conditions)
    std::printf(" %16s", Seconds(totals.lap_time_s[c.name]).c_str());
  std::printf(
      "\n  (lap time s as scored, on the lap's clock from the start line, position in brackets; "
      "* unfinished, scored at the %s s cap, also on the lap's clock)\n",
      Seconds(config.trial_cap_s).c_str());
  return totals;
}

/// `--json`'s line: the study, the trials and per-condition totals.
std::string StudyRunJson(const StudyConfig& config, const std::filesystem::path& database,
                         const std::vector<PlannedTrial>& plan, const std::vector<TrialRow>& trials,
                         bool finished, double speedup, const StudyRunTally& tally,
                         ConditionTotals& totals) {
  std::string out =
      "{\"study\":" + JsonString(config.name) + ",\"database\":" + JsonString(database.string()) +
      ",\"finished\":" + (finished ? "true" : "false") +
      ",\"trials_planned\":" + std::to_string(plan.size()) +
      ",\"trials_done\":" + std::to_string(trials.size()) +
      ",\"trials_done_before\":" + std::to_string(tally.done_before) +
      ",\"stopped\":" + JsonString(tally.stopped) +
      ",\"unsaved_file\":" + JsonString(tally.unsaved_file.string()) +
      ",\"speedup\":" + (speedup > 0.0 ? JsonNumber(speedup) : std::string("null")) +
      ",\"outputs_failed\":" + std::to_string(tally.outputs_failed) + ",\"conditions\":[";
  for (size_t i = 0; i < config.conditions.size(); ++i) {
    const std::string& name = config.conditions[i].name;
    if (i > 0) out += ",";
    out += "{\"name\":" + JsonString(name) + ",\"trials\":" + std::to_string(totals.trials[name]) +
           ",\"total_lap_time_s\":" + JsonNumber(totals.lap_time_s[name]) + "}";
  }
  out += "],\"trials\":[";
  for (size_t i = 0; i < trials.size(); ++i) {
    const TrialRow& t = trials[i];
    if (i > 0) out += ",";
    out += "{\"participant\":" + JsonString(t.participant) +
           ",\"position\":" + std::to_string(t.position) +
           ",\"condition\":" + JsonString(t.condition) + ",\"device\":" + JsonString(t.device) +
           ",\"lap_time_s\":" + JsonNumber(t.lap_time_s) + ",\"approach_s\":" +
           (std::isfinite(t.approach_s) ? JsonNumber(t.approach_s) : std::string("null")) +
           ",\"completed\":" + (t.completed ? "true" : "false") +
           ",\"obstacles\":" + std::to_string(t.obstacles) +
           ",\"run_id\":" + std::to_string(t.run_id) + "}";
  }
  out += "]}";
  return out;
}

/// The study's state after the trials run now, on stdout: the schedule,
/// the speed-up, lost outputs, how to report, and `--json`'s line.
void ReportStudyRun(const StudyRunOptions& options, const StudyRunPlan& p, StudyStore& store,
                    const StudyRunTally& tally, const std::atomic<bool>& interrupted) {
  const StudyConfig& config = p.config;
  const std::vector<PlannedTrial> plan =
      store.Plan();  // with the participants added in the console
  const std::vector<TrialRow> trials = store.Trials();
  const bool finished = trials.size() == plan.size() && !interrupted.load();
  if (finished) store.Event("finished", "", 0, std::to_string(trials.size()) + " trials");
  std::printf("study %s: %zu of %zu trials%s\n", config.name.c_str(), trials.size(), plan.size(),
              finished ? ", finished" : (", stopped: " + tally.stopped).c_str());
  ConditionTotals totals = PrintSchedule(config, plan, trials);
  const double speedup =
      options.simulated_time && tally.wall_s > 0.0 ? tally.simulated_s / tally.wall_s : 0.0;
  if (speedup > 0.0) {
    std::printf(
        "  simulated time: %.1f s simulated in %.1f s wall-clock over the trials run now, %.1fx "
        "real "
        "time\n",
        tally.simulated_s, tally.wall_s, speedup);
  }
  if (tally.outputs_failed > 0) {
    std::printf(
        "  outputs failed: %d trial%s run now lost %s CAN bus log or view recording (the laps "
        "are "
        "recorded; the [study] lines above say which and why)\n",
        tally.outputs_failed, tally.outputs_failed == 1 ? "" : "s",
        tally.outputs_failed == 1 ? "its" : "their");
  }
  std::printf("  report: haptel study report %s --study %s\n", p.database.c_str(),
              config.name.c_str());
  if (options.json) {
    std::printf(
        "%s\n",
        StudyRunJson(config, p.database, plan, trials, finished, speedup, tally, totals).c_str());
  }
  std::fflush(stdout);
}

}  // namespace

int RunStudy(const StudyRunOptions& options, const std::atomic<bool>& interrupted) {
  const StudyRunPlan plan = cli::ReadInput([&] { return PlanStudyRun(options); });
  StudyRun run(options, plan, interrupted);
  run.Open();
  run.RunTrials();
  ReportStudyRun(options, plan, run.store(), run.tally(), interrupted);
  return run.tally().exit_code;
}

}  // namespace haptel::study
