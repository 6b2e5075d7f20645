#include "haptel/study/definition.hpp"

#include <charconv>
#include <cstdlib>
#include <map>
#include <set>

#include "haptel/config/blimp_course.hpp"
#include "haptel/config/link.hpp"
#include "haptel/config/run.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/core/args.hpp"

namespace haptel::study {
namespace {

namespace fs = std::filesystem;

constexpr const char* kNone = "(none)";

/// The shortest text that reads back as exactly `value` (5, 0.05, 3600).
std::string Number(double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

std::string Joined(const std::vector<std::string>& items) {
  return items.empty() ? kNone : JoinList(items, ", ");
}

/// Relative to the study file's folder, as the file would say it: the same
/// study resumes from another working directory, or with its folder moved
/// together with what it names.
std::string FromStudyFolder(const StudyConfig& config, const fs::path& path) {
  if (path.empty()) return kNone;
  const fs::path folder = fs::absolute(config.file).parent_path().lexically_normal();
  const fs::path target = fs::absolute(path).lexically_normal();
  const fs::path relative = target.lexically_relative(folder);
  return relative.empty() ? target.generic_string() : relative.generic_string();
}

/// "(x, y)", built piecewise: GCC 12 warns falsely (-Wrestrict) on "(" + string.
std::string Point(const Vec2& p) {
  std::string text(1, '(');
  text += Number(p.x());
  text += ", ";
  text += Number(p.y());
  text += ')';
  return text;
}

/// The track as the trials drive and score it, whatever its file's comments.
void AddTrack(const fs::path& file, std::vector<DefiningValue>& out) {
  const TrackConfig track = LoadTrack(file);
  out.push_back({"track.name", track.name});
  out.push_back({"track.lap_cap_s", Number(track.lap_cap_s)});
  out.push_back({"track.corridor_width_m", Number(track.corridor_width)});
  out.push_back({"track.post_radius_m", Number(track.post_radius)});
  out.push_back({"track.start_behind_m", Number(track.start_behind)});
  for (size_t i = 0; i < track.centerline.size(); ++i) {
    out.push_back({"track.centerline[" + std::to_string(i + 1) + "]", Point(track.centerline[i])});
  }
  for (size_t i = 0; i < track.gates.size(); ++i) {
    out.push_back({"track.gates[" + std::to_string(i + 1) + "]",
                   "along " + Number(track.gates[i].along) + " m, width " +
                       Number(track.gates[i].width) + " m"});
  }
  for (size_t i = 0; i < track.obstacles.size(); ++i) {
    out.push_back({"track.obstacles[" + std::to_string(i + 1) + "]",
                   "centre " + Point(track.obstacles[i].center) + " m, radius " +
                       Number(track.obstacles[i].radius) + " m"});
  }
}

/// A blimp's course as its trials fly and score it.
void AddCourse(const fs::path& file, std::vector<DefiningValue>& out) {
  const BlimpCourseConfig course = LoadBlimpCourse(file);
  out.push_back({"track.name", course.name});
  out.push_back({"track.lap_cap_s", Number(course.lap_cap_s)});
  out.push_back({"track.gates", std::to_string(course.gates.size())});
  out.push_back({"track.buildings", std::to_string(course.buildings.size())});
  out.push_back({"track.crash_speed_m_s", Number(course.crash_speed)});
}

void AddProfile(const std::string& name, const DriverProfile& p, std::vector<DefiningValue>& out) {
  const std::string key = "profiles." + name + ".";
  const std::pair<const char*, double> fields[] = {
      {"steering_noise", p.steering_noise},
      {"noise_time_s", p.noise_time_s},
      {"slip_rate_hz", p.slip_rate_hz},
      {"regrasp_s", p.regrasp_s},
      {"holding_reaction_s", p.holding_reaction_s},
      {"holding_cruise", p.holding_cruise},
      {"stay_put_cruise", p.stay_put_cruise},
      {"recentre_s", p.recentre_s},
      {"recentre_error", p.recentre_error},
      {"hud_use", p.hud_use},
      {"unsure_cruise", p.unsure_cruise},
      {"learning_gain", p.learning_gain},
      {"learning_trials", p.learning_trials},
  };
  for (const auto& [field, value] : fields) out.push_back({key + field, Number(value)});
  out.push_back({key + "seed", std::to_string(p.seed)});
}

/// Backslash escapes: `specials` are the characters escaped besides the
/// backslash itself ('\n' is written as "\n").
std::string Escaped(const std::string& text, const std::string& specials) {
  std::string out;
  for (const char c : text) {
    if (c == '\n') {
      out += "\\n";
    } else if (c == '\\' || specials.find(c) != std::string::npos) {
      out += '\\';
      out += c;
    } else {
      out += c;
    }
  }
  return out;
}

std::string Unescaped(const std::string& text) {
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\\' && i + 1 < text.size()) {
      ++i;
      out += text[i] == 'n' ? '\n' : text[i];
    } else {
      out += text[i];
    }
  }
  return out;
}

int FormVersion(const std::vector<DefiningValue>& values) {
  for (const DefiningValue& v : values) {
    if (v.key == "form") return std::atoi(v.value.c_str());
  }
  return 0;
}

}  // namespace

