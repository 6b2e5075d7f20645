#include "haptel/study/answers.hpp"

#include <algorithm>
#include <charconv>
#include <set>
#include <stdexcept>
#include <string_view>

namespace haptel::study {

namespace {

constexpr size_t kMaxQuotedBytes = 40;  // of a bad value repeated in a message

std::string Trim(std::string_view s) {
  const auto space = [](char c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
  };
  while (!s.empty() && space(s.front())) s.remove_prefix(1);
  while (!s.empty() && space(s.back())) s.remove_suffix(1);
  return std::string(s);
}

/// A whole number written plainly ("7", "-2"; not "7.0", "+7", "7 apples").
std::optional<int> ParseInt(const std::string& s) {
  int value = 0;
  const char* end = s.data() + s.size();
  const auto [ptr, ec] = std::from_chars(s.data(), end, value);
  if (s.empty() || ec != std::errc() || ptr != end) return std::nullopt;
  return value;
}

/// 'value', shortened (at a character boundary) when long.
std::string Quote(const std::string& value) {
  size_t cut = std::min(value.size(), kMaxQuotedBytes);
  while (cut < value.size() && cut > 0 && (static_cast<unsigned char>(value[cut]) & 0xC0) == 0x80) {
    --cut;
  }
  std::string quoted = "'";
  quoted.append(value, 0, cut);
  quoted += cut < value.size() ? "...'" : "'";
  return quoted;
}

std::string ScaleExpected(const Scale& s) {
  return "an integer " + std::to_string(s.min) + ".." + std::to_string(s.max) +
         (s.step != 1 ? " in steps of " + std::to_string(s.step) : "");
}

/// Collects the answers and the errors of one submission.
class Checker {
 public:
  explicit Checker(const std::map<std::string, std::string>& submitted) : submitted_(submitted) {}

  /// The submitted text under `key`, trimmed; nullopt when absent or blank
  /// (an optional item left empty in a form).
  std::optional<std::string> Get(const std::string& key) const {
    const auto it = submitted_.find(key);
    if (it == submitted_.end()) return std::nullopt;
    std::string value = Trim(it->second);
    if (value.empty()) return std::nullopt;
    return value;
  }

  void Error(const std::string& item, const std::string& key, const std::string& what) {
    check_.errors.push_back({item, "item '" + key + "': " + what});
  }
  void Add(const std::string& item, const std::string& value) {
    check_.answers.push_back({item, value});
  }

  void Check(const Item& item) {
    switch (item.type) {
      case ItemType::kScale:
        return CheckScale(item);
      case ItemType::kChoice:
        return CheckChoice(item);
      case ItemType::kText:
        return CheckText(item);
      case ItemType::kTree:
        return CheckTree(item);
    }
    throw std::logic_error("ValidateAnswers: item '" + item.id + "' has an unknown type");
  }

  AnswerCheck Result() && {
    if (!check_.errors.empty()) check_.answers.clear();
    return std::move(check_);
  }

 private:
  void CheckScale(const Item& item) {
    const std::optional<std::string> value = Get(item.id);
    const std::string expected = "expected " + ScaleExpected(item.scale);
    if (!value) {
      if (item.required) Error(item.id, item.id, expected + ", but it is missing");
      return;
    }
    const std::optional<int> n = ParseInt(*value);
    if (!n || *n < item.scale.min || *n > item.scale.max ||
        (*n - item.scale.min) % item.scale.step) {
      return Error(item.id, item.id, expected + ", got " + Quote(*value));
    }
    Add(item.id, std::to_string(*n));
  }

  void CheckChoice(const Item& item) {
    std::string expected = "expected one of ";
    for (size_t i = 0; i < item.options.size(); ++i) {
      expected += (i == 0 ? "'" : ", '") + item.options[i].value + "'";
    }
    const std::optional<std::string> value = Get(item.id);
    if (!value) {
      if (item.required) Error(item.id, item.id, expected + ", but it is missing");
      return;
    }
    for (const ChoiceOption& option : item.options) {
      if (option.value == *value) return Add(item.id, option.value);
    }
    Error(item.id, item.id, expected + ", got " + Quote(*value));
  }

  void CheckText(const Item& item) {
    const std::optional<std::string> value = Get(item.id);
    if (!value) {
      if (item.required) Error(item.id, item.id, "expected some text, but it is missing");
      return;
    }
    if (!IsUtf8(*value)) return Error(item.id, item.id, "expected UTF-8 text, got other bytes");
    if (const size_t n = Utf8Characters(*value); n > static_cast<size_t>(item.max_length)) {
      return Error(item.id, item.id,
                   "expected at most " + std::to_string(item.max_length) + " characters, got " +
                       std::to_string(n));
    }
    Add(item.id, *value);
  }

