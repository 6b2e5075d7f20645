// ValidateAnswers on the shipped questionnaires (and a choice item): good
// submissions come back normalised, one (item, value) each; every bad one is
// an error per problem, with a message for the participant, never a throw.
#include <catch2/catch.hpp>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "haptel/study/answers.hpp"
#include "haptel/study/questionnaire.hpp"
#include "test_env.hpp"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using haptel::study::AnswerCheck;
using haptel::study::LoadQuestionnaire;
using haptel::study::PathKey;
using haptel::study::Questionnaire;
using haptel::study::ValidateAnswers;
using Submission = std::map<std::string, std::string>;

namespace {

/// "q1".."q10" (built by appending: GCC 12 warns, wrongly, on "q" + string).
std::string SusId(size_t i) {
  std::string id = "q";
  id += std::to_string(i);
  return id;
}

const Questionnaire& Shipped(const std::string& name) {
  static std::map<std::string, Questionnaire> loaded;
  auto it = loaded.find(name);
  if (it == loaded.end()) {
    it = loaded.emplace(name, LoadQuestionnaire("config/questionnaires/" + name + ".yaml")).first;
  }
  return it->second;
}

/// The one error of a check (fails when there are none or several).
std::string OnlyError(const AnswerCheck& check) {
  std::string all;
  for (const auto& e : check.errors) all += e.message + "\n";
  INFO("errors:\n" << all);
  REQUIRE(check.errors.size() == 1);
  CHECK(check.answers.empty());
  return check.errors.front().message;
}

/// A full SUS submission: q1..q10 all `value`.
Submission AllSus(const std::string& value) {
  Submission s;
  for (int i = 1; i <= 10; ++i) s[SusId(i)] = value;
  return s;
}

Submission GoodTlx() {
  return {{"mental", "50"},      {"physical", "20"}, {"temporal", "35"},
          {"performance", "15"}, {"effort", "60"},   {"frustration", "30"}};
}

const std::string kPathTo5 = "controllable=yes,adequate=yes,satisfactory=no";

}  // namespace

// --- thesis ----------------------------------------------------------------

TEST_CASE("thesis: a full submission comes back normalised, in item order", "[answers][thesis]") {
  const AnswerCheck check =
      ValidateAnswers(Shipped("thesis"), {{"remarks", "  The wheel shakes too much.\n"},
                                          {"efficient", " 2"},
                                          {"easy_to_learn", "04"}});
  REQUIRE(check.ok());
  REQUIRE(check.answers.size() == 3);
  CHECK(check.answers[0].item == "easy_to_learn");
  CHECK(check.answers[0].value == "4");
  CHECK(check.answers[1].item == "efficient");
  CHECK(check.answers[1].value == "2");
  CHECK(check.answers[2].item == "remarks");
  CHECK(check.answers[2].value == "The wheel shakes too much.");
}

TEST_CASE("thesis: the optional remarks may be left out or blank", "[answers][thesis]") {
  for (const Submission& s :
       {Submission{{"easy_to_learn", "5"}, {"efficient", "1"}},
        Submission{{"easy_to_learn", "5"}, {"efficient", "1"}, {"remarks", " \n"}}}) {
    const AnswerCheck check = ValidateAnswers(Shipped("thesis"), s);
    REQUIRE(check.ok());
    CHECK(check.answers.size() == 2);
  }
}

TEST_CASE("thesis: a scale answer out of range", "[answers][thesis]") {
  const AnswerCheck check =
      ValidateAnswers(Shipped("thesis"), {{"easy_to_learn", "7"}, {"efficient", "3"}});
  CHECK(OnlyError(check) == "item 'easy_to_learn': expected an integer 1..5, got '7'");
  CHECK(check.errors.front().item == "easy_to_learn");
}

TEST_CASE("thesis: a scale answer that is not an integer", "[answers][thesis]") {
  for (const std::string bad : {"3.5", "three", "+3", "3 ", "1e0", "99999999999999999999"}) {
    const AnswerCheck check =
        ValidateAnswers(Shipped("thesis"), {{"easy_to_learn", "3"}, {"efficient", bad}});
    if (bad == "3 ") {  // surrounding white space is not an error
      CHECK(check.ok());
      continue;
    }
    CHECK_THAT(OnlyError(check), Contains("item 'efficient': expected an integer 1..5, got '"));
  }
}

