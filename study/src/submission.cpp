#include "haptel/study/submission.hpp"

#include <algorithm>
#include <cstdio>

namespace haptel::study {

SubmissionResult SubmitAnswers(StudyStore& store,
                               const std::map<std::string, Questionnaire>& questionnaires,
                               const std::string& participant, const std::string& condition,
                               const std::string& questionnaire,
                               const std::map<std::string, std::string>& fields,
                               const std::string& demographics) {
  SubmissionResult result;
  auto refuse = [&](int status, std::string message) {
    result.accepted = false;
    result.status = status;
    result.message = std::move(message);
    return result;
  };
  const auto q = questionnaires.find(questionnaire);
  if (q == questionnaires.end())
    return refuse(400, "this study does not ask questionnaire '" + questionnaire + "'");
  const bool background = !demographics.empty() && questionnaire == demographics;
  if (background || condition.empty()) {
    // The participant's background: once, about no condition.
    if (!background) {
      return refuse(400, "questionnaire '" + questionnaire +
                             "' is asked after a condition: name the condition");
    }
    if (!condition.empty()) {
      return refuse(400, "questionnaire '" + questionnaire +
                             "' is the participant's background, asked once "
                             "before their first trial, not after condition '" +
                             condition + "'");
    }
    const std::vector<std::string> participants = store.Participants();
    if (std::find(participants.begin(), participants.end(), participant) == participants.end()) {
      return refuse(400, "no participant '" + participant + "' in this study");
    }
  } else {
    // The plan says who drives what; the trials say what has been driven.
    bool planned = false;
    int planned_trials = 0;
    for (const PlannedTrial& t : store.Plan()) {
      if (t.participant == participant && t.condition == condition) {
        planned = true;
        ++planned_trials;
      }
    }
    if (!planned) {
      return refuse(400, "participant '" + participant + "' has no condition '" + condition +
                             "' in this study");
    }
    int driven = 0;
    for (const TrialRow& t : store.Trials())
      driven += t.participant == participant && t.condition == condition ? 1 : 0;
    if (driven < planned_trials) {
      return refuse(409, "participant " + participant + " has not finished condition " + condition +
                             " yet (" + std::to_string(driven) + " of " +
                             std::to_string(planned_trials) +
                             " trials): its questionnaires come after it");
    }
  }
  if (store.Answered(participant, condition, questionnaire)) {
    return refuse(409, "participant " + participant + " has already answered '" + questionnaire +
                           "'" + (condition.empty() ? std::string() : " for " + condition) +
                           "; the first answers are kept");
  }
  const AnswerCheck check = ValidateAnswers(q->second, fields);
  if (!check.ok()) {
    result = refuse(422, std::to_string(check.errors.size()) + " answer" +
                             (check.errors.size() == 1 ? "" : "s") +
                             " to correct: " + check.errors.front().message);
    result.errors = check.errors;
    return result;
  }
  std::vector<std::pair<std::string, std::string>> rows;
  for (const Answer& a : check.answers) rows.emplace_back(a.item, a.value);
  if (const std::optional<double> score = Score(q->second, check.answers)) {
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", *score);
    rows.emplace_back("score", text);
  }
  try {
    store.SaveAnswers(participant, condition, questionnaire, rows);
  } catch (const AlreadyAnswered& e) {  // a second form that raced the first one in
    return refuse(409, e.what());
  }
  result.accepted = true;
  result.status = 200;
  result.message =
      "recorded " + questionnaire + " for participant " + participant + " after " + condition;
  return result;
}

SubmissionResult SubmitNote(StudyStore& store, const std::string& participant,
                            const std::string& position, const std::string& text) {
  SubmissionResult result;
  auto refuse = [&](int status, std::string message) {
    result.accepted = false;
    result.status = status;
    result.message = "note not recorded: " + std::move(message);
    return result;
  };
  const std::vector<std::string> participants = store.Participants();
  if (std::find(participants.begin(), participants.end(), participant) == participants.end()) {
    return refuse(400, "no participant '" + participant.substr(0, 40) + "' in this study");
  }
  int at = -1;
  const bool digits = !position.empty() && position.size() <= 6 &&
                      position.find_first_not_of("0123456789") == std::string::npos;
  if (digits) at = std::stoi(position);
  bool planned = at == 0;
  for (const PlannedTrial& t : store.Plan())
    planned = planned || (t.participant == participant && t.position == at);
  if (!planned) {
    return refuse(400, "participant " + participant + " has no trial at position '" +
                           position.substr(0, 12) + "' (0 notes the participant as a whole)");
  }
  const size_t first = text.find_first_not_of(" \t\r\n\f\v");
  const size_t last = text.find_last_not_of(" \t\r\n\f\v");
  const std::string kept =
      first == std::string::npos ? std::string() : text.substr(first, last - first + 1);
  if (kept.empty()) return refuse(422, "the note is empty");
  if (!IsUtf8(kept)) return refuse(422, "the note is not UTF-8 text");
  if (const size_t n = Utf8Characters(kept); n > static_cast<size_t>(kMaxNoteCharacters)) {
    return refuse(422, "a note is at most " + std::to_string(kMaxNoteCharacters) +
                           " characters, this one has " + std::to_string(n) +
                           ": shorten it, or split it in two notes");
  }
  store.SaveNote(participant, at, kept);
  result.accepted = true;
  result.status = 200;
  result.message = "noted on participant " + participant +
                   (at == 0 ? std::string() : ", position " + std::to_string(at));
  return result;
}

}  // namespace haptel::study
