// Questionnaire files: the four shipped ones load with what they say; every
// way a file can be wrong is a ConfigError naming the file, the line, the key
// and what was expected. Runs from the repository root (ctest sets it).
#include <catch2/catch.hpp>
#include <filesystem>
#include <string>

#include "haptel/config/error.hpp"
#include "haptel/study/questionnaire.hpp"
#include "test_env.hpp"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;
using haptel::ConfigError;
using haptel::study::FindQuestionnaire;
using haptel::study::ItemType;
using haptel::study::LoadQuestionnaire;
using haptel::study::Questionnaire;
using haptel::study::Scoring;

namespace {

const fs::path kShipped = "config/questionnaires";

fs::path ScratchDir() {
  static const fs::path dir = haptel::test::ScratchDir("test_questionnaire_loader");
  return dir;
}

fs::path Write(const std::string& name, const std::string& text) {
  return haptel::test::WriteFile(ScratchDir() / name, text);
}

/// `text` with its first `from` replaced by `to` (which must be there).
std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}

/// Loads `text` (as file `name`) and checks the ConfigError it must raise:
/// it starts with "<file>:<line>:", names the key and says `expected`.
void ExpectError(const std::string& name, const std::string& text, int line, const std::string& key,
                 const std::string& expected) {
  const fs::path file = Write(name, text);
  const std::string msg = haptel::test::WhatOf<ConfigError>([&] { LoadQuestionnaire(file); });
  INFO(msg);
  CHECK_THAT(msg, StartsWith(file.string() + ":" + std::to_string(line) + ":"));
  CHECK_THAT(msg, Contains("key '" + key + "'"));
  CHECK_THAT(msg, Contains(expected));
}

// One scale item; line numbers on the right.
const std::string kScale =
    "name: t\n"             // 1
    "title: T\n"            // 2
    "items:\n"              // 3
    "  - id: a\n"           // 4
    "    text: A\n"         // 5
    "    type: scale\n"     // 6
    "    min: 1\n"          // 7
    "    max: 5\n"          // 8
    "    min_label: lo\n"   // 9
    "    max_label: hi\n";  // 10

// One choice item.
const std::string kChoice =
    "name: t\n"                        // 1
    "title: T\n"                       // 2
    "items:\n"                         // 3
    "  - id: c\n"                      // 4
    "    text: C\n"                    // 5
    "    type: choice\n"               // 6
    "    options:\n"                   // 7
    "      - {value: x, label: X}\n"   // 8
    "      - {value: y, label: Y}\n";  // 9

// A two-question tree: a -no-> low (4); a -yes-> b; b -yes-> top (1-2),
// b -no-> mid (3).
const std::string kTree =
    "name: t\n"                               // 1
    "title: T\n"                              // 2
    "scoring: rating-tree\n"                  // 3
    "items:\n"                                // 4
    "  - id: r\n"                             // 5
    "    text: R\n"                           // 6
    "    type: tree\n"                        // 7
    "    nodes:\n"                            // 8
    "      - id: a\n"                         // 9
    "        question: A?\n"                  // 10
    "        if_yes: b\n"                     // 11
    "        if_no: low\n"                    // 12
    "      - id: b\n"                         // 13
    "        question: B?\n"                  // 14
    "        if_yes: top\n"                   // 15
    "        if_no: mid\n"                    // 16
    "    bands:\n"                            // 17
    "      - id: top\n"                       // 18
    "        text: Top\n"                     // 19
    "        ratings:\n"                      // 20
    "          - {rating: 1, text: one}\n"    // 21
    "          - {rating: 2, text: two}\n"    // 22
    "      - id: mid\n"                       // 23
    "        text: Mid\n"                     // 24
    "        ratings:\n"                      // 25
    "          - {rating: 3, text: three}\n"  // 26
    "      - id: low\n"                       // 27
    "        text: Low\n"                     // 28
    "        ratings:\n"                      // 29
    "          - {rating: 4, text: four}\n";  // 30