TEST_CASE("thesis: a missing required answer", "[answers][thesis]") {
  const AnswerCheck check =
      ValidateAnswers(Shipped("thesis"), {{"efficient", "3"}, {"easy_to_learn", ""}});
  CHECK(OnlyError(check) == "item 'easy_to_learn': expected an integer 1..5, but it is missing");
}

TEST_CASE("thesis: an unknown item", "[answers][thesis]") {
  const AnswerCheck check = ValidateAnswers(
      Shipped("thesis"), {{"easy_to_learn", "3"}, {"efficient", "3"}, {"intuitive", "5"}});
  const std::string msg = OnlyError(check);
  CHECK(check.errors.front().item == "intuitive");
  CHECK_THAT(msg, Contains("item 'intuitive': unknown item; expected one of: easy_to_learn, "
                           "efficient, remarks (questionnaire 'thesis')"));
}

TEST_CASE("thesis: remarks longer than allowed, or not UTF-8", "[answers][thesis]") {
  // 2001 characters, some of them two bytes long: counted as characters.
  const std::string long_text =
      std::string(1990, 'a') + std::string("\xC3\xA9", 2) + std::string(10, 'b');
  CHECK(OnlyError(ValidateAnswers(
            Shipped("thesis"),
            {{"easy_to_learn", "3"}, {"efficient", "3"}, {"remarks", long_text}})) ==
        "item 'remarks': expected at most 2000 characters, got 2001");
  const std::string exactly = std::string(1999, 'a') + std::string("\xC3\xA9", 2);
  CHECK(ValidateAnswers(Shipped("thesis"),
                        {{"easy_to_learn", "3"}, {"efficient", "3"}, {"remarks", exactly}})
            .ok());
  CHECK(OnlyError(ValidateAnswers(Shipped("thesis"), {{"easy_to_learn", "3"},
                                                      {"efficient", "3"},
                                                      {"remarks", std::string("caf\xC3", 4)}})) ==
        "item 'remarks': expected UTF-8 text, got other bytes");
}

TEST_CASE("thesis: every problem at once, and no answers", "[answers][thesis]") {
  const AnswerCheck check =
      ValidateAnswers(Shipped("thesis"), {{"efficient", "0"}, {"x", "1"}, {"y", "2"}});
  REQUIRE(check.errors.size() == 4);  // easy_to_learn missing, efficient, x, y
  CHECK(check.errors[0].item == "easy_to_learn");
  CHECK(check.errors[1].item == "efficient");
  CHECK(check.errors[2].item == "x");
  CHECK(check.errors[3].item == "y");
  CHECK(check.answers.empty());
}

// --- sus -------------------------------------------------------------------

TEST_CASE("sus: a full submission", "[answers][sus]") {
  const AnswerCheck check = ValidateAnswers(Shipped("sus"), AllSus("3"));
  REQUIRE(check.ok());
  CHECK(check.answers.size() == 10);
}

TEST_CASE("sus: a missing statement", "[answers][sus]") {
  Submission s = AllSus("3");
  s.erase("q7");
  CHECK(OnlyError(ValidateAnswers(Shipped("sus"), s)) ==
        "item 'q7': expected an integer 1..5, but it is missing");
}

TEST_CASE("sus: out of range and not an integer", "[answers][sus]") {
  Submission s = AllSus("3");
  s["q1"] = "0";
  s["q2"] = "6";
  s["q3"] = "2.5";
  const AnswerCheck check = ValidateAnswers(Shipped("sus"), s);
  REQUIRE(check.errors.size() == 3);
  CHECK(check.errors[0].message == "item 'q1': expected an integer 1..5, got '0'");
  CHECK(check.errors[1].message == "item 'q2': expected an integer 1..5, got '6'");
  CHECK(check.errors[2].message == "item 'q3': expected an integer 1..5, got '2.5'");
}

TEST_CASE("sus: an unknown item", "[answers][sus]") {
  Submission s = AllSus("3");
  s["q11"] = "3";
  CHECK_THAT(OnlyError(ValidateAnswers(Shipped("sus"), s)), Contains("item 'q11': unknown item"));
}

// --- tlx -------------------------------------------------------------------

TEST_CASE("tlx: a full submission", "[answers][tlx]") {
  const AnswerCheck check = ValidateAnswers(Shipped("tlx"), GoodTlx());
  REQUIRE(check.ok());
  CHECK(check.answers.size() == 6);
}

