#include "haptel/config/study.hpp"

#include <algorithm>
#include <optional>
#include <set>

#include "haptel/config/check.hpp"
#include "haptel/config/device.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/interface_kinds.hpp"
#include "haptel/config/link.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/reality.hpp"
#include "haptel/config/run.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/config/yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

namespace {

DriverProfile ReadProfile(YamlMap map) {
  DriverProfile p;
  for (const DriverProfileTrait& t : DriverProfileTraits()) {
    p.*t.member = map.Number(t.key, p.*t.member);
  }
  p.seed = static_cast<uint64_t>(map.Integer("seed", static_cast<int>(p.seed), 0, 1 << 30));
  map.Finish();
  config_detail::ValidateIn(map, p);
  return p;
}

/// Names in reports, file names and web forms: short and plain.
bool PlainName(const std::string& name) { return IsPlainName(name); }

constexpr const char* kPlainName = "a name of 1 to 40 letters, digits, '-', '_' or '.'";

}  // namespace

bool IsPlainName(const std::string& name) {
  if (name.empty() || name.size() > 40) return false;
  for (const char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '-' || c == '_' || c == '.';
    if (!ok) return false;
  }
  return true;
}

const std::vector<DriverProfileTrait>& DriverProfileTraits() {
  static const std::vector<DriverProfileTrait> kTraits = {
      {"steering_noise", &DriverProfile::steering_noise, 0.0, 1.0},
      {"noise_time_s", &DriverProfile::noise_time_s, 0.01, 10.0},
      {"slip_rate_hz", &DriverProfile::slip_rate_hz, 0.0, 5.0},
      {"regrasp_s", &DriverProfile::regrasp_s, 0.1, 10.0},
      {"holding_reaction_s", &DriverProfile::holding_reaction_s, 0.0, 2.0},
      {"holding_cruise", &DriverProfile::holding_cruise, 0.1, 1.0},
      {"stay_put_cruise", &DriverProfile::stay_put_cruise, 0.1, 1.0},
      {"recentre_s", &DriverProfile::recentre_s, 0.0, 10.0},
      {"recentre_error", &DriverProfile::recentre_error, 0.0, 0.5},
      {"hud_use", &DriverProfile::hud_use, 0.0, 1.0},
      {"unsure_cruise", &DriverProfile::unsure_cruise, 0.1, 1.0},
      {"learning_gain", &DriverProfile::learning_gain, 0.0, 10.0},
      {"learning_trials", &DriverProfile::learning_trials, 0.1, 100.0},
  };
  return kTraits;
}

void DriverProfile::ValidateOrThrow() const {
  for (const DriverProfileTrait& t : DriverProfileTraits())
    check::Number(t.key, this->*t.member, t.min, t.max);
}

void StudyConfig::ValidateOrThrow() const {
  check::NonEmpty("name", name);
  if (operators != "synthetic" && operators != "person")
    check::Fail("operators", "synthetic or person");
  check::Number("trial_cap_s", trial_cap_s, 5.0, 3600.0);
  check::Whole("design.repetitions", repetitions, 1, 10);
  if (conditions.size() < 2 || conditions.size() > 10) {
    check::Fail("conditions", "a list of 2 to 10 conditions, each {name, interface}");
  }
  for (const auto& [name, profile] : profiles) check::Nested("profiles." + name, profile);
}

std::string ToString(StudyOrder order) {
  switch (order) {
    case StudyOrder::kBalancedLatinSquare:
      return "balanced-latin-square";
    case StudyOrder::kRandom:
      return "random";
    case StudyOrder::kFixed:
      return "fixed";
  }
  return "?";
}

