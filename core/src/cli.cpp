#include "haptel/core/cli.hpp"

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "haptel/core/args.hpp"
#include "haptel/core/command_line.hpp"

namespace haptel::cli {

bool HelpRequested(int argc, const char* const* argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--") == 0) return false;
    if (std::strcmp(argv[i], "--help") == 0 || std::strcmp(argv[i], "-h") == 0) return true;
  }
  return false;
}

std::string CommandLine(int argc, const char* const* argv) {
  std::string line = "haptel";
  for (int i = 0; i < argc; ++i) {
    const std::string word = argv[i];
    line += ' ';
    if (!word.empty() && word.find_first_of(" \t\n'\"\\$`*?;&|<>()[]{}!#~") == std::string::npos) {
      line += word;
      continue;
    }
    line += '\'';
    for (const char c : word) line += c == '\'' ? std::string("'\\''") : std::string(1, c);
    line += '\'';
  }
  return line;
}

std::vector<std::string> CommandLineWords(const std::string& line) {
  std::vector<std::string> words;
  std::string word;
  bool in_word = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (c == ' ') {
      if (in_word) words.push_back(word);
      word.clear();
      in_word = false;
    } else if (c == '\'') {
      in_word = true;
      const size_t close = line.find('\'', i + 1);
      if (close == std::string::npos) throw UsageError("an unterminated quote in: " + line);
      word += line.substr(i + 1, close - i - 1);
      i = close;
    } else if (c == '\\' && i + 1 < line.size()) {
      word += line[++i];
      in_word = true;
    } else {
      word += c;
      in_word = true;
    }
  }
  if (in_word) words.push_back(word);
  return words;
}

bool HasOption(int argc, const char* const* argv, std::string_view option) {
  for (int i = 1; i < argc; ++i) {
    if (argv[i] == option) return true;
  }
  return false;
}

int Main(const Program& program, int argc, const char* const* argv,
         const std::function<int()>& body) {
  if (HelpRequested(argc, argv)) {
    std::fputs(program.usage.c_str(), stdout);
    return kExitOk;
  }
  try {
    return body();
  } catch (const UsageError& e) {
    std::fprintf(stderr, "%s: %s (see %s --help)\n", program.name.c_str(), e.what(),
                 program.name.c_str());
    return kExitBadInput;
  } catch (const InputError& e) {
    std::fprintf(stderr, "%s: %s\n", program.name.c_str(), e.what());
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", program.name.c_str(), e.what());
    return kExitFailed;
  }
}

}  // namespace haptel::cli
