#pragma once
// The head of a study file written by an e2e test into its scratch folder:
// its name, then the shipped run configuration and the short track by
// absolute path (the file is not beside them), and the twin's reality (the
// tests are about the study, not the vehicle). The test appends the rest.
#include <filesystem>
#include <string>

namespace haptel::test {

inline std::string StudyFileHead(const std::string& name) {
  const std::filesystem::path source = std::filesystem::current_path();
  return "name: " + name + "\nrun: " + (source / "config/haptel.yaml").string() +
         "\ntrack: " + (source / "config/tracks/test-short.yaml").string() + "\nreality: none\n";
}

}  // namespace haptel::test
