// `haptel study power STUDY.yaml` below its command line
// (app/src/study_power_command.cpp): how many participants the study needs.
#include "haptel/study/study_power.hpp"

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
#include "haptel/core/child_process.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/json.hpp"
#include "haptel/mediator/run_setup.hpp"
#include "haptel/study/plan.hpp"
#include "haptel/study/power.hpp"
#include "haptel/study/power_pool.hpp"
#include "haptel/study/report.hpp"
#include "haptel/study/store.hpp"
#include "haptel/study/study_sessions.hpp"

namespace haptel::study {
namespace {

std::string Fixed(double value, int decimals) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  return buffer;
}

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

/// The pool's study as the options and the study file make it, checked
/// before any trial runs.
struct PowerPlan {
  StudyConfig study;
  StudyConfig pool_config;
  std::vector<PlannedTrial> plan;
  int rows = 1;  ///< the design's order rows
  int pool = 0;  ///< simulated participants
  std::string domain;
  std::filesystem::path out;
  std::filesystem::path pool_database;
};

PowerPlan PlanPower(const StudyPowerOptions& options) {
  PowerPlan p;
  p.study = LoadStudy(options.file);
  const StudyConfig& study = p.study;
  if (study.operators != "synthetic") {
    throw ConfigError(
        study.file.string() +
        ": key 'operators': expected synthetic for `haptel study power` (it simulates the "
        "participants with the file's driver profiles), got " +
        study.operators);
  }
  if (study.participants.empty()) {
    throw ConfigError(study.file.string() +
                      ": key 'participants': expected at least one simulated participant (their "
                      "profiles are the pool's)");
  }
  p.rows = BlockSize(study);
  for (const int n : options.power.participant_counts) {
    if (n % p.rows != 0) {
      throw UsageError("option --participants: expected multiples of " + std::to_string(p.rows) +
                       " (the rows of the study's " + ToString(study.order) +
                       " design: a balanced draw takes as many from each), got " +
                       std::to_string(n));
    }
  }
  p.pool = options.pool.value_or(8 * p.rows);
  if (p.pool % p.rows != 0) {
    throw UsageError("option --pool: expected a multiple of " + std::to_string(p.rows) +
                     " (the rows of the study's design), got " + std::to_string(p.pool));
  }
  p.pool_config = PowerPoolStudy(study, p.pool, p.rows, options.power.seed);
  p.plan = PlanTrials(p.pool_config);
  const RunConfig run_config = LoadRun(study.run);
  // In real time each worker's vehicles get a DDS domain of their own:
  // two vehicles of one name on one domain would answer each other's operator.
  const int jobs = options.jobs;
  const int base_domain = options.domain.value_or(run_config.link.domain_id);
  if (options.real_time && base_domain + jobs - 1 > 232) {
    throw UsageError("option --domain: the " + std::to_string(jobs) + " workers take domains " +
                     std::to_string(base_domain) + ".." + std::to_string(base_domain + jobs - 1) +
                     ", past 232; expected a lower --domain");
  }
  if (options.real_time) {
    p.domain = std::to_string(base_domain + options.worker.value_or(0));
  } else if (options.domain) {
    p.domain = std::to_string(base_domain);
  }
  const std::filesystem::path database =
      !study.database.empty() ? study.database : run_config.database;
  p.out = options.out.value_or(database.parent_path() / ("power-" + study.name));
  p.pool_database = p.out / ("pool-" + std::to_string(p.pool) + "-seed" +
                             std::to_string(options.power.seed) + ".db");
  CheckWritableFolder(p.out);
  // The first trial set up now: a word `haptel run` refuses is bad input, before anything runs.
  try {
    TrialSetup(p.pool_config, p.plan.front(), p.pool_database, p.domain, options.verbose, 0,
               !options.real_time);
  } catch (const UsageError& e) {
    if (options.real_time || std::string(e.what()).find("--simulated-time") == std::string::npos)
      throw;
    throw UsageError(
        "the trials run in simulated time (haptel run --simulated-time), which this build's "
        "`haptel run` does not have (" +
        std::string(e.what()) +
        "); --real-time runs them in "
        "real time");
  }
  return p;
}

/// Plans the pool's study in its database, once (each worker process then
/// opens it again); returns the trials done before.
size_t OpenPool(const PowerPlan& p) {
  auto recorder =
      cli::ReadInput([&] { return std::make_unique<record::Recorder>(p.pool_database); });
  const auto store = cli::ReadInput(
      [&] { return std::make_unique<StudyStore>(*recorder, p.pool_config, p.plan); });
  return store->Trials().size();
}

/// The workers, `jobs` processes (not threads: a simulated-time trial puts
/// its whole process on its simulated clock), each running every `jobs`-th
/// participant; waits for them all. Returns how the ones that failed ended
/// ("" when none did).
std::string RunWorkers(const StudyPowerOptions& options, const PowerPlan& p,
                       const std::atomic<bool>& interrupted) {
  std::vector<std::unique_ptr<ChildProcess>> workers;
  for (int w = 0; w < options.jobs && static_cast<size_t>(w) < p.pool_config.participants.size();
       ++w) {
    std::vector<std::string> words = options.words;
    words.insert(words.end(), {"--worker", std::to_string(w)});
    workers.push_back(
        std::make_unique<ChildProcess>((ProgramDirectory() / "haptel").string(), words));
  }
  std::string failures;
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
      failures += (failures.empty() ? "" : "; ") +
                  ("worker " + std::to_string(w) + " " + workers[w]->ExitDescription());
    }
  }
  return failures;
}

