#pragma once
/// @file An A/B study (config/studies/*.yaml): which interfaces are compared
/// (the conditions), on which track, by whom (participants, each a person or
/// a simulated driver with a profile), in which order (the design), with a
/// practice lap, a cap per trial, repetitions, and the questionnaires each
/// condition is followed by. `haptel study run FILE` runs it.
///
/// The simulated drivers' profiles (DriverProfile) say how a person differs
/// from the ideal driver in ways that make interfaces differ for them: how
/// late and how steadily they steer, how often a virtual control slips out of
/// their hand, what it costs them to re-centre a control that stays where it
/// was left, whether they read the speedometer, and how fast they learn.
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace haptel {

/// A simulated driver's traits beyond the shared OperatorConfig. Defaults are
/// the ideal driver: all zero, the interfaces cannot tell apart.
struct DriverProfile {
  /// The steering wanders: an Ornstein–Uhlenbeck process added to the turn
  /// intent, with this standard deviation (fraction of a full turn)...
  double steering_noise = 0.0;
  double noise_time_s = 0.5;  ///< ...and this correlation time.
  /// While driving, a grasped virtual control slips out of the hand this
  /// often (per second and hand; a Poisson process). The hand then opens,
  /// lifts, comes back down and closes again over regrasp_s: a control that
  /// returns to zero stops the vehicle meanwhile, one that stays keeps
  /// driving it as it was left.
  double slip_rate_hz = 0.0;
  double regrasp_s = 1.2;
  /// Holding virtual controls takes attention from the road: the driver
  /// reacts this much later while the interface has controls to grasp (the
  /// thesis: drivers concentrated on grasping more than on driving).
  double holding_reaction_s = 0.0;
  /// ...and drives slower: forward command factor while holding virtual
  /// controls (1: as fast as with free hands).
  double holding_cruise = 1.0;
  /// A control that stays where it is left must be aimed back to its centre
  /// without a tactile reference, so the driver watches their hands (the
  /// thesis's drivers did) and holds back: forward command factor on such
  /// controls (1: no holding back)...
  double stay_put_cruise = 1.0;
  /// ...bringing it back takes this much longer than moving it away (s,
  /// added to the arm's time constant)...
  double recentre_s = 0.0;
  /// ...and misses the centre by this much (standard deviation, fraction of
  /// the control's range; drawn anew at each return).
  double recentre_error = 0.0;
  /// Share of the time the driver reads the speedometer when the interface
  /// shows one (0..1).
  double hud_use = 0.0;
  /// Cruise command factor when the driver has no speed cue (they hold back
  /// not to overshoot the next gate); 1: drives as if they knew the speed.
  double unsure_cruise = 1.0;
  /// Errors (noise, slips, re-centring) at the first trial are (1 + gain)
  /// times the practised ones, falling off with e-folding over
  /// learning_trials trials done before.
  double learning_gain = 0.0;
  double learning_trials = 2.0;
  /// Seeds the driver's random processes (with the trial's position).
  uint64_t seed = 1;

  /// Throws ConfigFieldError naming the first field out of its range.
  void ValidateOrThrow() const;
};

/// One numeric trait of DriverProfile: its key in the study file, its
/// member, and the range ValidateOrThrow accepts (so a tool that varies a
/// profile, `haptel study power`, keeps it valid without its own copy).
struct DriverProfileTrait {
  const char* key;
  double DriverProfile::*member;
  double min;
  double max;
};

/// Every numeric trait of DriverProfile (the seed is not one), in the
/// order ValidateOrThrow checks them.
const std::vector<DriverProfileTrait>& DriverProfileTraits();

/// One compared variant: a mediator interface (a file interfaces/NAME.yaml of
/// the run configuration), driven with an input device.
struct StudyCondition {
  std::string name;       ///< as the report shows it
  std::string interface;  ///< interfaces/<interface>.yaml
  /// The predictive display on (haptel run --predict on): two conditions
  /// may differ in this alone, to A/B-test it with the same interface.
  bool predict = false;
  /// The input device its trials are driven with (a device file,
  /// config/devices/*.yaml; `device:` in the file, relative to the study
  /// file's folder), loaded and checked by LoadStudy. Empty: the run
  /// configuration's device (LoadStudy fills it in).
  std::filesystem::path device{};
  /// That device file's `name:` ("mouse", "sdl-ff-wheel", "sim"), as the
  /// plan, the trials' rows and the report show it; filled in by LoadStudy.
  std::string device_name{};
  /// Its camera set-up, so camera layouts are A/B-tested like interfaces:
  /// the run vehicle's cameras that stream in its trials (`cameras: [pilot,
  /// surveillance]`; the driven one always among them), the others off.
  /// Empty: every camera of the vehicle file.
  std::vector<std::string> cameras{};
  /// A camera a second person must hold from a station (`station:
  /// surveillance`, `haptel station --camera surveillance`) before a trial
  /// may start; it streams. Empty: no station.
  std::string station{};
};

/// A condition's camera set-up as the console and the plan say it:
/// "cameras pilot + surveillance, a station holds surveillance"; "" for the
/// vehicle's own (no `cameras:`, no `station:`).
std::string CameraSetupText(const StudyCondition& condition);

struct StudyParticipant {
  std::string id;       ///< e.g. "A"; unique in the study
  std::string profile;  ///< simulated drivers only: a key of StudyConfig::profiles
};

enum class StudyOrder {
  kBalancedLatinSquare,  ///< Williams design: positions and carry-over balanced
  kRandom,               ///< a seeded shuffle per participant
  kFixed,                ///< every participant the conditions' order
};

struct StudyConfig {
  std::filesystem::path file;
  std::string name;
  std::string description;
  /// The run configuration the trials start from (interfaces, device,
  /// vehicle, link; default config/haptel.yaml).
  std::filesystem::path run;
  std::filesystem::path track;     ///< the trials' track
  std::filesystem::path database;  ///< empty: the run configuration's
  /// The link's fault for every trial, as `--link-fault` writes it
  /// ("delay=200ms,jitter=20ms,loss=2%"; empty: the run configuration's).
  std::string link_fault;
  /// A link profile for every trial (config/links/NAME.yaml, or a file), as
  /// `--link-profile` takes it; `link_fault`'s keys override it. Empty: none.
  std::string link_profile;
  /// The simulated vehicle's reality in every trial and practice lap
  /// (config/realities/NAME.yaml, or a file beside the study), as
  /// `--reality` takes it. Empty: the vehicle file's `reality:`, else lab.
  std::filesystem::path reality;
  /// "synthetic" (simulated drivers, unattended) or "person".
  std::string operators = "person";
  std::vector<StudyCondition> conditions;
  /// A person study may start with none and add them in the console.
  std::vector<StudyParticipant> participants;
  std::map<std::string, DriverProfile> profiles;
  StudyOrder order = StudyOrder::kBalancedLatinSquare;
  uint64_t seed = 1;  ///< for StudyOrder::kRandom
  /// A practice lap per participant before the first trial (a person: with
  /// the keyboard and the camera's view, as in the thesis).
  bool practice = true;
  /// A trial ends here; an unfinished lap is scored at the cap (the thesis's
  /// 10 minutes).
  double trial_cap_s = 600.0;
  int repetitions = 1;  ///< each participant's sequence this many times
  /// Filled in after each condition (names of config/questionnaires/*.yaml).
  std::vector<std::string> questionnaires;
  std::filesystem::path questionnaires_dir;
  /// The participants' background (a questionnaire of questionnaires_dir,
  /// e.g. the shipped `demographics`), asked once per participant before
  /// their first trial; its answers are stored with an empty condition.
  /// Empty: not asked. People only.
  std::string demographics;
  /// Each trial recorded whole into a session file (MCAP, `haptel run
  /// --session`: the link's samples, the video, the hands, the events), in
  /// `sessions/<study>/` beside the database; the database and the report
  /// name each trial's file. Practice laps are not recorded.
  bool sessions = true;

  /// Throws ConfigFieldError naming the first field that cannot work (the
  /// checks against files — interfaces, profiles named — are the loader's).
  void ValidateOrThrow() const;
};

/// Whether `name` can name a study, a condition or a participant: 1 to 40
/// letters, digits, '-', '_' or '.' (safe in file names, URLs and CSV).
bool IsPlainName(const std::string& name);

/// "balanced-latin-square", "random", "fixed".
std::string ToString(StudyOrder order);

/// Loads and checks a study file (strict: unknown keys, duplicate
/// participants or conditions, an unknown interface or profile are errors
/// naming the file, the line, the key and what was expected). Whether the
/// design fits the participants is the design's own check (study/stats).
StudyConfig LoadStudy(const std::filesystem::path& file);

}  // namespace haptel