/// `count` scale items q1..q<count>, min..max (7 lines each, from line 5).
std::string Scales(const std::string& scoring, int count, int min, int max) {
  std::string text = "name: t\ntitle: T\nscoring: " + scoring + "\nitems:\n";
  for (int i = 1; i <= count; ++i) {
    text += "  - id: q" + std::to_string(i) +
            "\n    text: Q\n    type: scale\n    min: " + std::to_string(min) +
            "\n    max: " + std::to_string(max) + "\n    min_label: lo\n    max_label: hi\n";
  }
  return text;
}

}  // namespace

// --- The shipped files -----------------------------------------------------

TEST_CASE("shipped thesis.yaml: the thesis's three questions", "[questionnaire][shipped]") {
  const Questionnaire q = LoadQuestionnaire(kShipped / "thesis.yaml");
  CHECK(q.name == "thesis");
  CHECK(q.scoring == Scoring::kNone);
  REQUIRE(q.items.size() == 3);
  CHECK(q.items[0].text == "Is the interface easy to learn?");
  CHECK(q.items[0].type == ItemType::kScale);
  CHECK(q.items[0].scale.min == 1);
  CHECK(q.items[0].scale.max == 5);
  CHECK(q.items[1].text == "Do you think this interface is efficient to drive the robot?");
  CHECK(q.items[1].type == ItemType::kScale);
  CHECK(q.items[2].text == "Do you have any remarks about this interface?");
  CHECK(q.items[2].type == ItemType::kText);
  CHECK_FALSE(q.items[2].required);
  CHECK(q.items[0].required);
  CHECK_FALSE(q.instructions.empty());
  CHECK(q.instructions.back() != '\n');  // the folded block's newline dropped
}

TEST_CASE("shipped sus.yaml: ten 1-5 statements, scored as SUS", "[questionnaire][shipped]") {
  const Questionnaire q = LoadQuestionnaire(kShipped / "sus.yaml");
  CHECK(q.name == "sus");
  CHECK(q.scoring == Scoring::kSus);
  REQUIRE(q.items.size() == 10);
  for (const auto& item : q.items) {
    CHECK(item.type == ItemType::kScale);
    CHECK(item.scale.min == 1);
    CHECK(item.scale.max == 5);
    CHECK(item.scale.step == 1);
    CHECK(item.required);
  }
  CHECK(q.items[0].text == "I think that I would like to use this system frequently.");
  CHECK(q.items[9].text ==
        "I needed to learn a lot of things before I could get going with this system.");
}

TEST_CASE("shipped tlx.yaml: six 0-100 scales in steps of 5", "[questionnaire][shipped]") {
  const Questionnaire q = LoadQuestionnaire(kShipped / "tlx.yaml");
  CHECK(q.name == "tlx");
  CHECK(q.scoring == Scoring::kTlxRaw);
  REQUIRE(q.items.size() == 6);
  for (const auto& item : q.items) {
    CHECK(item.scale.min == 0);
    CHECK(item.scale.max == 100);
    CHECK(item.scale.step == 5);
  }
  const auto* performance = q.FindItem("performance");
  REQUIRE(performance != nullptr);
  CHECK(performance->scale.min_label == "Perfect");
  CHECK(performance->scale.max_label == "Failure");
  CHECK(q.FindItem("mental") != nullptr);
  CHECK(q.FindItem("frustration") != nullptr);
}