namespace {

/// `link_fault` and `link_profile`, each checked as it will be used.
void ReadStudyLink(YamlMap& root, const std::filesystem::path& dir, StudyConfig& s) {
  s.link_fault = root.String("link_fault", "");
  if (!s.link_fault.empty()) {
    try {
      ParseLinkFault(s.link_fault);
    } catch (const std::invalid_argument& e) {
      root.Fail("link_fault", e.what());
    }
  }
  s.link_profile = root.String("link_profile", "");
  // A profile file is relative to the study file, as `run` and `track` are; a name is shipped.
  if (s.link_profile.find('/') != std::string::npos ||
      std::filesystem::path(s.link_profile).extension() == ".yaml") {
    s.link_profile = (dir / s.link_profile).string();
  }
  if (!s.link_profile.empty()) {
    try {
      LoadLinkProfile(s.link_profile);
    } catch (const ConfigError& e) {
      root.Fail("link_profile", e.what());
    }
  }
}

/// The trials' reality: a shipped name (none, lab, harsh) or a file relative
/// to the study file, as `link_profile` is; only a simulated vehicle has one.
void ReadStudyReality(YamlMap& root, const std::filesystem::path& dir, const RunConfig& run,
                      StudyConfig& s) {
  const std::string reality = root.String("reality", "");
  if (reality.empty()) return;
  s.reality = RealityFile(reality);
  if (s.reality.string() != reality) {
    if (!std::filesystem::is_regular_file(s.reality))
      root.Fail("reality", "none, lab, harsh or a reality file (not '" + reality + "')");
  } else {
    s.reality = dir / reality;
    if (!std::filesystem::is_regular_file(s.reality))
      root.Fail("reality", "a reality file; no file '" + s.reality.string() + "'");
  }
  try {
    LoadReality(s.reality);
  } catch (const ConfigError& e) {
    root.Fail("reality", e.what());
  }
  const VehicleConfig vehicle = LoadVehicle(run.vehicle);
  if (!vehicle.Kind().simulated) {
    root.Fail("reality", "a simulated vehicle; the run's vehicle '" + vehicle.file.string() +
                             "' is " + vehicle.kind + ", whose reality is the world's");
  }
}

/// A condition's input device: the file it names (relative to the study
/// file's folder), else the run configuration's; loaded and checked as a
/// device file is, a bad one named with the condition's key.
void ReadConditionDevice(YamlMap& c, const std::filesystem::path& dir, const RunConfig& run_config,
                         StudyCondition& condition) {
  const std::string named = c.String("device", "");  // an empty one is refused as such
  condition.device = named.empty() ? run_config.device : dir / named;
  try {
    condition.device_name = LoadDevice(condition.device).name;
  } catch (const ConfigError& e) {
    c.Fail("device", "a device file (config/devices/*.yaml) that loads: " + std::string(e.what()));
  }
}

/// A condition's camera set-up (`cameras:`, `station:`) against the cameras
/// of the run's vehicle file: names it has, each once, the driven one among
/// them (the pilot flies by it); a station's camera one that streams and
/// that a station can hold (not the driven one).
void ReadConditionCameras(YamlMap& c, const VehicleConfig& vehicle, StudyCondition& condition) {
  std::vector<std::string> names{vehicle.camera.name};
  for (const CameraConfig& extra : vehicle.extra_cameras) names.push_back(extra.name);
  std::string known;
  for (const std::string& n : names) known += (known.empty() ? "" : ", ") + n;
  const std::string of = " of vehicle '" + vehicle.file.string() + "' (" + known + ")";
  const auto has = [&names](const std::string& n) {
    return std::find(names.begin(), names.end(), n) != names.end();
  };
  condition.cameras = c.Strings("cameras", {});
  if (c.Has("cameras")) {
    std::set<std::string> seen;
    for (const std::string& n : condition.cameras) {
      if (!has(n)) c.Fail("cameras", "a list of cameras" + of + "; no camera '" + n + "'");
      if (!seen.insert(n).second) c.Fail("cameras", "each camera once ('" + n + "' twice)");
    }
    if (seen.count(vehicle.camera.name) == 0) {
      c.Fail("cameras", "the driven camera '" + vehicle.camera.name +
                            "' among them (the pilot flies by its picture)");
    }
  }
  condition.station = c.String("station", "");
  if (!c.Has("station")) return;
  if (!has(condition.station))
    c.Fail("station", "a camera" + of + " a station holds; no camera '" + condition.station + "'");
  if (condition.station == vehicle.camera.name) {
    c.Fail("station", "a camera other than the driven one ('" + vehicle.camera.name +
                          "' turns with the pilot's commands, not a station's)");
  }
  if (!condition.cameras.empty() && std::find(condition.cameras.begin(), condition.cameras.end(),
                                              condition.station) == condition.cameras.end()) {
    c.Fail("station", "a camera of this condition's 'cameras' (a station needs its picture); '" +
                          condition.station + "' is not streamed");
  }
}

/// The conditions: each names an interface file of the run configuration
/// (`run_config`), one a simulated driver can use when `synthetic`, and the
/// device it is driven with.
void ReadConditions(YamlMap& root, const std::filesystem::path& dir, const RunConfig& run_config,
                    bool synthetic, StudyConfig& s) {
  std::vector<YamlMap> conditions = root.MapList("conditions");
  if (conditions.size() < 2 || conditions.size() > 10) {
    root.Fail("conditions", "a list of 2 to 10 conditions, each {name, interface, predict}");
  }
  std::set<std::string> condition_names;
  std::optional<VehicleConfig> vehicle;  // read once, when a condition names cameras
  for (YamlMap& c : conditions) {
    StudyCondition condition;
    condition.interface = c.RequireString("interface");
    condition.name = c.String("name", condition.interface);
    condition.predict = c.Bool("predict", false);
    ReadConditionDevice(c, dir, run_config, condition);
    if (c.Has("cameras") || c.Has("station")) {
      if (!vehicle) vehicle = LoadVehicle(run_config.vehicle);
      ReadConditionCameras(c, *vehicle, condition);
    }
    if (!PlainName(condition.name)) c.Fail("name", kPlainName);
    if (!condition_names.insert(condition.name).second) {
      c.Fail("name", "a name no other condition has ('" + condition.name + "' is taken)");
    }
    try {
      const std::string declared = InterfaceName(InterfaceFile(run_config, condition.interface));
      const InterfaceKindInfo* kind = FindInterfaceKind(declared);
      const bool manual = kind != nullptr && kind->manual();
      if (synthetic && manual) {
        c.Fail("interface", "an interface a simulated driver can use (gesture or a cockpit); '" +
                                condition.interface + "' is a person's keys or controller");
      }
    } catch (const ConfigError& e) {
      if (std::string(e.what()).find(c.Path("interface")) != std::string::npos) throw;
      c.Fail("interface", "an interface of " + s.run.string() + " (" + e.what() + ")");
    }
    c.Finish();
    s.conditions.push_back(condition);
  }
}

/// The participants: unique ids, and a simulated driver's profile.
void ReadParticipants(YamlMap& root, bool synthetic, StudyConfig& s) {
  std::vector<YamlMap> participants = root.MapList("participants");
  std::set<std::string> ids;
  for (YamlMap& p : participants) {
    StudyParticipant participant;
    participant.id = p.RequireString("id");
    if (!PlainName(participant.id)) p.Fail("id", kPlainName);
    if (!ids.insert(participant.id).second) {
      p.Fail("id", "an id no other participant has ('" + participant.id + "' appears twice)");
    }
    participant.profile = p.String("profile", "");
    if (synthetic) {
      if (participant.profile.empty())
        p.Fail("profile", "the profile of this simulated driver (a key of 'profiles')");
      if (s.profiles.count(participant.profile) == 0) {
        p.Fail("profile", "a key of 'profiles', got '" + participant.profile + "'");
      }
    } else if (!participant.profile.empty()) {
      p.Fail("profile",
             "no profile: participants of a person study are people (operators: person)");
    }
    p.Finish();
    s.participants.push_back(participant);
  }
  if (synthetic && s.participants.empty()) {
    root.Fail(
        "participants",
        "the simulated drivers, each {id, profile} (a synthetic study has no console to add them)");
  }
}

/// `design`: the order of conditions, its seed, the repetitions.
void ReadDesign(YamlMap& root, StudyConfig& s) {
  YamlMap design = root.Map("design");
  const std::string order = design.String("order", ToString(s.order));
  if (order == "balanced-latin-square") {
    s.order = StudyOrder::kBalancedLatinSquare;
  } else if (order == "random") {
    s.order = StudyOrder::kRandom;
  } else if (order == "fixed") {
    s.order = StudyOrder::kFixed;
  } else {
    design.Fail("order", "balanced-latin-square, random or fixed");
  }
  s.seed = static_cast<uint64_t>(design.Integer("seed", static_cast<int>(s.seed), 0, 1 << 30));
  if (s.order != StudyOrder::kRandom && design.Has("seed"))
    design.Fail("seed", "no seed unless order: random");
  s.repetitions = design.Integer("repetitions", s.repetitions, 1, 10);
  design.Finish();
}

/// The questionnaires asked after each condition, and the demographics one
/// asked once before a participant's first trial.
void ReadQuestionnaires(YamlMap& root, bool synthetic, StudyConfig& s) {
  s.questionnaires = root.Strings("questionnaires", {});
  std::set<std::string> seen;
  for (const std::string& q : s.questionnaires) {
    if (!seen.insert(q).second)
      root.Fail("questionnaires", "each questionnaire once ('" + q + "' twice)");
  }
  // The participants' background, asked once before a participant's first
  // trial: a questionnaire of the same folder, not one of those asked after
  // each condition.
  s.demographics = root.String("demographics", "");
  if (root.Has("demographics")) {
    if (!PlainName(s.demographics))
      root.Fail("demographics", std::string(kPlainName) + ": a questionnaire's name");
    if (seen.count(s.demographics) > 0) {
      root.Fail("demographics", "a questionnaire not also asked after each condition ('" +
                                    s.demographics + "' is in 'questionnaires')");
    }
    if (synthetic)
      root.Fail("demographics", "no demographics for simulated drivers (they have no background)");
  }
}

}  // namespace

