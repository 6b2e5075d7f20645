#pragma once
/// @file A participant's questionnaire, submitted (by the experimenter's
/// console's form): checked against the questionnaire, against the study's
/// order (only after the participant has driven that condition), and
/// against what is already recorded — then stored in one transaction, with
/// its score as one more row (item "score") when the questionnaire has one.
/// A form submitted twice, out of order or with a missing answer is refused
/// with a message, and never makes two rows.
#include <map>
#include <string>
#include <vector>

#include "haptel/study/answers.hpp"
#include "haptel/study/questionnaire.hpp"
#include "haptel/study/store.hpp"

namespace haptel::study {

/// What became of a submission: accepted, or why not — as an HTTP status
/// (400 unknown participant, condition or questionnaire; 409 out of order or
/// already answered; 422 answers that do not fit the questionnaire) with one
/// message, and per item for 422.
struct SubmissionResult {
  bool accepted = false;
  int status = 200;
  std::string message;
  std::vector<AnswerError> errors;
};

/// Checks and stores one questionnaire's answers from `participant` after
/// `condition`. `questionnaires`: the study's, by name. `demographics`: the
/// study's background questionnaire (StudyConfig::demographics; "" none),
/// answered once per participant with an empty `condition`, at any time
/// (the study asks for it before their first trial). Throws only if the
/// database fails.
SubmissionResult SubmitAnswers(StudyStore& store,
                               const std::map<std::string, Questionnaire>& questionnaires,
                               const std::string& participant, const std::string& condition,
                               const std::string& questionnaire,
                               const std::map<std::string, std::string>& fields,
                               const std::string& demographics = "");

/// The longest note the console takes, in characters (UTF-8 code points,
/// not bytes: a note in Japanese fits as well as one in English).
inline constexpr int kMaxNoteCharacters = 2000;

/// Checks and stores one of the experimenter's notes on `participant`'s
/// trial at `position` (as the form sends it, text; "0": on the participant
/// as a whole). Refused with a status and a message that says why: 400 an
/// unknown participant or a position not in their plan, 422 an empty note,
/// one that is not UTF-8 or longer than kMaxNoteCharacters (naming both
/// counts). The text is kept as written, surrounding white space removed.
/// Throws only if the database fails.
SubmissionResult SubmitNote(StudyStore& store, const std::string& participant,
                            const std::string& position, const std::string& text);

}  // namespace haptel::study
