#pragma once
// The head of a study file written by an e2e test into its scratch folder:
// its name, then the shipped run configuration and the short track by
// absolute path (the file is not beside them), and the twin's reality (the
// tests are about the study, not the vehicle). The test appends the rest.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

namespace haptel::test {

inline std::string StudyFileHead(const std::string& name) {
  const std::filesystem::path source = std::filesystem::current_path();
  return "name: " + name + "\nrun: " + (source / "config/haptel.yaml").string() +
         "\ntrack: " + (source / "config/tracks/test-short.yaml").string() + "\nreality: none\n";
}

/// The file at `from` with each of `replacements` made once (each must be there).
inline std::string Rewritten(const std::filesystem::path& from,
                             const std::vector<std::pair<std::string, std::string>>& replacements) {
  std::ifstream in(from);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  for (const auto& [old_text, new_text] : replacements) {
    const size_t at = text.find(old_text);
    REQUIRE(at != std::string::npos);
    text.replace(at, old_text.size(), new_text);
  }
  return text;
}

/// The shipped run configuration (config/haptel.yaml) written into `dir` as
/// `run.yaml` with `replacements` made, its other files by absolute path (a
/// vehicle file replaced by another keeps that one's path).
inline std::filesystem::path ShippedRunIn(
    const std::filesystem::path& dir,
    std::vector<std::pair<std::string, std::string>> replacements) {
  const auto config = std::filesystem::current_path() / "config";
  std::string text = Rewritten(config / "haptel.yaml", replacements);
  for (const char* key : {"track: ", "vehicle: ", "device: ", "physics: "}) {
    for (size_t at = text.find(std::string("\n") + key); at != std::string::npos;
         at = text.find(std::string("\n") + key, at + 1)) {
      const size_t value = at + 1 + std::string(key).size();
      if (text.compare(value, 1, "/") != 0) text.insert(value, config.string() + "/");
    }
  }
  const auto run = dir / "run.yaml";
  std::ofstream(run) << text << "interfaces_dir: " << (config / "interfaces").string() << "\n";
  return run;
}

}  // namespace haptel::test