/// The pool as data: each participant with every planned trial recorded
/// (the others left out), and pool.csv's text.
struct PoolData {
  std::vector<PowerParticipant> participants;
  std::vector<std::string> left_out;
  std::string csv;
};

PoolData ReadPool(const PowerPlan& p) {
  record::Recorder recorder(p.pool_database);
  const StudyStore store(recorder, p.pool_config, p.plan);
  const std::vector<TrialRow> rows_recorded = store.Trials();
  PoolData pool;
  std::ostringstream csv;
  csv << "participant,row,profile,position,condition,lap_time_s,completed,obstacles,run_id\n";
  for (size_t i = 0; i < p.pool_config.participants.size(); ++i) {
    const StudyParticipant& participant = p.pool_config.participants[i];
    PowerParticipant data;
    data.id = participant.id;
    data.row = static_cast<int>(i) % p.rows;
    size_t planned = 0;
    for (const PlannedTrial& t : p.plan) planned += t.participant == participant.id;
    for (const TrialRow& t : rows_recorded) {
      if (t.participant != participant.id) continue;
      const auto c = std::find_if(p.study.conditions.begin(), p.study.conditions.end(),
                                  [&](const StudyCondition& s) { return s.name == t.condition; });
      data.trials.push_back(
          {static_cast<int>(c - p.study.conditions.begin()), t.position, t.lap_time_s});
      csv << participant.id << ',' << data.row << ',' << participant.profile << ',' << t.position
          << ',' << t.condition << ',' << Fixed(t.lap_time_s, 3) << ',' << (t.completed ? 1 : 0)
          << ',' << t.obstacles << ',' << t.run_id << '\n';
    }
    if (data.trials.size() == planned) {
      pool.participants.push_back(std::move(data));
    } else {
      pool.left_out.push_back(participant.id);
    }
  }
  pool.csv = csv.str();
  return pool;
}

/// power.csv's text: each count's power and intervals.
std::string PowerTable(const PowerResult& power) {
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
  return table.str();
}

/// The files the command writes, each whole or not at all.
struct PowerFiles {
  std::filesystem::path power_csv;
  std::filesystem::path png;
  std::filesystem::path pool_csv;
};

PowerFiles WritePowerFiles(const PowerPlan& p, const PowerResult& power, const PoolData& pool) {
  const PowerFiles files{p.out / "power.csv", p.out / "power.png", p.out / "pool.csv"};
  const std::filesystem::path png_part =
      p.out / "power.part.png";  // the encoder goes by the extension
  DrawPowerCurve(power,
                 "Power of " + p.study.name + " (alpha 0.05, 95 % CI; pool of " +
                     std::to_string(power.pool_participants) + ")",
                 png_part);
  WriteWhole(files.pool_csv, pool.csv);
  WriteWhole(files.power_csv, PowerTable(power));
  std::error_code renamed;
  std::filesystem::rename(png_part, files.png, renamed);
  if (renamed)
    throw std::runtime_error("cannot write " + files.png.string() + ": " + renamed.message());
  return files;
}

void PrintPower(const StudyPowerOptions& options, const PowerPlan& p, const PowerResult& power,
                const PowerFiles& files, double pool_wall_s, double analysis_wall_s) {
  std::printf(
      "power of study %s: %d simulated participants in the pool (%d order rows), %d simulations "
      "per "
      "count, alpha %s\n",
      p.study.name.c_str(), power.pool_participants, p.rows, options.power.simulations,
      Fixed(options.power.alpha, 2).c_str());
  std::printf("  %12s  %-24s  %-24s\n", "participants", "Friedman power (95% CI)",
              "mixed-model power (95% CI)");
  for (const PowerPoint& point : power.points) {
    const std::string f = Fixed(point.friedman_power, 2) + " (" +
                          Fixed(point.friedman_interval.low, 2) + "-" +
                          Fixed(point.friedman_interval.high, 2) + ")";
    const std::string m = Fixed(point.lmm_power, 2) + " (" + Fixed(point.lmm_interval.low, 2) +
                          "-" + Fixed(point.lmm_interval.high, 2) + ")";
    std::printf("  %12d  %-24s  %-24s\n", point.participants, f.c_str(), m.c_str());
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
              Fixed(pool_wall_s, 1).c_str(), Fixed(analysis_wall_s, 1).c_str(),
              files.power_csv.c_str(), files.png.c_str(), files.pool_csv.c_str());
}

