#pragma once
// The program under an end-to-end test: the product's own ChildProcess with
// its stdout and stderr captured (one way to start processes in Haptel).
#include <string>
#include <vector>

#include "haptel/core/child_process.hpp"

namespace haptel::test {

class Child : public ChildProcess {
 public:
  /// argv[0] is the program.
  explicit Child(std::vector<std::string> argv)
      : ChildProcess(argv.at(0), std::vector<std::string>(argv.begin() + 1, argv.end()),
                     Options{true}) {}
  static constexpr int kRunning = kStillRunning;
};

/// Value of a top-level key in a flat JSON object line (numbers, bools, strings).
inline std::string JsonField(const std::string& json, const std::string& key) {
  const std::string needle = "\"" + key + "\":";
  const auto at = json.find(needle);
  if (at == std::string::npos) return "";
  auto start = at + needle.size();
  if (json[start] == '"') {
    const auto end = json.find('"', start + 1);
    return json.substr(start + 1, end - start - 1);
  }
  const auto end = json.find_first_of(",}", start);
  return json.substr(start, end - start);
}

}  // namespace haptel::test