  void CheckTree(const Item& item) {
    const DecisionTree& tree = item.tree;
    if (tree.nodes.empty() || tree.bands.empty()) {
      throw std::logic_error("ValidateAnswers: tree item '" + item.id + "' has no nodes or bands");
    }
    const std::string path_key = PathKey(item.id);
    const std::optional<std::string> rating_text = Get(item.id);
    const std::optional<std::string> path_text = Get(path_key);
    if (!rating_text && !path_text && !item.required) return;

    const size_t errors_before = check_.errors.size();
    const TreeBand* band = nullptr;
    std::string path;
    if (!path_text) {
      Error(item.id, path_key,
            "expected the yes/no answers from '" + tree.nodes.front().id + "' to a band, e.g. '" +
                tree.nodes.front().id + "=yes,...', but it is missing");
    } else {
      band = Follow(item, *path_text, &path);
    }

    const std::string expected = "expected an integer " + std::to_string(tree.min_rating) + ".." +
                                 std::to_string(tree.max_rating);
    std::optional<int> rating;
    if (!rating_text) {
      Error(item.id, item.id, expected + ", but it is missing");
    } else if (rating = ParseInt(*rating_text);
               !rating || *rating < tree.min_rating || *rating > tree.max_rating) {
      Error(item.id, item.id, expected + ", got " + Quote(*rating_text));
    } else if (band != nullptr && !band->Contains(*rating)) {
      Error(item.id, item.id,
            "expected a rating " + std::to_string(band->min()) + ".." +
                std::to_string(band->max()) + " (band '" + band->id +
                "', where the path leads), got " + Quote(*rating_text));
    }
    if (check_.errors.size() != errors_before) return;
    Add(item.id, std::to_string(*rating));
    Add(path_key, path);
  }

  /// Follows "node=yes,node=no,..." from the first node; the band it ends
  /// in, or null after recording why it does not. `normal` gets the path as
  /// stored.
  const TreeBand* Follow(const Item& item, const std::string& text, std::string* normal) {
    const DecisionTree& tree = item.tree;
    const std::string key = PathKey(item.id);
    const TreeNode* at = &tree.nodes.front();
    const TreeBand* band = nullptr;
    std::string previous;  // the step before, normalised
    size_t start = 0;
    for (size_t n = 1; start <= text.size(); ++n) {
      size_t comma = text.find(',', start);
      if (comma == std::string::npos) comma = text.size();
      const std::string step = Trim(std::string_view(text).substr(start, comma - start));
      start = comma + 1;
      const std::string at_step = "step " + std::to_string(n) + ": ";

      const size_t equals = step.find('=');
      const std::string node = Trim(std::string_view(step).substr(0, equals));
      const std::string answer =
          equals == std::string::npos ? "" : Trim(std::string_view(step).substr(equals + 1));
      if (band != nullptr) {
        Error(item.id, key,
              at_step + "expected nothing more: the path reached band '" + band->id + "' at step " +
                  std::to_string(n - 1) + ", got " + Quote(step));
        return nullptr;
      }
      if (answer != "yes" && answer != "no") {
        Error(item.id, key,
              at_step + "expected '" + at->id + "=yes' or '" + at->id + "=no', got " + Quote(step));
        return nullptr;
      }
      if (node != at->id) {
        Error(item.id, key,
              at_step + "expected an answer to '" + at->id + "' (" +
                  (previous.empty() ? "the first question" : "where " + previous + " leads") +
                  "), got " + Quote(step));
        return nullptr;
      }
      previous = node + "=" + answer;
      *normal += (normal->empty() ? "" : ",") + previous;
      const std::string& target = answer == "yes" ? at->if_yes : at->if_no;
      if (const TreeNode* next = tree.FindNode(target)) {
        at = next;
      } else if (const TreeBand* reached = tree.FindBand(target)) {
        band = reached;
      } else {
        throw std::logic_error("ValidateAnswers: tree item '" + item.id + "': node '" + at->id +
                               "' leads to '" + target + "', which is neither a node nor a band");
      }
    }
    if (band == nullptr) {
      Error(item.id, key,
            "expected an answer to '" + at->id + "' (where " + previous +
                " leads), but the path stops before it");
    }
    return band;
  }

