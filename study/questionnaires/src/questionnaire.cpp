#include "haptel/study/questionnaire.hpp"

#include <algorithm>
#include <functional>
#include <map>
#include <set>
#include <utility>

#include "haptel/config/yaml_map.hpp"

namespace haptel::study {

using config_detail::YamlMap;

namespace {

constexpr int kScaleLimit = 100000;  // |min|, |max| and step of a scale
constexpr int kMaxRating = 1000;     // ratings of a tree: 0..kMaxRating
constexpr int kMaxTextLength = 100000;
constexpr size_t kMaxIdLength = 64;

const std::string kIdExpected =
    "an id: a lower-case letter, then lower-case letters, digits or '_' (at most 64)";
const std::string kNameExpected =
    "a name: a lower-case letter or digit, then lower-case letters, digits, '_' or '-' (at most "
    "64)";
const std::string kTypeExpected = "one of: choice, scale, text, tree";
const std::string kScoringExpected = "one of: none, sus, tlx-raw, rating-tree";
const std::string kBranchExpected = "the id of a node or a band of this tree";

bool IsLowerOrDigit(char c) { return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9'); }

/// [a-z][a-z0-9_]*: item, node and band ids (no '.', so PathKey is free).
bool IsId(const std::string& s) {
  if (s.empty() || s.size() > kMaxIdLength || !(s[0] >= 'a' && s[0] <= 'z')) return false;
  return std::all_of(s.begin(), s.end(), [](char c) { return IsLowerOrDigit(c) || c == '_'; });
}

/// [a-z0-9][a-z0-9_-]*: a questionnaire's name, also its file's stem.
bool IsName(const std::string& s) {
  if (s.empty() || s.size() > kMaxIdLength || !IsLowerOrDigit(s[0])) return false;
  return std::all_of(s.begin(), s.end(),
                     [](char c) { return IsLowerOrDigit(c) || c == '_' || c == '-'; });
}

std::string Range(int min, int max) {
  return "[" + std::to_string(min) + ", " + std::to_string(max) + "]";
}

/// A required plain value: present, not empty. A key with nothing after it
/// is reported at its mapping's line: yaml-cpp marks an empty value where
/// the next token starts, often the next item's line.
std::string RequireText(YamlMap& m, const std::string& key,
                        const std::string& expected = "a non-empty string") {
  if (!m.Has(key) || m.IsMap(key)) m.Fail(key, expected);
  if (m.IsScalar(key)) return m.String(key, "");
  m.String(key, "");  // throws for a list; gives the fallback back for nothing
  throw ConfigError(m.Location() + ": key '" + m.Path(key) + "': expected " + expected +
                    ", but it is empty");
}

/// Text the participant reads (title, question, label...): required, its
/// surrounding white space dropped (a folded `>` block ends in a newline).
std::string DisplayText(YamlMap& m, const std::string& key) {
  std::string text = RequireText(m, key);
  const size_t first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) m.Fail(key, "a non-empty string");
  text.erase(text.find_last_not_of(" \t\r\n") + 1);
  return text.substr(first);
}

/// A list under `key` that is missing, or holds `count` entries too few.
[[noreturn]] void FailCount(const YamlMap& m, const std::string& key, const std::string& expected,
                            size_t count) {
  if (!m.Has(key)) m.Fail(key, expected);
  throw ConfigError(m.ItemLocation(key, 0) + ": key '" + m.Path(key) + "': expected " + expected +
                    ", got " + (count == 0 ? "none" : std::to_string(count)));
}

std::string RequireId(YamlMap& m, const std::string& key) {
  const std::string id = RequireText(m, key, kIdExpected);
  if (!IsId(id)) m.Fail(key, kIdExpected);
  return id;
}

int RequireInteger(YamlMap& m, const std::string& key, int min, int max) {
  if (!m.IsScalar(key)) m.Fail(key, "a whole number in " + Range(min, max));
  return m.Integer(key, 0, min, max);
}

Scoring ReadScoring(YamlMap& root) {
  const std::string s = root.String("scoring", "none");
  if (s == "none") return Scoring::kNone;
  if (s == "sus") return Scoring::kSus;
  if (s == "tlx-raw") return Scoring::kTlxRaw;
  if (s == "rating-tree") return Scoring::kRatingTree;
  root.Fail("scoring", kScoringExpected);
}

std::vector<ChoiceOption> ReadOptions(YamlMap& m) {
  std::vector<YamlMap> maps = m.MapList("options");
  if (maps.size() < 2) {
    FailCount(m, "options", "a list of at least two options {value, label}", maps.size());
  }
  std::vector<ChoiceOption> options;
  std::set<std::string> values;
  for (YamlMap& o : maps) {
    ChoiceOption option;
    option.value = RequireText(o, "value");
    if (option.value.find_first_of(" \t\r\n") == 0 ||
        option.value.find_last_of(" \t\r\n") == option.value.size() - 1) {
      o.Fail("value", "a value without surrounding white space (answers are trimmed)");
    }
    option.label = DisplayText(o, "label");
    if (!values.insert(option.value).second) {
      o.Fail("value", "a value no other option of this item has");
    }
    o.Finish();
    options.push_back(std::move(option));
  }
  return options;
}

Scale ReadScale(YamlMap& m) {
  Scale s;
  s.min = RequireInteger(m, "min", -kScaleLimit, kScaleLimit);
  s.max = RequireInteger(m, "max", -kScaleLimit, kScaleLimit);
  if (s.max <= s.min) m.Fail("max", "a whole number above min (" + std::to_string(s.min) + ")");
  s.step = m.Integer("step", 1, 1, kScaleLimit);
  if ((s.max - s.min) % s.step != 0) {
    m.Fail("step", "a step that divides max - min (" + std::to_string(s.max - s.min) + ")");
  }
  s.min_label = DisplayText(m, "min_label");
  s.max_label = DisplayText(m, "max_label");
  return s;
}

/// Node and band ids, each with where it is defined: one id, one place.
class TreeIds {
 public:
  void Claim(YamlMap& map, const std::string& id) {
    if (auto [it, fresh] = where_.emplace(id, map.Location()); !fresh) {
      map.Fail("id", "an id no other node or band of this tree has ('" + id + "' is also at " +
                         it->second + ")");
    }
  }
  bool Has(const std::string& id) const { return where_.count(id) != 0; }
  std::string List() const {
    std::string ids;
    for (const auto& [id, loc] : where_) ids += (ids.empty() ? "" : ", ") + id;
    return ids;
  }

