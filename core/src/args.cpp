#include "haptel/core/args.hpp"

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
      if (values_[name].empty()) throw UsageError("option --" + name + " expects a non-empty value");
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

}  // namespace haptel