/// `--json`'s line.
std::string PowerJson(const StudyPowerOptions& options, const PowerPlan& p,
                      const PowerResult& power, const PowerFiles& files, size_t left_out,
                      double pool_wall_s, double wall_s) {
  std::string line = "{\"study\":" + JsonString(p.study.name) + ",\"power\":[";
  for (size_t i = 0; i < power.points.size(); ++i) {
    const PowerPoint& point = power.points[i];
    line +=
        std::string(i > 0 ? "," : "") + "{\"participants\":" + std::to_string(point.participants) +
        ",\"friedman_power\":" + JsonNumber(point.friedman_power) + ",\"friedman_ci\":[" +
        JsonNumber(point.friedman_interval.low) + "," + JsonNumber(point.friedman_interval.high) +
        "],\"lmm_power\":" + JsonNumber(point.lmm_power) + ",\"lmm_ci\":[" +
        JsonNumber(point.lmm_interval.low) + "," + JsonNumber(point.lmm_interval.high) + "]}";
  }
  line +=
      "],\"recommended_participants\":" +
      (power.recommended_participants ? std::to_string(*power.recommended_participants) : "null") +
      ",\"recommended_by\":\"lmm\",\"alpha\":" + JsonNumber(options.power.alpha) +
      ",\"pool_participants\":" + std::to_string(power.pool_participants) +
      ",\"pool_left_out\":" + std::to_string(left_out) + ",\"rows\":" + std::to_string(p.rows) +
      ",\"simulations\":" + std::to_string(options.power.simulations) +
      ",\"simulated_time\":" + (options.real_time ? "false" : "true") +
      ",\"pool_wall_s\":" + JsonNumber(pool_wall_s) + ",\"wall_s\":" + JsonNumber(wall_s) +
      ",\"pool_database\":" + JsonString(p.pool_database.string()) +
      ",\"csv\":" + JsonString(files.power_csv.string()) +
      ",\"png\":" + JsonString(files.png.string()) + "}";
  return line;
}

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int RunStudyPower(const StudyPowerOptions& options, const std::atomic<bool>& interrupted) {
  const auto started = std::chrono::steady_clock::now();
  const PowerPlan p = cli::ReadInput([&] { return PlanPower(options); });
  // A worker runs every `jobs`-th participant of the pool, in order.
  if (options.worker) {
    return RunPoolShare(p.pool_config, p.plan, p.pool_database, p.domain, options.verbose,
                        !options.real_time, *options.worker, options.jobs, interrupted);
  }
  const size_t done_before = OpenPool(p);
  std::fprintf(
      stderr,
      "[power] %s: a pool of %d simulated participants (%d per order row, %d rows), %zu trials "
      "(%zu done), %s, %d at a time; database %s\n",
      p.study.name.c_str(), p.pool, p.pool / p.rows, p.rows, p.plan.size(), done_before,
      options.real_time ? "in real time" : "in simulated time", options.jobs,
      p.pool_database.c_str());
  const auto pool_started = std::chrono::steady_clock::now();
  const std::string worker_failures = RunWorkers(options, p, interrupted);
  const double pool_wall_s = SecondsSince(pool_started);
  if (interrupted.load()) {
    std::fprintf(stderr,
                 "[power] interrupted: the pool's trials so far are in %s; run the same command "
                 "again to resume\n",
                 p.pool_database.c_str());
    return cli::kExitFailed;
  }

  const PoolData pool = ReadPool(p);
  if (!pool.left_out.empty()) {
    std::string who;
    for (const std::string& id : pool.left_out) who += (who.empty() ? "" : ", ") + id;
    std::fprintf(stderr, "[power] left out of the pool (trials not finished; %s): %s\n",
                 worker_failures.c_str(), who.c_str());
  }

  const auto analysis_started = std::chrono::steady_clock::now();
  std::fprintf(stderr,
               "[power] the pool is done: %d simulations for each of %zu participant counts\n",
               options.power.simulations, options.power.participant_counts.size());
  PowerResult power;
  PowerOptions estimate = options.power;
  estimate.stop = &interrupted;
  try {
    power = EstimatePower(pool.participants, static_cast<int>(p.study.conditions.size()), p.rows,
                          estimate);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(std::string("cannot estimate the power from the pool in ") +
                             p.pool_database.string() + ": " + e.what());
  }
  const double analysis_wall_s = SecondsSince(analysis_started);
  if (power.stopped || interrupted.load()) {
    std::fprintf(
        stderr,
        "[power] interrupted during the analysis: no file written; the pool's trials are in %s, "
        "and the same command runs the analysis again\n",
        p.pool_database.c_str());
    return cli::kExitFailed;
  }

  const PowerFiles files = WritePowerFiles(p, power, pool);
  PrintPower(options, p, power, files, pool_wall_s, analysis_wall_s);
  if (options.json) {
    std::printf("%s\n", PowerJson(options, p, power, files, pool.left_out.size(), pool_wall_s,
                                  SecondsSince(started))
                            .c_str());
  }
  std::fflush(stdout);
  return pool.left_out.empty() ? cli::kExitOk : cli::kExitFailed;
}

}  // namespace haptel::study