TEST_CASE("tlx: a value off the grid of 5 and one past 100", "[answers][tlx]") {
  Submission s = GoodTlx();
  s["mental"] = "42";
  CHECK(OnlyError(ValidateAnswers(Shipped("tlx"), s)) ==
        "item 'mental': expected an integer 0..100 in steps of 5, got '42'");
  s = GoodTlx();
  s["effort"] = "105";
  CHECK(OnlyError(ValidateAnswers(Shipped("tlx"), s)) ==
        "item 'effort': expected an integer 0..100 in steps of 5, got '105'");
  s["effort"] = "-5";
  CHECK_THAT(OnlyError(ValidateAnswers(Shipped("tlx"), s)), Contains("got '-5'"));
}

TEST_CASE("tlx: a missing scale and an unknown one", "[answers][tlx]") {
  Submission s = GoodTlx();
  s.erase("frustration");
  s["stress"] = "50";
  const AnswerCheck check = ValidateAnswers(Shipped("tlx"), s);
  REQUIRE(check.errors.size() == 2);
  CHECK(check.errors[0].message ==
        "item 'frustration': expected an integer 0..100 in steps of 5, but it is missing");
  CHECK_THAT(check.errors[1].message, Contains("item 'stress': unknown item"));
}

// --- rating (the tree) -----------------------------------------------------

TEST_CASE("rating: a path to each band and a rating in it", "[answers][rating]") {
  struct Case {
    std::string path;
    std::string rating;
  };
  for (const Case& c :
       {Case{"controllable=no", "10"}, Case{"controllable=yes,adequate=no", "8"},
        Case{kPathTo5, "5"}, Case{"controllable=yes,adequate=yes,satisfactory=yes", "1"}}) {
    const AnswerCheck check =
        ValidateAnswers(Shipped("rating"), {{"rating", c.rating}, {"rating.path", c.path}});
    INFO(c.path);
    REQUIRE(check.ok());
    REQUIRE(check.answers.size() == 2);
    CHECK(check.answers[0].item == "rating");
    CHECK(check.answers[0].value == c.rating);
    CHECK(check.answers[1].item == PathKey("rating"));
    CHECK(check.answers[1].value == c.path);
  }
}

TEST_CASE("rating: a path written loosely is stored plainly", "[answers][rating]") {
  const AnswerCheck check = ValidateAnswers(
      Shipped("rating"),
      {{"rating", " 6 "}, {"rating.path", " controllable = yes , adequate=yes,satisfactory= no "}});
  REQUIRE(check.ok());
  CHECK(check.answers[0].value == "6");
  CHECK(check.answers[1].value == kPathTo5);
}

TEST_CASE("rating: a rating outside the band the path reached", "[answers][rating]") {
  const AnswerCheck check =
      ValidateAnswers(Shipped("rating"), {{"rating", "2"}, {"rating.path", kPathTo5}});
  CHECK(OnlyError(check) ==
        "item 'rating': expected a rating 4..6 (band 'deficient', where the path leads), got '2'");
  CHECK(check.errors.front().item == "rating");
}

TEST_CASE("rating: a rating outside the scale", "[answers][rating]") {
  CHECK(OnlyError(
            ValidateAnswers(Shipped("rating"), {{"rating", "11"}, {"rating.path", kPathTo5}})) ==
        "item 'rating': expected an integer 1..10, got '11'");
  CHECK(OnlyError(
            ValidateAnswers(Shipped("rating"), {{"rating", "five"}, {"rating.path", kPathTo5}})) ==
        "item 'rating': expected an integer 1..10, got 'five'");
}

TEST_CASE("rating: a path answering the wrong question", "[answers][rating]") {
  CHECK(OnlyError(ValidateAnswers(
            Shipped("rating"),
            {{"rating", "5"}, {"rating.path", "controllable=yes,satisfactory=no"}})) ==
        "item 'rating.path': step 2: expected an answer to 'adequate' (where controllable=yes "
        "leads), "
        "got 'satisfactory=no'");
  CHECK(
      OnlyError(
          ValidateAnswers(Shipped("rating"), {{"rating", "5"}, {"rating.path", "adequate=yes"}})) ==
      "item 'rating.path': step 1: expected an answer to 'controllable' (the first question), got "
      "'adequate=yes'");
}