TEST_CASE("shipped rating.yaml: the Cooper-Harper-like tree, 1 to 10", "[questionnaire][shipped]") {
  const Questionnaire q = LoadQuestionnaire(kShipped / "rating.yaml");
  CHECK(q.name == "rating");
  CHECK(q.scoring == Scoring::kRatingTree);
  REQUIRE(q.items.size() == 1);
  const auto& tree = q.items[0].tree;
  CHECK(tree.min_rating == 1);
  CHECK(tree.max_rating == 10);
  REQUIRE(tree.nodes.size() == 3);
  CHECK(tree.nodes[0].id == "controllable");
  // The three questions in Cooper-Harper order, each "no" to its band.
  const auto band_of_no = [&](const std::string& node) {
    const auto* b = tree.FindBand(tree.FindNode(node)->if_no);
    REQUIRE(b != nullptr);
    return std::make_pair(b->min(), b->max());
  };
  CHECK(band_of_no("controllable") == std::make_pair(10, 10));
  CHECK(band_of_no("adequate") == std::make_pair(7, 9));
  CHECK(band_of_no("satisfactory") == std::make_pair(4, 6));
  const auto* best = tree.FindBand(tree.FindNode("satisfactory")->if_yes);
  REQUIRE(best != nullptr);
  CHECK(best->min() == 1);
  CHECK(best->max() == 3);
  for (const auto& band : tree.bands) {
    for (const auto& r : band.ratings) CHECK_FALSE(r.text.empty());
  }
}

TEST_CASE("FindQuestionnaire loads a shipped questionnaire by name", "[questionnaire][find]") {
  CHECK(FindQuestionnaire(kShipped, "sus").scoring == Scoring::kSus);
  CHECK(FindQuestionnaire(kShipped, "rating").items.size() == 1);
}

// --- FindQuestionnaire's errors ---------------------------------------------

TEST_CASE("FindQuestionnaire: an unknown name lists the available ones",
          "[questionnaire][find][error]") {
  const std::string msg =
      haptel::test::WhatOf<ConfigError>([] { FindQuestionnaire(kShipped, "nasa"); });
  CHECK_THAT(msg, StartsWith(kShipped.string()));
  CHECK_THAT(msg, Contains("'nasa'"));
  CHECK_THAT(msg, Contains("expected one of: demographics, rating, sus, thesis, tlx"));
  // Not a path either.
  CHECK_THAT(haptel::test::WhatOf<ConfigError>([] { FindQuestionnaire(kShipped, "../tlx"); }),
             Contains("expected one of: demographics, rating, sus, thesis, tlx"));
}

TEST_CASE("FindQuestionnaire: a file whose name is not its file's",
          "[questionnaire][find][error]") {
  const fs::path dir = ScratchDir() / "find";
  fs::create_directories(dir);
  const fs::path file = haptel::test::WriteFile(dir / "other.yaml", kScale);
  const std::string msg =
      haptel::test::WhatOf<ConfigError>([&] { FindQuestionnaire(dir, "other"); });
  CHECK_THAT(msg, StartsWith(file.string() + ":1:"));
  CHECK_THAT(msg, Contains("key 'name'"));
  CHECK_THAT(msg, Contains("expected 'other', the name the file is found by, got 't'"));
}

// --- Loader errors: one case each -------------------------------------------

TEST_CASE("loader: a missing file names it", "[questionnaire][error]") {
  const std::string msg =
      haptel::test::WhatOf<ConfigError>([] { LoadQuestionnaire(ScratchDir() / "absent.yaml"); });
  CHECK_THAT(msg, Contains("absent.yaml"));
  CHECK_THAT(msg, Contains("cannot open"));
}

TEST_CASE("loader: the minimal files load", "[questionnaire]") {
  CHECK(LoadQuestionnaire(Write("ok_scale.yaml", kScale)).items.size() == 1);
  CHECK(LoadQuestionnaire(Write("ok_choice.yaml", kChoice)).items[0].options.size() == 2);
  const Questionnaire tree = LoadQuestionnaire(Write("ok_tree.yaml", kTree));
  CHECK(tree.items[0].tree.min_rating == 1);
  CHECK(tree.items[0].tree.max_rating == 4);
}

TEST_CASE("loader: an unknown top-level key", "[questionnaire][error]") {
  ExpectError("unknown_top.yaml", kScale + "titel: X\n", 11, "titel",
              "unknown key (expected one of: instructions, items, name, scoring, title)");
}

TEST_CASE("loader: an unknown key in an item (a scale has no options)", "[questionnaire][error]") {
  ExpectError("unknown_item_key.yaml", kScale + "    options: []\n", 11, "items[0].options",
              "unknown key (expected one of:");
}