  const std::map<std::string, std::string>& submitted_;
  AnswerCheck check_;
};

}  // namespace

bool IsUtf8(const std::string& s) {
  size_t i = 0;
  while (i < s.size()) {
    const auto c = static_cast<unsigned char>(s[i]);
    size_t extra = 0;
    unsigned int cp = 0;
    if (c < 0x80) {
      ++i;
      continue;
    } else if (c >= 0xC2 && c <= 0xDF) {
      extra = 1;
      cp = c & 0x1F;
    } else if (c >= 0xE0 && c <= 0xEF) {
      extra = 2;
      cp = c & 0x0F;
    } else if (c >= 0xF0 && c <= 0xF4) {
      extra = 3;
      cp = c & 0x07;
    } else {
      return false;
    }
    if (i + extra >= s.size()) return false;  // cut short
    for (size_t k = 1; k <= extra; ++k) {
      const auto d = static_cast<unsigned char>(s[i + k]);
      if ((d & 0xC0) != 0x80) return false;
      cp = (cp << 6) | (d & 0x3F);
    }
    const unsigned int least[] = {0, 0x80, 0x800, 0x10000};
    if (cp < least[extra] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return false;
    i += extra + 1;
  }
  return true;
}

size_t Utf8Characters(const std::string& s) {
  size_t n = 0;
  for (const char c : s) n += (static_cast<unsigned char>(c) & 0xC0) != 0x80 ? 1 : 0;
  return n;
}

std::string PathKey(const std::string& tree_item_id) { return tree_item_id + ".path"; }

AnswerCheck ValidateAnswers(const Questionnaire& questionnaire,
                            const std::map<std::string, std::string>& submitted) {
  Checker checker(submitted);
  std::set<std::string> known;
  for (const Item& item : questionnaire.items) {
    known.insert(item.id);
    if (item.type == ItemType::kTree) known.insert(PathKey(item.id));
    checker.Check(item);
  }
  for (const auto& [key, value] : submitted) {
    if (known.count(key) != 0) continue;
    std::string list;
    for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
    checker.Error(
        key, key,
        "unknown item; expected one of: " + list + " (questionnaire '" + questionnaire.name + "')");
  }
  return std::move(checker).Result();
}

std::optional<double> Score(const Questionnaire& questionnaire,
                            const std::vector<Answer>& answers) {
  const std::string what = "Score: questionnaire '" + questionnaire.name + "': ";
  std::map<std::string, std::string> value_of;
  for (const Answer& a : answers) {
    if (!value_of.emplace(a.item, a.value).second) {
      throw std::invalid_argument(what + "item '" + a.item + "' is answered twice");
    }
  }
  // The integer answer to `item` within [min, max].
  const auto integer = [&](const Item& item, int min, int max) {
    const auto it = value_of.find(item.id);
    if (it == value_of.end()) {
      throw std::invalid_argument(what + "no answer to item '" + item.id + "'");
    }
    const std::optional<int> n = ParseInt(it->second);
    if (!n || *n < min || *n > max) {
      throw std::invalid_argument(what + "item '" + item.id + "': " + Quote(it->second) +
                                  " is not an integer " + std::to_string(min) + ".." +
                                  std::to_string(max) + " (answers not from ValidateAnswers?)");
    }
    return *n;
  };
  const auto need = [&](size_t count, ItemType type) {
    bool fits = questionnaire.items.size() == count;
    for (const Item& item : questionnaire.items) fits = fits && item.type == type;
    if (!fits) {
      throw std::logic_error(what + "scoring " + ToString(questionnaire.scoring) + " needs " +
                             std::to_string(count) + " " + ToString(type) +
                             " items (a questionnaire LoadQuestionnaire would refuse)");
    }
  };

  switch (questionnaire.scoring) {
    case Scoring::kNone:
      return std::nullopt;
    case Scoring::kSus: {
      // Items 1, 3, 5, 7, 9 (indices 0, 2, ...) are worded positively.
      need(10, ItemType::kScale);
      int sum = 0;
      for (size_t i = 0; i < questionnaire.items.size(); ++i) {
        const int x = integer(questionnaire.items[i], 1, 5);
        sum += i % 2 == 0 ? x - 1 : 5 - x;
      }
      return 2.5 * sum;
    }
    case Scoring::kTlxRaw: {
      need(6, ItemType::kScale);
      double sum = 0.0;
      for (const Item& item : questionnaire.items) sum += integer(item, 0, 100);
      return sum / static_cast<double>(questionnaire.items.size());
    }
    case Scoring::kRatingTree: {
      need(1, ItemType::kTree);
      const DecisionTree& tree = questionnaire.items.front().tree;
      return integer(questionnaire.items.front(), tree.min_rating, tree.max_rating);
    }
  }
  throw std::logic_error(what + "unknown scoring");
}

}  // namespace haptel::study
