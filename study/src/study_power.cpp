// `haptel study power STUDY.yaml`: how many participants the study needs.
// A pool of simulated participants (the file's driver profiles, varied) runs
// the study's trials, in simulated time; the Monte Carlo of power.hpp then
// draws balanced samples of each participant count from the pool and
// analyses them as the report does.
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "haptel/config/error.hpp"
#include "haptel/config/run.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/child_process.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/json.hpp"
#include "haptel/core/stop_signals.hpp"
#include "haptel/mediator/run_command.hpp"
#include "haptel/study/plan.hpp"
#include "haptel/study/power.hpp"
#include "haptel/study/power_pool.hpp"
#include "haptel/study/report.hpp"
#include "haptel/study/store.hpp"
#include "haptel/study/study_command.hpp"
#include "haptel/study/study_sessions.hpp"

namespace haptel::study {
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

std::string Fixed(double value, int decimals) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  return buffer;
}

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

/// The output folder, made if missing, and a file written and removed in
/// it: an output that cannot be written is bad input (exit 2), found before
/// any trial runs.
void CheckWritableFolder(const std::filesystem::path& out) {
  std::error_code error;
  std::filesystem::create_directories(out, error);
  if (!error && !std::filesystem::is_directory(out, error))
    error = std::make_error_code(std::errc::not_a_directory);
  const std::filesystem::path probe = out / (".write-check-" + std::to_string(getpid()));
  if (!error) {
    std::ofstream file(probe);
    file << "x";
    file.close();
    if (!file) error = std::error_code(errno != 0 ? errno : EACCES, std::generic_category());
    std::error_code ignored;
    std::filesystem::remove(probe, ignored);
  }
  if (error) {
    throw UsageError(
        "option --out: cannot write into the folder " + out.string() + " (" + error.message() +
        "); expected a folder this user can write (default <database dir>/power-<study>)");
  }
}

/// Writes `text` to `file` through a temporary file renamed over it: a
/// file is there whole or not at all.
void WriteWhole(const std::filesystem::path& file, const std::string& text) {
  const std::filesystem::path part = file.string() + ".part";
  std::ofstream out(part, std::ios::binary);
  out << text;
  out.close();
  std::error_code renamed;
  if (out) std::filesystem::rename(part, file, renamed);
  if (!out || renamed) {
    std::filesystem::remove(part, renamed);
    throw std::runtime_error("cannot write " + file.string());
  }
}

/// Worker `worker` of `jobs`: runs the pool participants i with
/// i mod jobs = worker, each one's trials in order as `haptel study run` runs
/// a synthetic participant's (experience counts the trials before and the
/// practice; a flagged trial runs again once). A trial that cannot be
/// finished (a fault) runs once more; after a second fault the participant
/// is left, the others go on. Returns 0 when all its participants are done,
/// 1 otherwise.
int RunPoolShare(const StudyConfig& pool_config, const std::vector<PlannedTrial>& plan,
                 const std::filesystem::path& pool_database, const std::string& domain,
                 bool verbose, bool simulated_time, int worker, int jobs,
                 const std::atomic<bool>& interrupted) {
  record::Recorder recorder(pool_database);
  StudyStore store(recorder, pool_config, plan);
  const auto started = std::chrono::steady_clock::now();
  int exit_code = cli::kExitOk;
  for (size_t i = static_cast<size_t>(worker);
       i < pool_config.participants.size() && !interrupted.load(); i += static_cast<size_t>(jobs)) {
    const std::string& participant = pool_config.participants[i].id;
    int faults = 0;
    for (;;) {
      std::optional<PlannedTrial> trial;
      const std::vector<TrialRow> done = store.Trials();
      for (const PlannedTrial& t : plan) {
        if (t.participant != participant) continue;
        const bool has_row = std::any_of(done.begin(), done.end(), [&](const TrialRow& r) {
          return r.participant == t.participant && r.position == t.position;
        });
        if (!has_row) {
          trial = t;
          break;
        }
      }
      if (!trial || interrupted.load()) break;
      const int experience = store.TrialsDone(participant) + (pool_config.practice ? 1 : 0);
      const mediator::SessionSetup setup = TrialSetup(pool_config, *trial, pool_database, domain,
                                                      verbose, experience, simulated_time);
      const mediator::RecordedRun run = mediator::RunAndRecord(
          setup, recorder, interrupted, store.TrialWriter(*trial, pool_config.trial_cap_s));
      const std::string outcome = mediator::ToString(run.result.outcome);
      if (run.run_id != 0 && FinishesTrial(outcome)) {
        const double elapsed =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
        std::fprintf(
            stderr,
            "[power] %zu/%zu %s position %d %s: %s, lap %s s (run %lld, worker %d, %.0f s)\n",
            store.Trials().size(), plan.size(), participant.c_str(), trial->position,
            trial->condition.c_str(), outcome.c_str(),
            Fixed(run.result.record.completed ? run.result.record.lap_time_s
                                              : pool_config.trial_cap_s,
                  2)
                .c_str(),
            static_cast<long long>(run.run_id), worker, elapsed);
        if (store.RedoFlaggedOnce(*trial)) {
          std::fprintf(stderr, "[power]   flagged (%s): run again once\n",
                       TrialFlags(run.result.record).c_str());
        }
        continue;
      }
      if (interrupted.load()) break;
      std::fprintf(stderr, "[power] %s position %d %s: %s: %s%s\n", participant.c_str(),
                   trial->position, trial->condition.c_str(), outcome.c_str(),
                   run.result.message.c_str(),
                   faults == 0 ? "; once more" : "; the participant is left out");
      if (++faults > 1) {
        exit_code = cli::kExitFailed;
        break;
      }
    }
  }
  std::fflush(stderr);
  return interrupted.load() ? cli::kExitFailed : exit_code;
}

}  // namespace

