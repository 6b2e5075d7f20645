#pragma once
/// @file What defines a study, in a canonical form the database keeps
/// (studies.definition_form, schema v6) so that a resumed study can be
/// compared with its file key by key, and a change refused naming each key
/// and both values.
///
/// The form is one `key: value` line per thing that changes what a trial is
/// or how it is scored, in a fixed order: the operators, the run
/// configuration and the track (by path, relative to the study file's
/// folder, and the track's geometry as loaded: gates, obstacles, lap cap,
/// corridor, centre line), the conditions in order with their interfaces and
/// devices (by path), the
/// design (order, seed, repetitions), the practice lap, the cap per trial,
/// the questionnaires in order and their folder, the participants the file
/// lists in order, and the profiles those participants drive with (every
/// field). Formatting is canonical: numbers in their shortest exact form,
/// lists in order joined by ", ", "(none)" for nothing — so two files that
/// load to the same study give the same form, whatever their comments,
/// spacing or key order.
///
/// Not in the form, so free to change: the name (it is the study's key),
/// the description, the database, the file's own path, profiles no
/// participant uses, and participants added in the console (they are the
/// record's, not the file's). The contents of the run configuration, its
/// interface files and the questionnaires are named by path, not compared.
#include <string>
#include <vector>

#include "haptel/config/study.hpp"

namespace haptel::study {

/// One line of a study's definition.
struct DefiningValue {
  std::string key;    ///< e.g. "trial_cap_s", "conditions.b.interface"
  std::string value;  ///< e.g. "600", "cockpit-hud"
};

/// The version of the form's keys, its first line ("form: 2"). Forms of
/// different versions are compared only on the keys both have. Form 2 adds
/// each condition's device (conditions.NAME.device, by path).
constexpr int kDefinitionFormVersion = 2;

/// The canonical form of `config` (see the file's comment). Loads the track
/// when `config.track` is set: throws ConfigError naming the track file when
/// it cannot be loaded (the trials could not run on it either).
std::vector<DefiningValue> StudyDefinition(const StudyConfig& config);

/// As stored: one "key: value" line each, in order (a newline, a backslash
/// in a value, or a ':' in a key is escaped with a backslash).
std::string DefinitionText(const std::vector<DefiningValue>& values);

/// The lines of DefinitionText back; lines that are not "key: value" are
/// skipped.
std::vector<DefiningValue> ParseDefinition(const std::string& text);

/// Each key whose value differs between the definition on record and the
/// file's now, as "KEY: RECORDED, the file now says NOW" (a key only one
/// side has reads "(absent)" on the other), in the recorded order and then
/// the file's new keys; when the track's path changed, not its geometry's
/// keys too. Empty when the two define the same study.
std::vector<std::string> DefinitionChanges(const std::vector<DefiningValue>& recorded,
                                           const std::vector<DefiningValue>& now);

}  // namespace haptel::study
