#pragma once
/// @file Questionnaires as data files (config/questionnaires/*.yaml): what a
/// participant fills in after each condition of a study. A study names its
/// questionnaires; a study can add its own file. The structure is plain so
/// the console can render it; answers are checked and scored in answers.hpp.
///
/// The file format (every key strict: an unknown key is an error):
///
///     name: sus                  # [a-z0-9][a-z0-9_-]*, the file's stem
///     title: System Usability Scale
///     instructions: >            # optional, shown above the items
///       Rate how much you agree with each statement.
///     scoring: sus               # none (default) | sus | tlx-raw | rating-tree
///     items:                     # at least one; ids unique, [a-z][a-z0-9_]*
///       - id: ease
///         text: Is the interface easy to learn?
///         type: scale            # integer min..max in steps of `step`
///         min: 1
///         max: 5
///         step: 1                # optional, default 1; must divide max - min
///         min_label: Strongly disagree
///         max_label: Strongly agree
///       - id: hand
///         text: Which hand do you write with?
///         type: choice           # one of at least two labelled options
///         options:
///           - {value: left, label: Left}
///           - {value: right, label: Right}
///       - id: remarks
///         text: Do you have any remarks about this interface?
///         type: text             # free text
///         max_length: 2000       # optional, characters, default 2000
///         required: false        # any item may say so; default true
///       - id: rating
///         text: Rate the interface.
///         type: tree             # a decision tree ending in a rating
///         nodes:                 # questions; the first is where it starts
///           - id: controllable
///             question: Could you keep the robot under control?
///             if_yes: adequate   # each branch names a node or a band
///             if_no: lost
///           - ...
///         bands:                 # each a run of consecutive ratings
///           - id: lost
///             text: Not controllable
///             ratings:
///               - {rating: 10, text: I lost control of the robot.}
///           - ...
///
/// The tree must be a tree: every branch names a node or a band, no branch
/// leads back to the first node, every other node and every band is reached
/// by exactly one branch. The bands' ratings together cover one run of whole
/// numbers (min..max of the tree) with no gap and no rating in two bands.
///
/// The scoring kinds fix the items: `sus` needs exactly ten items, each a
/// required scale 1..5 in steps of 1 (Brooke 1996); `tlx-raw` exactly six,
/// each a required scale 0..100 (raw NASA-TLX, 0 = low, 100 = high: the
/// performance scale runs from perfect to failure); `rating-tree` exactly one,
/// a required tree. `none` takes any items and gives no score.
#include <filesystem>
#include <string>
#include <vector>

#include "haptel/config/error.hpp"

namespace haptel::study {

/// How a questionnaire's answers make one number (see Score).
enum class Scoring { kNone, kSus, kTlxRaw, kRatingTree };
/// "none", "sus", "tlx-raw", "rating-tree": as in the file.
std::string ToString(Scoring scoring);

enum class ItemType { kChoice, kScale, kText, kTree };
/// "choice", "scale", "text", "tree": as in the file.
std::string ToString(ItemType type);

/// One answer a choice item offers: `value` is what is stored, `label` what
/// the participant reads.
struct ChoiceOption {
  std::string value;
  std::string label;
};

/// An integer scale: min, min + step, ..., max. The labels name the ends.
struct Scale {
  int min = 1;
  int max = 5;
  int step = 1;
  std::string min_label;
  std::string max_label;
};

/// A yes/no question of a decision tree. Each branch holds the id of the
/// node or the band it leads to.
struct TreeNode {
  std::string id;
  std::string question;
  std::string if_yes;
  std::string if_no;
};

/// One rating of a band and what it means.
struct BandRating {
  int rating = 0;
  std::string text;
};

/// Where a path through the tree ends: a run of consecutive ratings,
/// ascending, the participant then picks one of.
struct TreeBand {
  std::string id;
  std::string text;
  std::vector<BandRating> ratings;

  int min() const { return ratings.front().rating; }
  int max() const { return ratings.back().rating; }
  bool Contains(int rating) const { return rating >= min() && rating <= max(); }
};

/// A decision tree: nodes[0] is the first question. Node and band ids are
/// unique within the tree (one namespace for both).
struct DecisionTree {
  std::vector<TreeNode> nodes;
  std::vector<TreeBand> bands;
  int min_rating = 0;  ///< the lowest rating of any band
  int max_rating = 0;  ///< the highest rating of any band

  /// Null when there is no such node / band.
  const TreeNode* FindNode(const std::string& id) const;
  const TreeBand* FindBand(const std::string& id) const;
};

/// One item; only the fields of its `type` are filled.
struct Item {
  std::string id;
  std::string text;
  ItemType type = ItemType::kText;
  bool required = true;
  std::vector<ChoiceOption> options;  ///< kChoice
  Scale scale;                        ///< kScale
  int max_length = 2000;              ///< kText: characters (UTF-8 code points)
  DecisionTree tree;                  ///< kTree
};

struct Questionnaire {
  std::filesystem::path file;
  std::string name;
  std::string title;
  std::string instructions;  ///< may be empty
  Scoring scoring = Scoring::kNone;
  std::vector<Item> items;  ///< in the file's order

  /// Null when there is no such item.
  const Item* FindItem(const std::string& id) const;
};

/// Loads and checks a questionnaire file (format above). Throws ConfigError
/// naming file:line:column, the key path (e.g. "items[2].nodes[1].if_no")
/// and what was expected, for anything the format does not allow.
Questionnaire LoadQuestionnaire(const std::filesystem::path& file);

/// The questionnaire `name` from `<dir>/<name>.yaml`, loaded. Throws
/// ConfigError listing the names available in `dir` when there is no such
/// file, and naming the file when its `name` is not `name`.
Questionnaire FindQuestionnaire(const std::filesystem::path& dir, const std::string& name);

}  // namespace haptel::study