int StudyPowerCommand(int argc, const char* const* argv) {
  const std::atomic<bool>& interrupted = InstallStopSignals();
  return cli::Main({"haptel study power", kPowerUsage}, argc, argv, [&] {
    const auto started = std::chrono::steady_clock::now();
    StudyConfig study;
    StudyConfig pool_config;
    std::vector<PlannedTrial> plan;
    PowerOptions options;
    int rows = 1;
    int pool = 0;
    int jobs = 2;
    std::optional<int>
        worker;  ///< set: this process is worker N of the pool (spawned by the command itself)
    bool json = false;
    bool verbose = false;
    bool real_time = false;
    std::string domain;
    std::filesystem::path out;
    std::filesystem::path pool_database;
    cli::ReadInput([&] {
      const Args args(
          argc, argv,
          {"participants", "simulations", "pool", "seed", "jobs", "out", "domain", "worker"},
          {"json", "verbose", "real-time"});
      if (args.positional().size() != 2 || args.positional()[0] != "power") {
        throw UsageError(args.positional().size() < 2
                             ? "missing the study file"
                             : "unexpected argument '" + args.positional()[2] + "'");
      }
      json = args.Flag("json");
      verbose = args.Flag("verbose");
      real_time = args.Flag("real-time");
      options.simulations = args.Int("simulations", 1, 1000000).value_or(100);
      options.seed = static_cast<std::uint64_t>(args.Int("seed", 0, 1 << 30).value_or(1));
      jobs = args.Int("jobs", 1, 1 << 20).value_or(2);
      if (jobs > MaxJobs()) {
        throw UsageError("option --jobs: expected at most " + std::to_string(MaxJobs()) +
                         " (twice this machine's " + std::to_string(HardwareThreads()) +
                         " hardware threads: each job is a trial process that "
                         "runs flat out; more only share the same processors), got " +
                         std::to_string(jobs));
      }
      worker = args.Int("worker", 0, jobs - 1);
      if (const auto counts = args.Value("participants"))
        options.participant_counts = ParseCounts(*counts);
      const std::optional<int> pool_option = args.Int("pool", 1, 10000);
      study = LoadStudy(args.positional()[1]);
      if (study.operators != "synthetic") {
        throw ConfigError(
            study.file.string() +
            ": key 'operators': expected synthetic for `haptel study power` (it simulates the "
            "participants with the file's driver profiles), got " +
            study.operators);
      }
      if (study.participants.empty()) {
        throw ConfigError(
            study.file.string() +
            ": key 'participants': expected at least one simulated participant (their profiles "
            "are the pool's)");
      }
      rows = BlockSize(study);
      for (const int n : options.participant_counts) {
        if (n % rows != 0) {
          throw UsageError("option --participants: expected multiples of " + std::to_string(rows) +
                           " (the rows of the study's " + ToString(study.order) +
                           " design: a balanced draw takes as many from each), got " +
                           std::to_string(n));
        }
      }
      pool = pool_option.value_or(8 * rows);
      if (pool % rows != 0) {
        throw UsageError("option --pool: expected a multiple of " + std::to_string(rows) +
                         " (the rows of the study's design), got " + std::to_string(pool));
      }
      pool_config = PowerPoolStudy(study, pool, rows, options.seed);
      plan = PlanTrials(pool_config);
      const RunConfig run_config = LoadRun(study.run);
      // In real time each worker's vehicles get a DDS domain of their own:
      // two vehicles of one name on one domain would answer each other's operator.
      const int base_domain = args.Int("domain", 0, 232).value_or(run_config.link.domain_id);
      if (real_time && base_domain + jobs - 1 > 232) {
        throw UsageError("option --domain: the " + std::to_string(jobs) + " workers take domains " +
                         std::to_string(base_domain) + ".." +
                         std::to_string(base_domain + jobs - 1) +
                         ", past 232; expected a lower --domain");
      }
      if (real_time) {
        domain = std::to_string(base_domain + worker.value_or(0));
      } else if (args.Value("domain")) {
        domain = std::to_string(base_domain);
      }
      const std::filesystem::path database =
          !study.database.empty() ? study.database : run_config.database;
      out = args.Value("out").value_or((database.parent_path() / ("power-" + study.name)).string());
      pool_database =
          out / ("pool-" + std::to_string(pool) + "-seed" + std::to_string(options.seed) + ".db");
      CheckWritableFolder(out);
      // The first trial set up now: a word `haptel run` refuses is bad input, before anything runs.
      try {
        TrialSetup(pool_config, plan.front(), pool_database, domain, verbose, 0, !real_time);
      } catch (const UsageError& e) {
        if (real_time || std::string(e.what()).find("--simulated-time") == std::string::npos) throw;
        throw UsageError(
            "the trials run in simulated time (haptel run --simulated-time), which this build's "
            "`haptel run` does not have (" +
            std::string(e.what()) +
            "); --real-time runs them in "
            "real time");
      }
    });
    // A worker runs every `jobs`-th participant of the pool, in order.
    if (worker)
      return RunPoolShare(pool_config, plan, pool_database, domain, verbose, !real_time, *worker,
                          jobs, interrupted);

    // The pool's study is planned here, once; each worker process then opens
    // it again. Processes, not threads: a simulated-time trial puts its whole
    // process on its simulated clock.
    size_t done_before = 0;
    {
      auto recorder =
          cli::ReadInput([&] { return std::make_unique<record::Recorder>(pool_database); });
      StudyStore store = cli::ReadInput([&] { return StudyStore(*recorder, pool_config, plan); });
      done_before = store.Trials().size();
    }
    std::fprintf(
        stderr,
        "[power] %s: a pool of %d simulated participants (%d per order row, %d rows), %zu trials "
        "(%zu done), %s, %d at a time; database %s\n",
        study.name.c_str(), pool, pool / rows, rows, plan.size(), done_before,
        real_time ? "in real time" : "in simulated time", jobs, pool_database.c_str());
    const auto pool_started = std::chrono::steady_clock::now();
    std::vector<std::string> worker_words;
    for (int i = 0; i < argc; ++i)
      worker_words.push_back(argv[i]);  // "study", "power", FILE, options
    std::vector<std::unique_ptr<ChildProcess>> workers;
    for (int w = 0; w < jobs && static_cast<size_t>(w) < pool_config.participants.size(); ++w) {
      std::vector<std::string> words = worker_words;
      words.insert(words.end(), {"--worker", std::to_string(w)});
      workers.push_back(
          std::make_unique<ChildProcess>((ProgramDirectory() / "haptel").string(), words));
    }
    std::string worker_failures;
    bool stopping = false;
    for (size_t w = 0; w < workers.size(); ++w) {
      int code = ChildProcess::kStillRunning;
      while ((code = workers[w]->Wait(0.2)) == ChildProcess::kStillRunning) {
        // A signal to this process alone is passed on (a terminal's reaches
        // the workers too); each ends its trial, recorded as interrupted.
        if (interrupted.load() && !stopping) {
          stopping = true;
          for (auto& other : workers) {
            if (other->Alive()) kill(other->pid(), SIGTERM);
          }
        }
        // A worker that has not ended its trial in a while is ended.
        if (stopping && workers[w]->Alive()) workers[w]->Terminate(10.0);
      }
      if (code != 0) {
        worker_failures += (worker_failures.empty() ? "" : "; ") +
                           ("worker " + std::to_string(w) + " " + workers[w]->ExitDescription());
      }
    }
    const double pool_wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - pool_started).count();
    if (interrupted.load()) {
      std::fprintf(
          stderr,
          "[power] interrupted: the pool's trials so far are in %s; run the same command again "
          "to resume\n",
          pool_database.c_str());
      return cli::kExitFailed;
    }

    // The pool as data: each participant with every planned trial recorded.
    record::Recorder recorder(pool_database);
    const StudyStore store(recorder, pool_config, plan);
    const std::vector<TrialRow> rows_recorded = store.Trials();
    std::vector<PowerParticipant> pool_data;
    std::vector<std::string> left_out;
    const std::filesystem::path pool_csv = out / "pool.csv";
    std::ostringstream csv;
    csv << "participant,row,profile,position,condition,lap_time_s,completed,obstacles,run_id\n";
    for (size_t i = 0; i < pool_config.participants.size(); ++i) {
      const StudyParticipant& p = pool_config.participants[i];
      PowerParticipant data;
      data.id = p.id;
      data.row = static_cast<int>(i) % rows;
      size_t planned = 0;
      for (const PlannedTrial& t : plan) planned += t.participant == p.id;
      for (const TrialRow& t : rows_recorded) {
        if (t.participant != p.id) continue;
        const auto c = std::find_if(study.conditions.begin(), study.conditions.end(),
                                    [&](const StudyCondition& s) { return s.name == t.condition; });
        data.trials.push_back(
            {static_cast<int>(c - study.conditions.begin()), t.position, t.lap_time_s});
        csv << p.id << ',' << data.row << ',' << p.profile << ',' << t.position << ','
            << t.condition << ',' << Fixed(t.lap_time_s, 3) << ',' << (t.completed ? 1 : 0) << ','
            << t.obstacles << ',' << t.run_id << '\n';
      }
      if (data.trials.size() == planned) {
        pool_data.push_back(std::move(data));
      } else {
        left_out.push_back(p.id);
      }
    }
    if (!left_out.empty()) {
      std::string who;
      for (const std::string& id : left_out) who += (who.empty() ? "" : ", ") + id;
      std::fprintf(stderr, "[power] left out of the pool (trials not finished; %s): %s\n",
                   worker_failures.c_str(), who.c_str());
    }

    const auto analysis_started = std::chrono::steady_clock::now();
    std::fprintf(stderr,
                 "[power] the pool is done: %d simulations for each of %zu participant counts\n",
                 options.simulations, options.participant_counts.size());
    PowerResult power;
    options.stop = &interrupted;
    try {
      power = EstimatePower(pool_data, static_cast<int>(study.conditions.size()), rows, options);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(std::string("cannot estimate the power from the pool in ") +
                               pool_database.string() + ": " + e.what());
    }
    const double analysis_wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - analysis_started).count();
    if (power.stopped || interrupted.load()) {
      std::fprintf(
          stderr,
          "[power] interrupted during the analysis: no file written; the pool's trials are in %s, "
          "and the same command runs the analysis again\n",
          pool_database.c_str());
      return cli::kExitFailed;
    }

    // The table, the CSV and the curve, each whole or not at all.
    const std::filesystem::path power_csv = out / "power.csv";
    std::ostringstream table;
    table << "participants,simulations,friedman_power,friedman_ci_low,friedman_ci_high,lmm_power,"
             "lmm_ci_low,"
             "lmm_ci_high,friedman_not_analysed,lmm_not_analysed\n";
    for (const PowerPoint& p : power.points) {
      table << p.participants << ',' << p.simulations << ',' << Fixed(p.friedman_power, 4) << ','
            << Fixed(p.friedman_interval.low, 4) << ',' << Fixed(p.friedman_interval.high, 4) << ','
            << Fixed(p.lmm_power, 4) << ',' << Fixed(p.lmm_interval.low, 4) << ','
            << Fixed(p.lmm_interval.high, 4) << ',' << p.friedman_not_analysed << ','
            << p.lmm_not_analysed << '\n';
    }
    const std::filesystem::path png = out / "power.png";
    const std::filesystem::path png_part =
        out / "power.part.png";  // the encoder goes by the extension
    DrawPowerCurve(power,
                   "Power of " + study.name + " (alpha 0.05, 95 % CI; pool of " +
                       std::to_string(power.pool_participants) + ")",
                   png_part);
    WriteWhole(pool_csv, csv.str());
    WriteWhole(power_csv, table.str());
    std::error_code renamed;
    std::filesystem::rename(png_part, png, renamed);
    if (renamed)
      throw std::runtime_error("cannot write " + png.string() + ": " + renamed.message());

    std::printf(
        "power of study %s: %d simulated participants in the pool (%d order rows), %d simulations "
        "per "
        "count, alpha %s\n",
        study.name.c_str(), power.pool_participants, rows, options.simulations,
        Fixed(options.alpha, 2).c_str());
    std::printf("  %12s  %-24s  %-24s\n", "participants", "Friedman power (95% CI)",
                "mixed-model power (95% CI)");
    for (const PowerPoint& p : power.points) {
      const std::string f = Fixed(p.friedman_power, 2) + " (" + Fixed(p.friedman_interval.low, 2) +
                            "-" + Fixed(p.friedman_interval.high, 2) + ")";
      const std::string m = Fixed(p.lmm_power, 2) + " (" + Fixed(p.lmm_interval.low, 2) + "-" +
                            Fixed(p.lmm_interval.high, 2) + ")";
      std::printf("  %12d  %-24s  %-24s\n", p.participants, f.c_str(), m.c_str());
    }
    std::printf(
        "  (mixed model: log(lap time) ~ condition + position + (1 | participant), Satterthwaite's "
        "F test of "
        "condition; intervals Clopper-Pearson)\n");
    if (power.recommended_participants) {
      std::printf(
          "  recommended participants: %d (the smallest count whose mixed-model power reaches 80 "
          "%%)\n",
          *power.recommended_participants);
    } else {
      std::printf(
          "  recommended participants: none of these counts reaches 80 %% mixed-model power\n");
    }
    std::printf("  pool: %s s of trials, analysis %s s; files: %s, %s, %s\n",
                Fixed(pool_wall_s, 1).c_str(), Fixed(analysis_wall_s, 1).c_str(), power_csv.c_str(),
                png.c_str(), pool_csv.c_str());
    if (json) {
      const double wall_s =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
      std::string line = "{\"study\":" + JsonString(study.name) + ",\"power\":[";
      for (size_t i = 0; i < power.points.size(); ++i) {
        const PowerPoint& p = power.points[i];
        line += std::string(i > 0 ? "," : "") +
                "{\"participants\":" + std::to_string(p.participants) +
                ",\"friedman_power\":" + JsonNumber(p.friedman_power) + ",\"friedman_ci\":[" +
                JsonNumber(p.friedman_interval.low) + "," + JsonNumber(p.friedman_interval.high) +
                "],\"lmm_power\":" + JsonNumber(p.lmm_power) + ",\"lmm_ci\":[" +
                JsonNumber(p.lmm_interval.low) + "," + JsonNumber(p.lmm_interval.high) + "]}";
      }
      line += "],\"recommended_participants\":" +
              (power.recommended_participants ? std::to_string(*power.recommended_participants)
                                              : "null") +
              ",\"recommended_by\":\"lmm\",\"alpha\":" + JsonNumber(options.alpha) +
              ",\"pool_participants\":" + std::to_string(power.pool_participants) +
              ",\"pool_left_out\":" + std::to_string(left_out.size()) +
              ",\"rows\":" + std::to_string(rows) +
              ",\"simulations\":" + std::to_string(options.simulations) +
              ",\"simulated_time\":" + (real_time ? "false" : "true") +
              ",\"pool_wall_s\":" + JsonNumber(pool_wall_s) + ",\"wall_s\":" + JsonNumber(wall_s) +
              ",\"pool_database\":" + JsonString(pool_database.string()) +
              ",\"csv\":" + JsonString(power_csv.string()) +
              ",\"png\":" + JsonString(png.string()) + "}";
      std::printf("%s\n", line.c_str());
    }
    std::fflush(stdout);
    return left_out.empty() ? cli::kExitOk : cli::kExitFailed;
  });
}

}  // namespace haptel::study