std::string CameraSetupText(const StudyCondition& condition) {
  std::string text;
  for (const std::string& camera : condition.cameras)
    text += (text.empty() ? "cameras " : " + ") + camera;
  if (!condition.station.empty())
    text += (text.empty() ? "" : ", ") + std::string("a station holds ") + condition.station;
  return text;
}

StudyConfig LoadStudy(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  const std::filesystem::path dir = file.parent_path();
  StudyConfig s;
  s.file = file;
  s.name = root.RequireString("name");
  if (!PlainName(s.name)) root.Fail("name", kPlainName);
  s.description = root.String("description", "");
  const std::string run = root.String("run", "");
  s.run = run.empty() ? ShippedFile("config/haptel.yaml") : dir / run;
  const RunConfig run_config = LoadRun(s.run);
  const std::string track = root.String("track", "");
  s.track = track.empty() ? run_config.track : dir / track;
  if (const std::string db = root.String("database", ""); !db.empty()) s.database = db;
  ReadStudyLink(root, dir, s);
  ReadStudyReality(root, dir, run_config, s);
  s.operators = root.String("operators", s.operators);
  if (s.operators != "synthetic" && s.operators != "person")
    root.Fail("operators", "synthetic or person");
  const bool synthetic = s.operators == "synthetic";

  ReadConditions(root, dir, run_config, synthetic, s);
  // Simulated drivers' profiles, by name.
  YamlMap profiles = root.Map("profiles");
  for (const std::string& name : profiles.Keys()) {
    s.profiles[name] = ReadProfile(profiles.Map(name));
  }
  profiles.Finish();

  ReadParticipants(root, synthetic, s);
  ReadDesign(root, s);
  s.practice = root.Bool("practice", s.practice);
  s.sessions = root.Bool("sessions", s.sessions);
  s.trial_cap_s = root.Number("trial_cap_s", s.trial_cap_s);
  ReadQuestionnaires(root, synthetic, s);
  const std::string qdir = root.String("questionnaires_dir", "");
  s.questionnaires_dir = qdir.empty() ? ShippedFile("config/questionnaires") : dir / qdir;
  root.Finish();
  config_detail::ValidateIn(root, s);
  return s;
}

}  // namespace haptel
