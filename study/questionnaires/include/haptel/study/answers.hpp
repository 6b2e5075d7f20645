#pragma once
/// @file A participant's answers to a questionnaire: checked against it
/// (ValidateAnswers) and turned into its score (Score).
///
/// Answers travel as text, one (item, value) pair each, both as submitted by
/// the console and as stored (one row per answer):
///   - scale: the integer, e.g. "4";
///   - choice: the option's value;
///   - text: the text, surrounding white space removed;
///   - tree: two pairs. `<id>` holds the final rating, e.g. "5", and
///     `<id>.path` (PathKey) the yes/no answers from the first node to the
///     band, e.g. "controllable=yes,adequate=yes,satisfactory=no".
/// An optional item left out (or submitted empty) has no pair at all.
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "haptel/study/questionnaire.hpp"

namespace haptel::study {

struct Answer {
  std::string item;  ///< an item id, or PathKey(id) for a tree's path
  std::string value;
};

/// Whether `s` is well-formed UTF-8 (no overlong forms, no surrogates).
bool IsUtf8(const std::string& s);
/// Characters (code points) of well-formed UTF-8: what a text's length
/// limit counts (2 000 CJK characters or emoji fit a 2 000-character remark).
size_t Utf8Characters(const std::string& s);

/// The key of a tree item's path: "<id>.path" (item ids have no dot).
std::string PathKey(const std::string& tree_item_id);

/// One problem with a submission, to show next to `item` (an item id, or the
/// submitted key for an unknown item). `message` says it all on its own,
/// e.g. "item 'ease': expected an integer 1..5, got '7'".
struct AnswerError {
  std::string item;
  std::string message;
};

/// Either the normalised answers (errors empty) or every problem found
/// (answers empty).
struct AnswerCheck {
  std::vector<Answer> answers;  ///< in the questionnaire's item order
  std::vector<AnswerError> errors;

  bool ok() const { return errors.empty(); }
};

/// Checks a submission (key → text) against `questionnaire`: every required
/// item answered, no unknown key, scales integers on their grid, choices one
/// of the options, texts within their length, a tree's path following the
/// tree to a band and its rating in that band. Never throws for what was
/// submitted; throws std::logic_error only for a questionnaire the loader
/// would not have produced (a branch to nowhere).
AnswerCheck ValidateAnswers(const Questionnaire& questionnaire,
                            const std::map<std::string, std::string>& submitted);

/// The questionnaire's score from validated answers: `sus` 0..100
/// (2.5 × Σ over items 1..10 of x − 1 for odd items, 5 − x for even ones);
/// `tlx-raw` 0..100, the mean of the six scales; `rating-tree` the rating;
/// `none` nullopt. Throws std::invalid_argument when an answer the score
/// needs is missing, repeated or not valid (answers not from
/// ValidateAnswers).
std::optional<double> Score(const Questionnaire& questionnaire, const std::vector<Answer>& answers);

}  // namespace haptel::study