std::vector<DefiningValue> StudyDefinition(const StudyConfig& config) {
  std::vector<DefiningValue> out;
  out.push_back({"form", std::to_string(kDefinitionFormVersion)});
  out.push_back({"operators", config.operators});
  out.push_back({"run", FromStudyFolder(config, config.run)});
  out.push_back({"track", FromStudyFolder(config, config.track)});
  if (!config.track.empty()) {
    // A blimp study flies a course (the run file's vehicle says which; with
    // no run file, haptel run's default vehicle, a robot, drives a track).
    const bool blimp = !config.run.empty() &&
                       LoadVehicle(LoadRun(config.run).vehicle).family() == VehicleFamily::kBlimp;
    (blimp ? AddCourse : AddTrack)(config.track, out);
  }

  std::vector<std::string> conditions;
  for (const StudyCondition& c : config.conditions) conditions.push_back(c.name);
  out.push_back({"conditions", Joined(conditions)});
  for (const StudyCondition& c : config.conditions) {
    out.push_back({"conditions." + c.name + ".interface", c.interface});
    // Keys written only when set: forms stored before they existed still match.
    if (c.predict) out.push_back({"conditions." + c.name + ".predict", "true"});
    // Form 2: the device a person holds changes what the trial is. By path,
    // as the run file is (its contents are not compared).
    out.push_back({"conditions." + c.name + ".device", FromStudyFolder(config, c.device)});
    // Its camera set-up, written only when set (as predict).
    if (!c.cameras.empty()) out.push_back({"conditions." + c.name + ".cameras", Joined(c.cameras)});
    if (!c.station.empty()) out.push_back({"conditions." + c.name + ".station", c.station});
  }

  out.push_back({"design.order", ToString(config.order)});
  out.push_back({"design.seed", std::to_string(config.seed)});
  out.push_back({"design.repetitions", std::to_string(config.repetitions)});
  out.push_back({"practice", config.practice ? "true" : "false"});
  out.push_back({"trial_cap_s", Number(config.trial_cap_s)});
  if (!config.link_fault.empty())
    out.push_back({"link_fault", LinkFaultText(ParseLinkFault(config.link_fault))});
  // The profile's name, and its figures (a shipped profile may be edited later).
  if (!config.link_profile.empty()) {
    out.push_back({"link_profile", config.link_profile});
    out.push_back({"link_profile_fault", LinkFaultText(LoadLinkProfile(config.link_profile))});
  }
  // Written only when set: studies planned before it existed still match.
  if (!config.reality.empty()) out.push_back({"reality", FromStudyFolder(config, config.reality)});
  out.push_back({"questionnaires", Joined(config.questionnaires)});
  out.push_back({"questionnaires_dir", FromStudyFolder(config, config.questionnaires_dir)});
  // Written only when asked: studies planned before it existed still match.
  if (!config.demographics.empty()) out.push_back({"demographics", config.demographics});

  // The file's participants, in order: their rows of the design. Those added
  // in the console later are not the file's and are not here.
  std::vector<std::string> ids;
  for (const StudyParticipant& p : config.participants) ids.push_back(p.id);
  out.push_back({"participants", Joined(ids)});
  std::set<std::string> used;
  for (const StudyParticipant& p : config.participants) {
    if (p.profile.empty()) continue;
    out.push_back({"participants." + p.id + ".profile", p.profile});
    used.insert(p.profile);
  }
  // Only the profiles someone drives with: an unused one changes no trial.
  for (const std::string& name : used) {
    const auto found = config.profiles.find(name);
    if (found != config.profiles.end()) AddProfile(name, found->second, out);
  }
  return out;
}

std::string DefinitionText(const std::vector<DefiningValue>& values) {
  std::string text;
  for (const DefiningValue& v : values)
    text += Escaped(v.key, ":") + ": " + Escaped(v.value, "") + "\n";
  return text;
}

std::vector<DefiningValue> ParseDefinition(const std::string& text) {
  std::vector<DefiningValue> values;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(start, end - start);
    start = end + 1;
    // The key ends at the first ':' no backslash escapes.
    size_t colon = std::string::npos;
    for (size_t i = 0; i < line.size(); ++i) {
      if (line[i] == '\\') {
        ++i;
      } else if (line[i] == ':') {
        colon = i;
        break;
      }
    }
    if (colon == std::string::npos || colon + 1 >= line.size() || line[colon + 1] != ' ') continue;
    values.push_back({Unescaped(line.substr(0, colon)), Unescaped(line.substr(colon + 2))});
  }
  return values;
}

std::vector<std::string> DefinitionChanges(const std::vector<DefiningValue>& recorded,
                                           const std::vector<DefiningValue>& now) {
  // A form of another version has other keys: only those both know compare
  // (a newer haptel resuming an older study does not refuse it for keys the
  // older one did not write).
  const bool same_version = FormVersion(recorded) == FormVersion(now);
  std::map<std::string, std::string> recorded_values;
  std::map<std::string, std::string> now_values;
  for (const DefiningValue& v : recorded) recorded_values[v.key] = v.value;
  for (const DefiningValue& v : now) now_values[v.key] = v.value;
  // Another track file differs in all its geometry: its path says it.
  const bool other_track = recorded_values["track"] != now_values["track"];
  auto follows = [&](const std::string& key) { return other_track && key.rfind("track.", 0) == 0; };
  std::vector<std::string> changes;
  for (const DefiningValue& v : recorded) {
    if (v.key == "form" || follows(v.key)) continue;
    const auto found = now_values.find(v.key);
    if (found == now_values.end()) {
      if (same_version) changes.push_back(v.key + ": " + v.value + ", the file now says (absent)");
    } else if (found->second != v.value) {
      changes.push_back(v.key + ": " + v.value + ", the file now says " + found->second);
    }
  }
  if (same_version) {
    for (const DefiningValue& v : now) {
      if (recorded_values.count(v.key) == 0 && !follows(v.key))
        changes.push_back(v.key + ": (absent), the file now says " + v.value);
    }
  }
  return changes;
}

}  // namespace haptel::study