TEST_CASE("rating: a path step that is not yes or no", "[answers][rating]") {
  CHECK(OnlyError(ValidateAnswers(Shipped("rating"),
                                  {{"rating", "5"}, {"rating.path", "controllable=maybe"}})) ==
        "item 'rating.path': step 1: expected 'controllable=yes' or 'controllable=no', got "
        "'controllable=maybe'");
  CHECK_THAT(OnlyError(ValidateAnswers(Shipped("rating"),
                                       {{"rating", "5"}, {"rating.path", "controllable=yes,,"}})),
             Contains("step 2: expected 'adequate=yes' or 'adequate=no', got ''"));
}

TEST_CASE("rating: a path that stops at a question", "[answers][rating]") {
  CHECK(OnlyError(
            ValidateAnswers(Shipped("rating"),
                            {{"rating", "5"}, {"rating.path", "controllable=yes,adequate=yes"}})) ==
        "item 'rating.path': expected an answer to 'satisfactory' (where adequate=yes leads), but "
        "the path stops before it");
}

TEST_CASE("rating: a path that goes on past its band", "[answers][rating]") {
  CHECK(OnlyError(
            ValidateAnswers(Shipped("rating"),
                            {{"rating", "10"}, {"rating.path", "controllable=no,adequate=yes"}})) ==
        "item 'rating.path': step 2: expected nothing more: the path reached band 'uncontrollable' "
        "at step 1, got 'adequate=yes'");
}

TEST_CASE("rating: the rating or the path missing", "[answers][rating]") {
  CHECK(OnlyError(ValidateAnswers(Shipped("rating"), {{"rating.path", kPathTo5}})) ==
        "item 'rating': expected an integer 1..10, but it is missing");
  CHECK(OnlyError(ValidateAnswers(Shipped("rating"), {{"rating", "5"}})) ==
        "item 'rating.path': expected the yes/no answers from 'controllable' to a band, e.g. "
        "'controllable=yes,...', but it is missing");
  CHECK(ValidateAnswers(Shipped("rating"), {}).errors.size() == 2);
}

TEST_CASE("rating: an unknown item", "[answers][rating]") {
  CHECK_THAT(
      OnlyError(ValidateAnswers(Shipped("rating"),
                                {{"rating", "5"}, {"rating.path", kPathTo5}, {"rating.pth", "x"}})),
      Contains("item 'rating.pth': unknown item; expected one of: rating, rating.path"));
}

// --- choice, and an optional tree ------------------------------------------

TEST_CASE("a choice item: an option's value, or an error listing them", "[answers][choice]") {
  const fs::path dir = haptel::test::ScratchDir("test_answers");
  const Questionnaire q = LoadQuestionnaire(haptel::test::WriteFile(
      dir / "hand.yaml",
      "name: hand\ntitle: Hand\nitems:\n"
      "  - id: hand\n    text: Which hand do you write with?\n    type: choice\n"
      "    options:\n      - {value: left, label: Left}\n      - {value: right, label: Right}\n"));
  const AnswerCheck good = ValidateAnswers(q, {{"hand", " right "}});
  REQUIRE(good.ok());
  CHECK(good.answers.front().value == "right");
  CHECK(OnlyError(ValidateAnswers(q, {{"hand", "Right"}})) ==
        "item 'hand': expected one of 'left', 'right', got 'Right'");
  CHECK(OnlyError(ValidateAnswers(q, {})) ==
        "item 'hand': expected one of 'left', 'right', but it is missing");
}

TEST_CASE("an optional tree may be left out, but not half answered", "[answers][rating]") {
  Questionnaire q = Shipped("rating");
  q.items[0].required = false;
  const AnswerCheck none = ValidateAnswers(q, {{"rating", ""}});
  REQUIRE(none.ok());
  CHECK(none.answers.empty());
  CHECK_THAT(OnlyError(ValidateAnswers(q, {{"rating", "3"}})),
             Contains("item 'rating.path': expected the yes/no answers"));
}

TEST_CASE("a long bad value is shortened in the message", "[answers]") {
  const std::string msg = OnlyError(ValidateAnswers(
      Shipped("thesis"), {{"easy_to_learn", std::string(500, '9')}, {"efficient", "3"}}));
  CHECK_THAT(msg, Contains("got '" + std::string(40, '9') + "...'"));
  CHECK(msg.size() < 120);
}
