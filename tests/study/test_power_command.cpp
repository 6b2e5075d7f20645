// `haptel study power`'s command line: options that cannot work are one line
// on stderr and exit 2, before any trial runs.
#include <signal.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "haptel/app/study_command.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/core/child_process.hpp"
#include "haptel/record/recorder.hpp"
#include "haptel/study/plan.hpp"
#include "haptel/study/power_pool.hpp"
#include "haptel/study/store.hpp"
#include "study_test_run.hpp"
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
  o.code = haptel::app::StudyCommand(static_cast<int>(argv.size()), argv.data());
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

int Lines(const std::string& text) {
  return static_cast<int>(std::count(text.begin(), text.end(), '\n'));
}

const std::string kStudy = haptel::ShippedFile("config/studies/grand-prix-synthetic.yaml").string();

}  // namespace

TEST_CASE("haptel study power: bad options are one line and exit 2", "[power]") {
  struct Case {
    std::vector<std::string> words;
    std::string says;
  };
  const std::vector<Case> cases = {
      {{kStudy, "--participants", "0"},
       "option --participants: expected a comma-separated list of counts from 1"},
      {{kStudy, "--participants", "4,x"}, "option --participants"},
      // The grand prix's balanced Latin square has 4 rows: a balanced draw needs multiples of 4.
      {{kStudy, "--participants", "3"}, "expected multiples of 4"},
      {{kStudy, "--participants", "4,6"}, "got 6"},
      {{kStudy, "--simulations", "0"}, "--simulations"},
      {{kStudy, "--pool", "6"}, "option --pool: expected a multiple of 4"},
      {{"/nonexistent/study.yaml"}, "/nonexistent/study.yaml"},
      // An output that cannot be written is found before anything runs.
      {{kStudy, "--out", "/etc/passwd"}, "option --out: cannot write into the folder /etc/passwd"},
      // More trial processes than twice the machine's threads only share
      // them. (With a bad --participants after it: unbounded, it would run.)
      {{kStudy, "--jobs", std::to_string(2 * std::max(1u, std::thread::hardware_concurrency()) + 1),
        "--participants", "0"},
       "option --jobs: expected at most"},
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

namespace {

/// The command's children (its worker processes), from /proc.
bool HasChildren(pid_t pid) {
  std::ifstream children("/proc/" + std::to_string(pid) + "/task/" + std::to_string(pid) +
                         "/children");
  std::string first;
  return static_cast<bool>(children >> first);
}

}  // namespace

TEST_CASE(
    "haptel study power: a signal during the analysis ends it at once, exit 1, no file written",
    "[power]") {
  using namespace haptel;
  // A pool of 8 whose every trial is recorded already, as a finished (or
  // resumed) pool is: the command goes straight to its simulations.
  const auto out = test::ScratchDir("power-signal");
  const StudyConfig study = LoadStudy(kStudy);
  const int rows = study::BlockSize(study);
  REQUIRE(rows == 4);
  const StudyConfig pool = study::PowerPoolStudy(study, 8, rows, 1);
  const std::vector<study::PlannedTrial> plan = study::PlanTrials(pool);
  {
    record::Recorder recorder(out / "pool-8-seed1.db");
    study::StudyStore store(recorder, pool, plan);
    int i = 0;
    for (const study::PlannedTrial& t : plan) {
      recorder.Save(test::TrialRun(30.0 + 3.0 * t.condition.size() + (i++ % 7)),
                    store.TrialWriter(t, 600.0));
    }
  }
  // A million simulations per count: hours, unless the signal ends them.
  ChildProcess command((test::BinDir() / "haptel").string(),
                       {"study", "power", kStudy, "--pool", "8", "--simulations", "1000000",
                        "--jobs", "1", "--out", out.string()},
                       ChildProcess::Options{true});
  // The pool's phase is over once its worker has come and gone.
  bool worker_seen = false;
  const bool analysing = test::WaitFor(
      [&] {
        command.Pump();
        const bool children = HasChildren(command.pid());
        worker_seen = worker_seen || children;
        return worker_seen && !children && command.err().find("a pool of 8") != std::string::npos;
      },
      60.0);
  INFO(command.err());
  REQUIRE(analysing);
  kill(command.pid(), SIGTERM);
  const int code = command.Wait(30.0);
  command.Pump();
  INFO(command.err());
  CHECK(code == 1);
  CHECK_THAT(command.err(), Contains("interrupted"));
  // Nothing that looks like a result: the pool's database alone.
  for (const auto& entry : std::filesystem::directory_iterator(out)) {
    CAPTURE(entry.path().filename().string());
    CHECK(entry.path().filename().string().rfind("pool-8-seed1.db", 0) == 0);
  }
}