 private:
  std::map<std::string, std::string> where_;  // node or band id -> its location
};

/// One band: its ratings consecutive and in no other band (`band_of`:
/// rating -> band id, over the bands read so far).
TreeBand ReadBand(YamlMap& b, TreeIds& ids, std::map<int, std::string>& band_of) {
  TreeBand band;
  band.id = RequireId(b, "id");
  ids.Claim(b, band.id);
  band.text = DisplayText(b, "text");
  std::vector<YamlMap> ratings = b.MapList("ratings");
  if (ratings.empty()) FailCount(b, "ratings", "a list of at least one {rating, text}", 0);
  for (YamlMap& r : ratings) {
    BandRating rating;
    rating.rating = RequireInteger(r, "rating", 0, kMaxRating);
    if (!band.ratings.empty() && rating.rating != band.ratings.back().rating + 1) {
      r.Fail("rating", std::to_string(band.ratings.back().rating + 1) +
                           " (a band's ratings are consecutive whole numbers, ascending)");
    }
    if (auto [it, fresh] = band_of.emplace(rating.rating, band.id); !fresh) {
      r.Fail("rating", "a rating no other band has (" + std::to_string(rating.rating) +
                           " is also in band '" + it->second + "')");
    }
    rating.text = DisplayText(r, "text");
    r.Finish();
    band.ratings.push_back(std::move(rating));
  }
  b.Finish();
  return band;
}

/// Missing bands: the ratings must run from the lowest to the highest.
void CheckRatingsCovered(YamlMap& m, const std::map<int, std::string>& band_of) {
  int expected = band_of.begin()->first;
  for (const auto& [rating, band] : band_of) {
    if (rating != expected) {
      throw ConfigError(m.ItemLocation("bands", 0) + ": key '" + m.Path("bands") +
                        "': expected bands covering every rating from " +
                        std::to_string(band_of.begin()->first) + " to " +
                        std::to_string(band_of.rbegin()->first) + ", but no band has rating " +
                        std::to_string(expected));
    }
    ++expected;
  }
}

/// Branches: to a node or a band, never to the first node, each target
/// reached by one branch only.
void CheckBranches(const DecisionTree& tree, std::vector<YamlMap>& nodes, const TreeIds& ids) {
  const std::string& root = tree.nodes.front().id;
  std::map<std::string, std::string> reached_from;  // target -> "nodes[i].if_yes"
  for (size_t i = 0; i < nodes.size(); ++i) {
    for (const std::string key : {"if_yes", "if_no"}) {
      const std::string& target = key == "if_yes" ? tree.nodes[i].if_yes : tree.nodes[i].if_no;
      if (!ids.Has(target)) nodes[i].Fail(key, kBranchExpected + " (one of: " + ids.List() + ")");
      if (target == root) {
        nodes[i].Fail(key, "a node or a band other than '" + root +
                               "', the first node, where the tree starts");
      }
      const std::string here = "nodes[" + std::to_string(i) + "]." + key;
      if (auto [it, fresh] = reached_from.emplace(target, here); !fresh) {
        nodes[i].Fail(key, "a node or a band no other branch leads to (a decision tree: '" +
                               target + "' is already reached from " + it->second + ")");
      }
    }
  }
}

/// Everything reachable from the first node: no orphan, no loop cut off
/// from the rest (each of its nodes reached once, but not from the start).
void CheckReachable(const DecisionTree& tree, std::vector<YamlMap>& nodes,
                    std::vector<YamlMap>& bands) {
  const std::string& root = tree.nodes.front().id;
  std::set<std::string> reached{root};
  std::vector<const TreeNode*> todo{&tree.nodes.front()};
  while (!todo.empty()) {
    const TreeNode* node = todo.back();
    todo.pop_back();
    for (const std::string& target : {node->if_yes, node->if_no}) {
      if (!reached.insert(target).second) continue;
      if (const TreeNode* next = tree.FindNode(target)) todo.push_back(next);
    }
  }
  const std::string unreached = "a node or a band some path from the first node ('" + root +
                                "') reaches (no branch leads to it from there)";
  for (size_t i = 0; i < nodes.size(); ++i) {
    if (reached.count(tree.nodes[i].id) == 0) nodes[i].Fail("id", unreached);
  }
  for (size_t i = 0; i < bands.size(); ++i) {
    if (reached.count(tree.bands[i].id) == 0) bands[i].Fail("id", unreached);
  }
}

/// Reads the nodes and bands of a tree item and checks that they make one
/// tree whose bands cover a run of ratings once each.
DecisionTree ReadTree(YamlMap& m) {
  DecisionTree tree;
  std::vector<YamlMap> nodes = m.MapList("nodes");
  if (nodes.empty()) {
    FailCount(m, "nodes", "a list of at least one question {id, question, if_yes, if_no}", 0);
  }
  std::vector<YamlMap> bands = m.MapList("bands");
  if (bands.empty()) FailCount(m, "bands", "a list of at least two bands {id, text, ratings}", 0);
  TreeIds ids;
  for (YamlMap& n : nodes) {
    TreeNode node;
    node.id = RequireId(n, "id");
    ids.Claim(n, node.id);
    node.question = DisplayText(n, "question");
    node.if_yes = RequireText(n, "if_yes", kBranchExpected);
    node.if_no = RequireText(n, "if_no", kBranchExpected);
    n.Finish();
    tree.nodes.push_back(std::move(node));
  }
  std::map<int, std::string> band_of;  // rating -> band id
  for (YamlMap& b : bands) tree.bands.push_back(ReadBand(b, ids, band_of));
  CheckRatingsCovered(m, band_of);
  tree.min_rating = band_of.begin()->first;
  tree.max_rating = band_of.rbegin()->first;
  CheckBranches(tree, nodes, ids);
  CheckReachable(tree, nodes, bands);
  return tree;
}

Item ReadItem(YamlMap& m, std::map<std::string, std::string>& item_where) {
  Item item;
  item.id = RequireId(m, "id");
  if (auto [it, fresh] = item_where.emplace(item.id, m.Location()); !fresh) {
    m.Fail("id",
           "an id no other item has ('" + item.id + "' is also the item at " + it->second + ")");
  }
  item.text = DisplayText(m, "text");
  item.required = m.Bool("required", true);
  const std::string type = RequireText(m, "type", kTypeExpected);
  if (type == "choice") {
    item.type = ItemType::kChoice;
    item.options = ReadOptions(m);
  } else if (type == "scale") {
    item.type = ItemType::kScale;
    item.scale = ReadScale(m);
  } else if (type == "text") {
    item.type = ItemType::kText;
    item.max_length = m.Integer("max_length", item.max_length, 1, kMaxTextLength);
  } else if (type == "tree") {
    item.type = ItemType::kTree;
    item.tree = ReadTree(m);
  } else {
    m.Fail("type", kTypeExpected);
  }
  m.Finish();
  return item;
}

/// "a scale 1..7 in steps of 1", "an optional text", ...: what an item is,
/// for a scoring that does not fit it.
std::string Describe(const Item& item) {
  std::string what = item.required ? "a " : "an optional ";
  what += ToString(item.type);
  if (item.type == ItemType::kScale) {
    what += " " + std::to_string(item.scale.min) + ".." + std::to_string(item.scale.max) +
            " in steps of " + std::to_string(item.scale.step);
  }
  return what;
}

/// Throws unless the items are what `scoring` needs (see the header).
void CheckScoring(const YamlMap& root, const Questionnaire& q,
                  const std::map<std::string, std::string>& item_where) {
  std::string needs;
  size_t count = 0;
  std::function<bool(const Item&)> fits;
  switch (q.scoring) {
    case Scoring::kNone:
      return;
    case Scoring::kSus:
      needs = "sus needs exactly 10 items, each a required scale 1..5 in steps of 1";
      count = 10;
      fits = [](const Item& i) {
        return i.type == ItemType::kScale && i.required && i.scale.min == 1 && i.scale.max == 5 &&
               i.scale.step == 1;
      };
      break;
    case Scoring::kTlxRaw:
      needs = "tlx-raw needs exactly 6 items, each a required scale 0..100";
      count = 6;
      fits = [](const Item& i) {
        return i.type == ItemType::kScale && i.required && i.scale.min == 0 && i.scale.max == 100;
      };
      break;
    case Scoring::kRatingTree:
      needs = "rating-tree needs exactly 1 item, a required tree";
      count = 1;
      fits = [](const Item& i) { return i.type == ItemType::kTree && i.required; };
      break;
  }
  if (q.items.size() != count) {
    root.Fail("scoring", "a scoring the items fit: " + needs + "; the file has " +
                             std::to_string(q.items.size()));
  }
  for (const Item& item : q.items) {
    if (!fits(item)) {
      root.Fail("scoring", "a scoring the items fit: " + needs + "; item '" + item.id + "' (" +
                               item_where.at(item.id) + ") is " + Describe(item));
    }
  }
}

}  // namespace

std::string ToString(Scoring scoring) {
  switch (scoring) {
    case Scoring::kNone:
      return "none";
    case Scoring::kSus:
      return "sus";
    case Scoring::kTlxRaw:
      return "tlx-raw";
    case Scoring::kRatingTree:
      return "rating-tree";
  }
  return "?";
}

std::string ToString(ItemType type) {
  switch (type) {
    case ItemType::kChoice:
      return "choice";
    case ItemType::kScale:
      return "scale";
    case ItemType::kText:
      return "text";
    case ItemType::kTree:
      return "tree";
  }
  return "?";
}

const TreeNode* DecisionTree::FindNode(const std::string& id) const {
  for (const TreeNode& n : nodes) {
    if (n.id == id) return &n;
  }
  return nullptr;
}

const TreeBand* DecisionTree::FindBand(const std::string& id) const {
  for (const TreeBand& b : bands) {
    if (b.id == id) return &b;
  }
  return nullptr;
}

const Item* Questionnaire::FindItem(const std::string& id) const {
  for (const Item& i : items) {
    if (i.id == id) return &i;
  }
  return nullptr;
}

Questionnaire LoadQuestionnaire(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  Questionnaire q;
  q.file = file;
  q.name = RequireText(root, "name", kNameExpected);
  if (!IsName(q.name)) root.Fail("name", kNameExpected);
  q.title = DisplayText(root, "title");
  q.instructions = root.String("instructions", "");  // optional
  if (root.Has("instructions")) q.instructions = DisplayText(root, "instructions");
  q.scoring = ReadScoring(root);
  std::vector<YamlMap> items = root.MapList("items");
  if (items.empty())
    FailCount(root, "items", "a list of at least one item {id, text, type, ...}", 0);
  std::map<std::string, std::string> item_where;  // id -> location
  for (YamlMap& m : items) q.items.push_back(ReadItem(m, item_where));
  root.Finish();
  CheckScoring(root, q, item_where);
  return q;
}

Questionnaire FindQuestionnaire(const std::filesystem::path& dir, const std::string& name) {
  const std::filesystem::path file = dir / (name + ".yaml");
  std::error_code ec;
  if (IsName(name) && std::filesystem::is_regular_file(file, ec)) {
    Questionnaire q = LoadQuestionnaire(file);
    if (q.name != name) {
      YamlMap::Load(file).Fail("name", "'" + name + "', the name the file is found by");
    }
    return q;
  }
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    if (entry.path().extension() == ".yaml") names.push_back(entry.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
  throw ConfigError(dir.string() + ": questionnaire '" + name +
                    "': expected one of: " + (list.empty() ? "(no .yaml files there)" : list) +
                    " (the files " + (dir / "<name>.yaml").string() + ")");
}

}  // namespace haptel::study
