// `haptel study power FILE`'s command line: its options parsed into
// StudyPowerOptions, then study::RunStudyPower (study/study_power.hpp) runs
// the pool and the analysis.
#include <algorithm>
#include <string>
#include <thread>
#include <vector>

#include "haptel/app/study_command.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/stop_signals.hpp"
#include "haptel/study/study_power.hpp"

namespace haptel::app {
namespace {

constexpr const char* kPowerUsage =
    "usage: haptel study power FILE [options]   how many participants a synthetic study needs\n"
    "\n"
    "Simulates the study (config/studies/*.yaml, simulated drivers) with a pool of simulated\n"
    "participants and estimates, per participant count, the probability that the planned\n"
    "analysis finds the condition effect at alpha 0.05: Friedman's test (its exact p where\n"
    "that is cheap, as the report's; the chi2 approximation past it), and the mixed model\n"
    "log(lap time) ~ condition + position + (1 | participant) by Satterthwaite's F test of\n"
    "condition (as `haptel study report` computes them). Recommends the smallest count whose\n"
    "mixed-model power reaches 80 %.\n"
    "\n"
    "The pool: participant i drives order row i mod rows of the study's design (the balanced\n"
    "Latin square's rows; one row for a random or fixed order) with one of the file's\n"
    "participants' profiles (taken in turn, each row getting each profile alike), every trait\n"
    "multiplied by exp(N(0, 0.1^2)) and clamped to its valid range, and a seed of its own.\n"
    "It runs every condition once per repetition in its row's order, as the study's trials run\n"
    "(practice, cap, link), each in simulated time, two at a time (each worker a process of its\n"
    "own: a simulated-time trial puts its process on its clock). The trials are recorded as\n"
    "a study of their own in OUT/pool-<M>-seed<S>.db (`haptel study report` reads it); run the\n"
    "same command again after a stop to resume. Each simulation then draws n/rows participants\n"
    "from each row of the pool, with replacement.\n"
    "options:\n"
    "  --participants LIST  participant counts, each a multiple of the design's rows\n"
    "                       (default 4,8,12,16)\n"
    "  --simulations N      Monte Carlo simulations per count (default 100)\n"
    "  --pool M             simulated participants in the pool, a multiple of the rows\n"
    "                       (default 8 per row)\n"
    "  --seed S             the pool's profiles and the draws (default 1)\n"
    "  --jobs J             trials run at the same time, one per worker process (default 2)\n"
    "  --out DIR            where the files go (default <database dir>/power-<study>/):\n"
    "                       power.csv, power.png, pool.csv and the pool's database\n"
    "  --domain N           DDS domain id of the trials' vehicles (real time: worker w takes N + "
    "w;\n"
    "                       default the run configuration's)\n"
    "  --real-time          run the pool's trials in real time, each with its vehicle process\n"
    "                       (slow: for checking against the simulated-time trials)\n"
    "  --json               end with one JSON line: power (participants, friedman_power,\n"
    "                       lmm_power and their intervals), recommended_participants,\n"
    "                       pool_participants, simulations, wall_s\n"
    "  --verbose            the sessions' own progress lines\n";

std::vector<int> ParseCounts(const std::string& text) {
  std::vector<int> counts;
  for (const std::string& word : SplitList(text)) {
    size_t used = 0;
    int n = 0;
    try {
      n = std::stoi(word, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != word.size() || n < 1 || n > 1000) {
      throw UsageError(
          "option --participants: expected a comma-separated list of counts from 1 to 1000, got '" +
          text + "'");
    }
    counts.push_back(n);
  }
  std::sort(counts.begin(), counts.end());
  counts.erase(std::unique(counts.begin(), counts.end()), counts.end());
  return counts;
}

unsigned HardwareThreads() { return std::max(1u, std::thread::hardware_concurrency()); }

/// The most trial processes at once: each runs a simulated-time trial as
/// fast as a processor allows.
int MaxJobs() { return static_cast<int>(2 * HardwareThreads()); }

study::StudyPowerOptions ParseStudyPowerArgs(int argc, const char* const* argv) {
  const Args args(
      argc, argv,
      {"participants", "simulations", "pool", "seed", "jobs", "out", "domain", "worker"},
      {"json", "verbose", "real-time"});
  if (args.positional().size() != 2 || args.positional()[0] != "power") {
    throw UsageError(args.positional().size() < 2
                         ? "missing the study file"
                         : "unexpected argument '" + args.positional()[2] + "'");
  }
  study::StudyPowerOptions options;
  options.json = args.Flag("json");
  options.verbose = args.Flag("verbose");
  options.real_time = args.Flag("real-time");
  options.power.simulations = args.Int("simulations", 1, 1000000).value_or(100);
  options.power.seed = static_cast<std::uint64_t>(args.Int("seed", 0, 1 << 30).value_or(1));
  options.jobs = args.Int("jobs", 1, 1 << 20).value_or(2);
  if (options.jobs > MaxJobs()) {
    throw UsageError("option --jobs: expected at most " + std::to_string(MaxJobs()) +
                     " (twice this machine's " + std::to_string(HardwareThreads()) +
                     " hardware threads: each job is a trial process that "
                     "runs flat out; more only share the same processors), got " +
                     std::to_string(options.jobs));
  }
  options.worker = args.Int("worker", 0, options.jobs - 1);
  if (const auto counts = args.Value("participants"))
    options.power.participant_counts = ParseCounts(*counts);
  options.pool = args.Int("pool", 1, 10000);
  options.file = args.positional()[1];
  options.domain = args.Int("domain", 0, 232);
  if (const auto out = args.Value("out")) options.out = *out;
  for (int i = 0; i < argc; ++i) options.words.push_back(argv[i]);  // "study", "power", FILE, ...
  return options;
}

}  // namespace

int StudyPowerCommand(int argc, const char* const* argv) {
  const std::atomic<bool>& interrupted = InstallStopSignals();
  return cli::Main({"haptel study power", kPowerUsage}, argc, argv, [&] {
    const study::StudyPowerOptions options =
        cli::ReadInput([&] { return ParseStudyPowerArgs(argc, argv); });
    return study::RunStudyPower(options, interrupted);
  });
}

}  // namespace haptel::app
