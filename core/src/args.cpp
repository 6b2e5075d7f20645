#include "haptel/core/args.hpp"

#include <cctype>
#include <cstdlib>
#include <sstream>

namespace haptel {

Args::Args(int argc, const char* const* argv, std::set<std::string> value_options,
           std::set<std::string> flags) {
  for (int i = 1; i < argc; ++i) {
    std::string word = argv[i];
    if (word.rfind("--", 0) != 0 || word == "--") {
      positional_.push_back(word);
      continue;
    }
    std::string name = word.substr(2);
    std::optional<std::string> inline_value;
    if (const auto eq = name.find('='); eq != std::string::npos) {
      inline_value = name.substr(eq + 1);
      name = name.substr(0, eq);
    }
    if (flags.count(name) != 0) {
      if (inline_value) throw UsageError("option --" + name + " takes no value");
      flags_set_.insert(name);
    } else if (value_options.count(name) != 0) {
      if (inline_value) {
        values_[name] = *inline_value;
      } else if (i + 1 < argc) {
        values_[name] = argv[++i];
      } else {
        throw UsageError("option --" + name + " expects a value");
      }
      if (values_[name].empty())
        throw UsageError("option --" + name + " expects a non-empty value");
    } else {
      throw UsageError("unknown option --" + name);
    }
  }
}

std::optional<std::string> Args::Value(const std::string& name) const {
  const auto it = values_.find(name);
  if (it == values_.end()) return std::nullopt;
  return it->second;
}

std::optional<int> Args::Int(const std::string& name, int min, int max) const {
  const auto text = Value(name);
  if (!text) return std::nullopt;
  try {
    size_t used = 0;
    const int value = std::stoi(*text, &used);
    if (used == text->size() && value >= min && value <= max) return value;
  } catch (const std::exception&) {
  }
  throw UsageError("option --" + name + ": expected a whole number in [" + std::to_string(min) +
                   ", " + std::to_string(max) + "], got '" + *text + "'");
}

size_t DecimalPrefix(const std::string& text) {
  const auto digit = [&](size_t i) { return i < text.size() && text[i] >= '0' && text[i] <= '9'; };
  size_t i = 0;
  if (i < text.size() && (text[i] == '+' || text[i] == '-')) ++i;
  size_t digits = 0;
  for (; digit(i); ++i) ++digits;
  if (i < text.size() && text[i] == '.') {
    ++i;
    for (; digit(i); ++i) ++digits;
  }
  if (digits == 0) return 0;
  // An exponent only when digits follow it: "5e" is 5 and a unit "e".
  if (i < text.size() && (text[i] == 'e' || text[i] == 'E')) {
    size_t j = i + 1;
    if (j < text.size() && (text[j] == '+' || text[j] == '-')) ++j;
    if (digit(j)) {
      for (i = j; digit(i); ++i) {
      }
    }
  }
  return i;
}

std::optional<double> Args::Number(const std::string& name, double min, double max) const {
  const auto text = Value(name);
  if (!text) return std::nullopt;
  char* end = nullptr;
  const double value = std::strtod(text->c_str(), &end);
  const bool whole = !text->empty() && DecimalPrefix(*text) == text->size() && *end == '\0';
  if (whole && value >= min && value <= max) return value;
  std::ostringstream range;
  range << "[" << min << ", " << max << "]";
  throw UsageError("option --" + name + ": expected a number in " + range.str() + ", got '" +
                   *text + "'");
}

std::string JoinList(const std::vector<std::string>& parts, const std::string& separator) {
  std::string text;
  for (size_t i = 0; i < parts.size(); ++i) {
    if (i > 0) text += separator;
    text += parts[i];
  }
  return text;
}

std::vector<std::string> SplitList(const std::string& text, char separator) {
  std::vector<std::string> parts;
  size_t start = 0;
  for (;;) {
    const size_t at = text.find(separator, start);
    parts.push_back(text.substr(start, at == std::string::npos ? std::string::npos : at - start));
    if (at == std::string::npos) return parts;
    start = at + 1;
  }
}

}  // namespace haptel