TEST_CASE("loader: an item without text", "[questionnaire][error]") {
  ExpectError("no_text.yaml", Replace(kScale, "    text: A\n", ""), 4, "items[0].text",
              "expected a non-empty string, but it is missing");
}

TEST_CASE("loader: a text that is only white space", "[questionnaire][error]") {
  ExpectError("blank_title.yaml", Replace(kScale, "title: T", "title: '  '"), 2, "title",
              "expected a non-empty string");
}

TEST_CASE("loader: an unknown item type", "[questionnaire][error]") {
  ExpectError("bad_type.yaml", Replace(kScale, "type: scale", "type: slider"), 6, "items[0].type",
              "expected one of: choice, scale, text, tree, got 'slider'");
}

TEST_CASE("loader: an unknown scoring", "[questionnaire][error]") {
  ExpectError("bad_scoring.yaml", Replace(kScale, "title: T\n", "title: T\nscoring: likert\n"), 3,
              "scoring", "expected one of: none, sus, tlx-raw, rating-tree, got 'likert'");
}

TEST_CASE("loader: a bad questionnaire name", "[questionnaire][error]") {
  ExpectError("bad_name.yaml", Replace(kScale, "name: t", "name: My Q"), 1, "name",
              "expected a name: a lower-case letter or digit");
}

TEST_CASE("loader: no items", "[questionnaire][error]") {
  ExpectError("no_items.yaml", "name: t\ntitle: T\nitems: []\n", 3, "items",
              "expected a list of at least one item {id, text, type, ...}, got none");
}

TEST_CASE("loader: an item id that is not an id", "[questionnaire][error]") {
  ExpectError("bad_id.yaml", Replace(kScale, "id: a", "id: Ease"), 4, "items[0].id",
              "expected an id: a lower-case letter");
}

TEST_CASE("loader: a duplicate item id", "[questionnaire][error]") {
  const std::string text = kScale +
                           "  - id: a\n"  // 11
                           "    text: again\n"
                           "    type: text\n";
  const fs::path file = Write("dup_item.yaml", text);
  ExpectError("dup_item.yaml", text, 11, "items[1].id",
              "expected an id no other item has ('a' is also the item at " + file.string() + ":4:");
}

TEST_CASE("loader: required is not true or false", "[questionnaire][error]") {
  ExpectError("bad_required.yaml", kScale + "    required: maybe\n", 11, "items[0].required",
              "expected true or false, got 'maybe'");
}

TEST_CASE("loader: a scale bound that is not a whole number", "[questionnaire][error]") {
  ExpectError("scale_float.yaml", Replace(kScale, "min: 1", "min: 1.5"), 7, "items[0].min",
              "expected a whole number in [-100000, 100000], got '1.5'");
}

TEST_CASE("loader: a scale without max", "[questionnaire][error]") {
  ExpectError("scale_no_max.yaml", Replace(kScale, "    max: 5\n", ""), 4, "items[0].max",
              "but it is missing");
}

TEST_CASE("loader: a scale whose max is not above its min", "[questionnaire][error]") {
  ExpectError("scale_empty.yaml", Replace(kScale, "max: 5", "max: 1"), 8, "items[0].max",
              "expected a whole number above min (1), got '1'");
}

TEST_CASE("loader: a scale step that does not divide the range", "[questionnaire][error]") {
  ExpectError("scale_step.yaml", kScale + "    step: 3\n", 11, "items[0].step",
              "expected a step that divides max - min (4), got '3'");
}

TEST_CASE("loader: a scale without its end labels", "[questionnaire][error]") {
  ExpectError("scale_label.yaml", Replace(kScale, "    max_label: hi\n", ""), 4,
              "items[0].max_label", "but it is missing");
}

TEST_CASE("loader: a choice with one option", "[questionnaire][error]") {
  ExpectError("choice_one.yaml", Replace(kChoice, "      - {value: y, label: Y}\n", ""), 8,
              "items[0].options", "expected a list of at least two options {value, label}, got 1");
}

