// `haptel study power`'s command line: options that cannot work are one line
// on stderr and exit 2, before any trial runs.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "haptel/config/paths.hpp"
#include "haptel/study/study_command.hpp"
#include "test_env.hpp"

using Catch::Matchers::Contains;

namespace {

struct Outcome {
  int code = -1;
  std::string err;
};

/// `haptel study power WORDS...`, its stderr caught in a file.
Outcome Power(const std::vector<std::string>& words) {
  std::vector<std::string> all = {"study", "power"};
  all.insert(all.end(), words.begin(), words.end());
  std::vector<const char*> argv;
  for (const std::string& w : all) argv.push_back(w.c_str());
  const auto file = haptel::test::ScratchDir("power-command") / "stderr.txt";
  std::fflush(stderr);
  const int saved = dup(fileno(stderr));
  std::FILE* capture = std::fopen(file.c_str(), "w");
  REQUIRE(capture != nullptr);
  dup2(fileno(capture), fileno(stderr));
  Outcome o;
  o.code = haptel::study::StudyCommand(static_cast<int>(argv.size()), argv.data());
  std::fflush(stderr);
  dup2(saved, fileno(stderr));
  close(saved);
  std::fclose(capture);
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  o.err = text.str();
  return o;
}

int Lines(const std::string& text) { return static_cast<int>(std::count(text.begin(), text.end(), '\n')); }

const std::string kStudy = haptel::ShippedFile("config/studies/grand-prix-synthetic.yaml").string();

}  // namespace

TEST_CASE("haptel study power: bad options are one line and exit 2", "[power]") {
  struct Case {
    std::vector<std::string> words;
    std::string says;
  };
  const std::vector<Case> cases = {
      {{kStudy, "--participants", "0"}, "option --participants: expected a comma-separated list of counts from 1"},
      {{kStudy, "--participants", "4,x"}, "option --participants"},
      // The grand prix's balanced Latin square has 4 rows: a balanced draw needs multiples of 4.
      {{kStudy, "--participants", "3"}, "expected multiples of 4"},
      {{kStudy, "--participants", "4,6"}, "got 6"},
      {{kStudy, "--simulations", "0"}, "--simulations"},
      {{kStudy, "--pool", "6"}, "option --pool: expected a multiple of 4"},
      {{"/nonexistent/study.yaml"}, "/nonexistent/study.yaml"},
      {{}, "missing the study file"},
  };
  for (const Case& c : cases) {
    const Outcome o = Power(c.words);
    INFO((c.words.empty() ? std::string("(no words)") : c.words.back()) << ": " << o.err);
    CHECK(o.code == 2);
    CHECK(Lines(o.err) == 1);
    CHECK_THAT(o.err, Contains("haptel study power") && Contains(c.says));
  }
}

TEST_CASE("haptel study power: a person study has no profiles to simulate", "[power]") {
  const Outcome o = Power({haptel::ShippedFile("config/studies/grand-prix.yaml").string()});
  INFO(o.err);
  CHECK(o.code == 2);
  CHECK(Lines(o.err) == 1);
  CHECK_THAT(o.err, Contains("key 'operators': expected synthetic"));
}
