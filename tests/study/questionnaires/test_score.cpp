// Score: SUS against hand-worked examples, raw NASA-TLX as the mean of its
// six scales, the rating tree as its rating in each band; no score for a
// questionnaire without scoring; answers that are not valid are refused.
#include <catch2/catch.hpp>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "haptel/study/answers.hpp"
#include "haptel/study/questionnaire.hpp"

using haptel::study::Answer;
using haptel::study::AnswerCheck;
using haptel::study::LoadQuestionnaire;
using haptel::study::Questionnaire;
using haptel::study::Score;
using haptel::study::ValidateAnswers;

namespace {

/// "q1".."q10" (built by appending: GCC 12 warns, wrongly, on "q" + string).
std::string SusId(size_t i) {
  std::string id = "q";
  id += std::to_string(i);
  return id;
}

Questionnaire Shipped(const std::string& name) {
  return LoadQuestionnaire("config/questionnaires/" + name + ".yaml");
}

/// Validates, then scores: the way the console does it.
std::optional<double> ScoreOf(const Questionnaire& q, const std::map<std::string, std::string>& s) {
  const AnswerCheck check = ValidateAnswers(q, s);
  std::string all;
  for (const auto& e : check.errors) all += e.message + "\n";
  INFO("errors:\n" << all);
  REQUIRE(check.ok());
  return Score(q, check.answers);
}

/// SUS answers to items 1..10 in order.
std::optional<double> Sus(const std::vector<int>& x) {
  static const Questionnaire sus = Shipped("sus");
  std::map<std::string, std::string> s;
  for (size_t i = 0; i < x.size(); ++i) s[SusId(i + 1)] = std::to_string(x[i]);
  return ScoreOf(sus, s);
}

}  // namespace

TEST_CASE("SUS: hand-worked scores", "[score][sus]") {
  // All 3: each item contributes 2 (odd: 3-1, even: 5-3); 2.5 x 20 = 50.
  CHECK(Sus({3, 3, 3, 3, 3, 3, 3, 3, 3, 3}) == Approx(50.0));
  // Best: odd items 5 (5-1 = 4), even items 1 (5-1 = 4); 2.5 x 40 = 100.
  CHECK(Sus({5, 1, 5, 1, 5, 1, 5, 1, 5, 1}) == Approx(100.0));
  // Worst: odd items 1 (0), even items 5 (0); 0.
  CHECK(Sus({1, 5, 1, 5, 1, 5, 1, 5, 1, 5}) == Approx(0.0));
  // Mixed: 4 2 5 1 4 2 5 1 3 2.
  //   odd items 1,3,5,7,9 = 4,5,4,5,3 -> x-1 = 3+4+3+4+2 = 16
  //   even items 2,4,6,8,10 = 2,1,2,1,2 -> 5-x = 3+4+3+4+3 = 17
  //   2.5 x (16 + 17) = 82.5
  CHECK(Sus({4, 2, 5, 1, 4, 2, 5, 1, 3, 2}) == Approx(82.5));
  // All 5 (agreeing with everything): odd 4 x 5 = 20, even 0; 2.5 x 20 = 50.
  CHECK(Sus({5, 5, 5, 5, 5, 5, 5, 5, 5, 5}) == Approx(50.0));
}

TEST_CASE("raw TLX: the mean of the six scales", "[score][tlx]") {
  const Questionnaire tlx = Shipped("tlx");
  // (50 + 20 + 35 + 15 + 60 + 30) / 6 = 210 / 6 = 35.
  CHECK(ScoreOf(tlx, {{"mental", "50"},
                      {"physical", "20"},
                      {"temporal", "35"},
                      {"performance", "15"},
                      {"effort", "60"},
                      {"frustration", "30"}}) == Approx(35.0));
  // (0 + 0 + 0 + 0 + 0 + 100) / 6.
  CHECK(ScoreOf(tlx, {{"mental", "0"},
                      {"physical", "0"},
                      {"temporal", "0"},
                      {"performance", "0"},
                      {"effort", "0"},
                      {"frustration", "100"}}) == Approx(100.0 / 6.0));
}

TEST_CASE("rating tree: the rating, in each band", "[score][rating]") {
  const Questionnaire rating = Shipped("rating");
  const auto score = [&](const std::string& path, const std::string& r) {
    return ScoreOf(rating, {{"rating", r}, {"rating.path", path}});
  };
  CHECK(score("controllable=no", "10") == Approx(10.0));
  CHECK(score("controllable=yes,adequate=no", "7") == Approx(7.0));
  CHECK(score("controllable=yes,adequate=no", "9") == Approx(9.0));
  CHECK(score("controllable=yes,adequate=yes,satisfactory=no", "4") == Approx(4.0));
  CHECK(score("controllable=yes,adequate=yes,satisfactory=no", "6") == Approx(6.0));
  CHECK(score("controllable=yes,adequate=yes,satisfactory=yes", "1") == Approx(1.0));
  CHECK(score("controllable=yes,adequate=yes,satisfactory=yes", "3") == Approx(3.0));
}

TEST_CASE("no scoring: no score", "[score][thesis]") {
  CHECK_FALSE(ScoreOf(Shipped("thesis"), {{"easy_to_learn", "4"}, {"efficient", "5"}}).has_value());
}

TEST_CASE("Score refuses answers that were not validated", "[score]") {
  const Questionnaire sus = Shipped("sus");
  std::vector<Answer> answers;
  for (int i = 1; i <= 9; ++i) answers.push_back({SusId(i), "3"});
  CHECK_THROWS_AS(Score(sus, answers), std::invalid_argument);  // q10 missing
  answers.push_back({"q10", "6"});
  CHECK_THROWS_AS(Score(sus, answers), std::invalid_argument);  // out of range
  answers.pop_back();
  answers.push_back({"q10", "3"});
  CHECK(Score(sus, answers) == Approx(50.0));
  answers.push_back({"q10", "3"});
  CHECK_THROWS_AS(Score(sus, answers), std::invalid_argument);  // twice
}