TEST_CASE("loader: a choice with two options of one value", "[questionnaire][error]") {
  ExpectError("choice_dup.yaml", Replace(kChoice, "value: y", "value: x"), 9,
              "items[0].options[1].value", "expected a value no other option of this item has");
}

TEST_CASE("loader: a choice option without a label", "[questionnaire][error]") {
  ExpectError("choice_label.yaml", Replace(kChoice, "{value: y, label: Y}", "{value: y}"), 9,
              "items[0].options[1].label", "but it is missing");
}

TEST_CASE("loader: a text item's max_length out of range", "[questionnaire][error]") {
  const std::string text =
      "name: t\ntitle: T\nitems:\n"
      "  - id: remarks\n"
      "    text: R\n"
      "    type: text\n"
      "    max_length: 0\n";  // 7
  ExpectError("text_length.yaml", text, 7, "items[0].max_length",
              "expected a whole number in [1, 100000], got '0'");
}

TEST_CASE("loader: a tree with an empty branch", "[questionnaire][error][tree]") {
  // Reported at the node's line: yaml-cpp marks an empty value at line 13.
  ExpectError("tree_empty_branch.yaml", Replace(kTree, "if_no: low", "if_no:"), 9,
              "items[0].nodes[0].if_no",
              "expected the id of a node or a band of this tree, but it is empty");
}

TEST_CASE("loader: a tree branch to nothing in the tree", "[questionnaire][error][tree]") {
  ExpectError("tree_unknown_branch.yaml", Replace(kTree, "if_no: low", "if_no: lowest"), 12,
              "items[0].nodes[0].if_no",
              "expected the id of a node or a band of this tree (one of: a, b, low, mid, top), "
              "got 'lowest'");
}

TEST_CASE("loader: a tree branch back to the first node", "[questionnaire][error][tree]") {
  ExpectError("tree_loop.yaml", Replace(kTree, "if_no: mid", "if_no: a"), 16,
              "items[0].nodes[1].if_no",
              "expected a node or a band other than 'a', the first node, where the tree starts");
}

TEST_CASE("loader: two branches to one band (not a tree)", "[questionnaire][error][tree]") {
  ExpectError("tree_join.yaml", Replace(kTree, "if_no: mid", "if_no: top"), 16,
              "items[0].nodes[1].if_no",
              "expected a node or a band no other branch leads to (a decision tree: 'top' is "
              "already reached from nodes[1].if_yes)");
}

TEST_CASE("loader: a band no path reaches", "[questionnaire][error][tree]") {
  const std::string text = kTree +
                           "      - id: extra\n"  // 31
                           "        text: Extra\n"
                           "        ratings:\n"
                           "          - {rating: 5, text: five}\n";
  ExpectError("tree_orphan.yaml", text, 31, "items[0].bands[3].id",
              "expected a node or a band some path from the first node ('a') reaches");
}

TEST_CASE("loader: a loop of nodes cut off from the first", "[questionnaire][error][tree]") {
  // c and d lead to each other: each is reached by one branch, but no path
  // from 'a' comes to them.
  const std::string text = Replace(kTree, "    bands:\n",
                                   "      - id: c\n"  // 17
                                   "        question: C?\n"
                                   "        if_yes: d\n"
                                   "        if_no: x\n"
                                   "      - id: d\n"
                                   "        question: D?\n"
                                   "        if_yes: c\n"
                                   "        if_no: y\n"
                                   "    bands:\n") +
                           "      - id: x\n        text: X\n        ratings:\n"
                           "          - {rating: 5, text: five}\n"
                           "      - id: y\n        text: Y\n        ratings:\n"
                           "          - {rating: 6, text: six}\n";
  ExpectError("tree_cycle.yaml", text, 17, "items[0].nodes[2].id",
              "expected a node or a band some path from the first node ('a') reaches");
}

