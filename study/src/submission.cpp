#include "haptel/study/submission.hpp"

#include <cstdio>

namespace haptel::study {

SubmissionResult SubmitAnswers(StudyStore& store, const std::map<std::string, Questionnaire>& questionnaires,
                               const std::string& participant, const std::string& condition,
                               const std::string& questionnaire, const std::map<std::string, std::string>& fields) {
  SubmissionResult result;
  auto refuse = [&](int status, std::string message) {
    result.accepted = false;
    result.status = status;
    result.message = std::move(message);
    return result;
  };
  const auto q = questionnaires.find(questionnaire);
  if (q == questionnaires.end()) return refuse(400, "this study does not ask questionnaire '" + questionnaire + "'");
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
    return refuse(400, "participant '" + participant + "' has no condition '" + condition + "' in this study");
  }
  int driven = 0;
  for (const TrialRow& t : store.Trials()) driven += t.participant == participant && t.condition == condition ? 1 : 0;
  if (driven < planned_trials) {
    return refuse(409, "participant " + participant + " has not finished condition " + condition + " yet (" +
                           std::to_string(driven) + " of " + std::to_string(planned_trials) +
                           " trials): its questionnaires come after it");
  }
  if (store.Answered(participant, condition, questionnaire)) {
    return refuse(409, "participant " + participant + " has already answered '" + questionnaire + "' for " +
                           condition + "; the first answers are kept");
  }
  const AnswerCheck check = ValidateAnswers(q->second, fields);
  if (!check.ok()) {
    result = refuse(422, std::to_string(check.errors.size()) + " answer" + (check.errors.size() == 1 ? "" : "s") +
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
  result.message = "recorded " + questionnaire + " for participant " + participant + " after " + condition;
  return result;
}

}  // namespace haptel::study