TEST_CASE("loader: a node id used again by a band", "[questionnaire][error][tree]") {
  const fs::path file = Write("tree_dup_id.yaml", kTree);
  ExpectError("tree_dup_id.yaml", Replace(kTree, "id: mid", "id: b"), 23, "items[0].bands[1].id",
              "expected an id no other node or band of this tree has ('b' is also at " +
                  file.string() + ":13:");
}

TEST_CASE("loader: overlapping bands", "[questionnaire][error][tree]") {
  ExpectError("tree_overlap.yaml",
              Replace(kTree, "{rating: 4, text: four}", "{rating: 3, text: four}"), 30,
              "items[0].bands[2].ratings[0].rating",
              "expected a rating no other band has (3 is also in band 'mid'), got '3'");
}

TEST_CASE("loader: a rating no band has (a missing band)", "[questionnaire][error][tree]") {
  ExpectError("tree_gap.yaml", Replace(kTree, "{rating: 4, text: four}", "{rating: 5, text: four}"),
              18, "items[0].bands",
              "expected bands covering every rating from 1 to 5, but no band has rating 4");
}

TEST_CASE("loader: a band whose ratings are not consecutive", "[questionnaire][error][tree]") {
  ExpectError("tree_band_gap.yaml",
              Replace(kTree, "{rating: 2, text: two}", "{rating: 3, text: two}"), 22,
              "items[0].bands[0].ratings[1].rating",
              "expected 2 (a band's ratings are consecutive whole numbers, ascending), got '3'");
}

TEST_CASE("loader: a band without ratings", "[questionnaire][error][tree]") {
  ExpectError("tree_no_ratings.yaml",
              Replace(kTree, "        ratings:\n          - {rating: 4, text: four}\n",
                      "        ratings: []\n"),
              29, "items[0].bands[2].ratings",
              "expected a list of at least one {rating, text}, got none");
}

TEST_CASE("loader: sus with nine items", "[questionnaire][error][scoring]") {
  ExpectError("sus_nine.yaml", Scales("sus", 9, 1, 5), 3, "scoring",
              "expected a scoring the items fit: sus needs exactly 10 items, each a required "
              "scale 1..5 in steps of 1; the file has 9, got 'sus'");
}

TEST_CASE("loader: sus with a 1-7 item", "[questionnaire][error][scoring]") {
  // Item q4 starts on line 5 + 3 * 7 = 26.
  const std::string text = Replace(Scales("sus", 10, 1, 5),
                                   "id: q4\n    text: Q\n    type: scale\n    min: 1\n    max: 5",
                                   "id: q4\n    text: Q\n    type: scale\n    min: 1\n    max: 7");
  const fs::path file = Write("sus_seven.yaml", text);
  ExpectError("sus_seven.yaml", text, 3, "scoring",
              "sus needs exactly 10 items, each a required scale 1..5 in steps of 1; item 'q4' (" +
                  file.string() + ":26:5) is a scale 1..7 in steps of 1");
}

TEST_CASE("loader: sus with an optional item", "[questionnaire][error][scoring]") {
  const std::string text = Replace(Scales("sus", 10, 1, 5), "id: q10\n    text: Q\n",
                                   "id: q10\n    text: Q\n    required: false\n");
  ExpectError("sus_optional.yaml", text, 3, "scoring", "item 'q10' (");
  ExpectError("sus_optional.yaml", text, 3, "scoring", ") is an optional scale 1..5");
}

TEST_CASE("loader: tlx-raw with 1-10 scales", "[questionnaire][error][scoring]") {
  ExpectError("tlx_ten.yaml", Scales("tlx-raw", 6, 1, 10), 3, "scoring",
              "tlx-raw needs exactly 6 items, each a required scale 0..100; item 'q1'");
}

TEST_CASE("loader: rating-tree on a scale", "[questionnaire][error][scoring]") {
  ExpectError("tree_scale.yaml", Replace(kScale, "title: T\n", "title: T\nscoring: rating-tree\n"),
              3, "scoring", "rating-tree needs exactly 1 item, a required tree; item 'a' (");
}
