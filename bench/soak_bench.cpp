#include "soak_bench.hpp"

#include <arpa/inet.h>
#include <httplib.h>
#include <netinet/in.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "haptel/config/paths.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/child_process.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/json.hpp"
#include "haptel/testing/loopback.hpp"
#include "smoke.hpp"

namespace haptel::bench {

namespace {

namespace fs = std::filesystem;

/// Debian's sqlite3 package (in HAPTEL_PACKAGES).
constexpr const char* kSqliteTool = "/usr/bin/sqlite3";
/// Bounds on waits (a hang, not a timing check).
constexpr double kStartBound_s = 120.0;
constexpr double kStopBound_s = 60.0;
/// How often the sqlite3 tool reads, and the console is written to.
constexpr double kReadEvery_s = 1.0;
constexpr double kPostEvery_s = 0.5;
/// A study that exits on its own this many times in a row ends the bench.
constexpr int kStudyFailuresAllowed = 3;

enum class Kind { kStudy, kRun, kReader };
constexpr const char* kKindNames[] = {"study", "run", "reader"};
const char* Name(Kind k) { return kKindNames[static_cast<int>(k)]; }

std::unique_ptr<ChildProcess> Start(const std::string& program,
                                    const std::vector<std::string>& words) {
  return std::make_unique<ChildProcess>(program, words, ChildProcess::Options{true});
}

/// Kills `child` with SIGKILL if it still runs; true when the signal ended it.
bool KillNine(ChildProcess& child) {
  if (!child.Alive()) return false;
  ::kill(child.pid(), SIGKILL);
  return child.Wait(kStopBound_s) == -SIGKILL;
}

/// What the processes acknowledged: each must be in the file at every check.
struct Acknowledged {
  std::mutex mutex;
  std::set<std::string> participants;  ///< a 303 to POST /participants
  std::set<std::string> notes;         ///< a 303 to POST /notes (their texts)
  std::map<int64_t, int64_t> runs;     ///< run id -> vehicle_pid, from "recorded":true
  size_t Total() {
    const std::lock_guard<std::mutex> lock(mutex);
    return participants.size() + notes.size() + runs.size();
  }
};

/// One look at the file: integrity_check, and how many of the rows
/// acknowledged so far it holds.
struct Check {
  double t_s = 0.0;
  std::string after;  ///< the kind killed, or "end"
  int pid = 0;
  std::string integrity;  ///< "ok", or what integrity_check (or opening) said
  size_t acknowledged = 0;
  size_t found = 0;
  std::string first_missing;
  bool ok() const { return integrity == "ok" && found == acknowledged; }
};

/// The first column of every row of `sql` on `db`; throws on an error.
std::vector<std::string> Column(sqlite3* db, const char* sql) {
  sqlite3_stmt* stmt = nullptr;
  if (sqlite3_prepare_v2(db, sql, -1, &stmt, nullptr) != SQLITE_OK) {
    const std::string e = sqlite3_errmsg(db);
    sqlite3_finalize(stmt);
    throw std::runtime_error(e);
  }
  std::vector<std::string> rows;
  int rc;
  while ((rc = sqlite3_step(stmt)) == SQLITE_ROW) {
    std::string row;
    for (int c = 0; c < sqlite3_column_count(stmt); ++c) {
      const unsigned char* text = sqlite3_column_text(stmt, c);
      if (c > 0) row.push_back('|');
      if (text != nullptr) row.append(reinterpret_cast<const char*>(text));
    }
    rows.push_back(row);
  }
  const std::string e = rc == SQLITE_DONE ? "" : sqlite3_errmsg(db);
  sqlite3_finalize(stmt);
  if (!e.empty()) throw std::runtime_error(e);
  return rows;
}

/// The file checked through SQLite (a connection of this process, opened
/// and closed for the check: SQLite's own, so it drops no one's locks).
Check CheckFile(const fs::path& db_file, Acknowledged& acked) {
  Check check;
  std::set<std::string> participants, notes;
  std::map<int64_t, int64_t> runs;
  {
    const std::lock_guard<std::mutex> lock(acked.mutex);
    participants = acked.participants;
    notes = acked.notes;
    runs = acked.runs;
  }
  check.acknowledged = participants.size() + notes.size() + runs.size();
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(db_file.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr) != SQLITE_OK) {
    check.integrity = std::string("cannot open: ") + sqlite3_errmsg(db);
    sqlite3_close_v2(db);
    return check;
  }
  sqlite3_busy_timeout(db, 30000);
  try {
    const std::vector<std::string> verdict = Column(db, "PRAGMA integrity_check");
    check.integrity = verdict.size() == 1
                          ? verdict[0]
                          : std::to_string(verdict.size()) + " faults, first: " + verdict[0];
    // One snapshot for the three tables.
    Column(db, "BEGIN");
    std::set<std::string> in_file;
    for (const std::string& p : Column(db, "SELECT participant FROM study_participants"))
      in_file.insert("p:" + p);
    for (const std::string& n : Column(db, "SELECT text FROM study_notes"))
      in_file.insert("n:" + n);
    for (const std::string& r : Column(db, "SELECT id, vehicle_pid FROM runs"))
      in_file.insert("r:" + r);
    Column(db, "COMMIT");
    auto look = [&](const std::string& key) {
      if (in_file.count(key) != 0) {
        ++check.found;
      } else if (check.first_missing.empty()) {
        check.first_missing = key;
      }
    };
    for (const std::string& p : participants) look("p:" + p);
    for (const std::string& n : notes) look("n:" + n);
    for (const auto& [id, pid] : runs) look("r:" + std::to_string(id) + "|" + std::to_string(pid));
  } catch (const std::exception& e) {
    if (check.integrity.empty()) check.integrity = e.what();
    if (check.first_missing.empty())
      check.first_missing = std::string("(cannot read: ") + e.what() + ")";
  }
  sqlite3_close_v2(db);
  return check;
}

/// The experimenter at the console: a participant added or a note taken
/// every kPostEvery_s, over real HTTP with the console's form token (read
/// again from its page after the study restarts). Each 303 is acknowledged.
class ConsoleDriver {
 public:
  ConsoleDriver(int port, Acknowledged& acked, uint32_t seed)
      : port_(port), acked_(acked), random_(seed) {
    thread_ = std::thread([this] { Loop(); });
  }
  ~ConsoleDriver() { Stop(); }
  void Stop() {
    stop_.store(true);
    if (thread_.joinable()) thread_.join();
  }
  int posts() const { return posts_.load(); }
  int acknowledged() const { return acknowledged_.load(); }
  /// Answers other than 303 (the study starting, killed mid-request...).
  int unanswered() const { return posts_.load() - acknowledged_.load(); }

 private:
  void Loop() {
    int n = 0;
    while (!stop_.load()) {
      std::this_thread::sleep_for(std::chrono::duration<double>(kPostEvery_s));
      httplib::Client client("127.0.0.1", port_);
      client.set_connection_timeout(2, 0);
      client.set_read_timeout(20, 0);
      if (token_.empty()) {
        const auto page = client.Get("/login");
        static const std::regex kToken("name=\"csrf\" value=\"([0-9a-f]+)\"");
        std::smatch match;
        if (page && std::regex_search(page->body, match, kToken)) token_ = match[1].str();
        if (token_.empty()) continue;  // not serving (yet)
      }
      std::string participant;
      {
        const std::lock_guard<std::mutex> lock(acked_.mutex);
        if (!acked_.participants.empty() && n % 2 == 1) {
          auto it = acked_.participants.begin();
          std::advance(it, std::uniform_int_distribution<size_t>(
                               0, acked_.participants.size() - 1)(random_));
          participant = *it;
        }
      }
      ++n;
      ++posts_;
      char text[64];
      httplib::Result r =
          participant.empty()
              ? (std::snprintf(text, sizeof text, "S%05d", n),
                 client.Post("/participants", httplib::Params{{"id", text}, {"csrf", token_}}))
              : (std::snprintf(text, sizeof text, "soak note %d", n),
                 client.Post("/notes", httplib::Params{{"participant", participant},
                                                       {"position", "0"},
                                                       {"text", text},
                                                       {"csrf", token_}}));
      if (r && r->status == 303) {
        ++acknowledged_;
        const std::lock_guard<std::mutex> lock(acked_.mutex);
        (participant.empty() ? acked_.participants : acked_.notes).insert(text);
      } else if (!r || r->status == 403) {
        token_.clear();  // a restarted study has a token of its own
      }
    }
  }

  const int port_;
  Acknowledged& acked_;
  std::mt19937 random_;
  std::string token_;
  std::atomic<bool> stop_{false};
  std::atomic<int> posts_{0};
  std::atomic<int> acknowledged_{0};
  std::thread thread_;
};

/// The last `lines` lines of `text` (all of it when it has fewer).
std::string LastLines(const std::string& text, size_t lines) {
  size_t end = text.size();
  while (end > 0 && text[end - 1] == '\n') --end;
  size_t start = end;
  for (size_t n = 0; n < lines && start > 0; ++n) {
    const size_t newline = text.rfind('\n', start - 1);
    start = newline == std::string::npos ? 0 : newline;
  }
  if (start > 0) ++start;  // past the newline
  return text.substr(start, end - start);
}

struct KindStats {
  int kills = 0;
  int restarts = 0;
};

}  // namespace

int BenchSoakMain(int argc, const char* const* argv) {
  bool json = false, smoke = false;
  double duration_s = 600.0, kill_min_s = 5.0, kill_max_s = 15.0;
  uint32_t seed = 1;
  int port = 0;
  int domain = 150 + static_cast<int>(getpid() % 30);
  try {
    const Args args(argc, argv, {"duration", "kill-every", "seed", "port", "domain"},
                    {"json", kSmokeFlag});
    json = args.Flag("json");
    smoke = args.Flag(kSmokeFlag);
    if (smoke) {
      duration_s = 25.0;
      kill_min_s = 3.0;
      kill_max_s = 5.0;
    }
    duration_s = args.Number("duration", 5.0, 7 * 86400.0).value_or(duration_s);
    if (const auto every = args.Value("kill-every")) {
      const std::vector<std::string> bounds = SplitList(*every);
      try {
        if (bounds.size() != 2) throw std::invalid_argument(*every);
        kill_min_s = std::stod(bounds[0]);
        kill_max_s = std::stod(bounds[1]);
      } catch (const std::exception&) {
        throw UsageError("option --kill-every: expected MIN,MAX seconds, got '" + *every + "'");
      }
      if (!(kill_min_s >= 0.5 && kill_max_s >= kill_min_s)) {
        throw UsageError("option --kill-every: expected 0.5 <= MIN <= MAX, got '" + *every + "'");
      }
    }
    seed = static_cast<uint32_t>(args.Int("seed", 0, 1 << 30).value_or(1));
    port = args.Int("port", 1024, 65535).value_or(testing::FreeLoopbackPort());
    domain = args.Int("domain", 0, 232).value_or(domain);
    if (!fs::exists(kSqliteTool)) {
      throw UsageError(std::string("the sqlite3 tool is not at ") + kSqliteTool +
                       " (Debian's package sqlite3; scripts/install-deps installs it)");
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel bench soak: %s\n", e.what());
    return 2;
  }

  const fs::path out_dir = OutputDir(smoke);
  const fs::path dir = out_dir / "soak";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path db = dir / "soak.db";
  const fs::path study_file = dir / "soak-study.yaml";
  std::ofstream(study_file)
      << "# written by haptel bench soak: a person study, its participants added in the "
         "console\nname: soak\nrun: "
      << ShippedFile("config/haptel.yaml").string()
      << "\ntrack: " << ShippedFile("config/tracks/test-short.yaml").string()
      << "\noperators: person\nconditions:\n  - {name: first, interface: gesture}\n"
         "  - {name: second, interface: gesture}\n"
         "design: {order: fixed}\npractice: false\ntrial_cap_s: 12\n";
  const std::string haptel = (ProgramDirectory() / "haptel").string();
  const std::vector<std::string> study_words = {"study",
                                                "run",
                                                study_file.string(),
                                                "--database",
                                                db.string(),
                                                "--port",
                                                std::to_string(port),
                                                "--domain",
                                                std::to_string(domain)};
  auto run_words = [&](int which) {
    return std::vector<std::string>{"run",
                                    "--config",
                                    ShippedFile("config/haptel.yaml").string(),
                                    "--track",
                                    ShippedFile("config/tracks/test-short.yaml").string(),
                                    "--interface",
                                    "gesture",
                                    "--view",
                                    "none",
                                    "--simulated-time",
                                    "--time-limit",
                                    "30",
                                    "--quiet",
                                    "--json",
                                    "--database",
                                    db.string(),
                                    "--domain",
                                    std::to_string(domain + 1 + which)};
  };

  PrintSmokeNote("soak", smoke, "%.0f s, a kill every %.0f-%.0f s", duration_s, kill_min_s,
                 kill_max_s);
  std::printf(
      "haptel bench soak: %.0f s on %s: a person study with its console (participants and notes "
      "every "
      "%.1f s), two `haptel run --simulated-time` loops, the sqlite3 tool reading every %.0f s; a "
      "kill -9 "
      "every %.0f-%.0f s (seed %u)\n\n",
      duration_s, db.c_str(), kPostEvery_s, kReadEvery_s, kill_min_s, kill_max_s, seed);
  std::fflush(stdout);

  Acknowledged acked;
  std::map<Kind, KindStats> stats;
  std::vector<Check> checks;
  std::vector<std::string>
      failures;  ///< what went wrong beyond a check (a process refusing the file...)
  int runs_recorded = 0, runs_not_saved = 0, runs_refused = 0, runs_unfinished = 0;
  std::string not_saved_why;
  int reads = 0, reads_failed = 0, study_starts = 0, study_resumes = 0;
  std::string read_error;
  const int64_t start_ns = MonotonicNs();
  auto now_s = [&] { return NsToS(MonotonicNs() - start_ns); };

  // The study first: the file, its tables and the console.
  std::unique_ptr<ChildProcess> study;
  int study_failures = 0;
  bool study_killed = false;
  auto start_study = [&] {
    study = Start(haptel, study_words);
    ++study_starts;
    const int64_t t0 = MonotonicNs();
    while (NsToS(MonotonicNs() - t0) < kStartBound_s) {
      study->Pump();
      if (study->err().find("[study] soak: ") != std::string::npos || !study->Alive()) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    if (study_starts > 1 && study->err().find("[study] soak: resuming") != std::string::npos)
      ++study_resumes;
  };
  start_study();
  if (!study->Alive()) {
    std::fprintf(stderr, "haptel bench soak: the study did not start (%s):\n%s\n",
                 study->ExitDescription().c_str(), study->err().c_str());
    return 1;
  }
  ConsoleDriver console(port, acked, seed);

  std::unique_ptr<ChildProcess> runners[2];
  auto collect_run = [&](ChildProcess& run) {
    run.Pump();
    const std::string line = run.LastLine();
    if (JsonFieldOf(line, "recorded") == "true") {
      ++runs_recorded;
      const std::lock_guard<std::mutex> lock(acked.mutex);
      acked.runs[std::stoll(JsonFieldOf(line, "run_id"))] =
          std::stoll(JsonFieldOf(line, "vehicle_pid"));
      return;
    }
    if (run.ExitDescription().find("signal 9") != std::string::npos) return;  // killed here
    if (JsonFieldOf(line, "recorded") == "false") {
      // Kept in a file beside the database (e.g. busy past the save's time-out).
      ++runs_not_saved;
      if (not_saved_why.empty()) not_saved_why = LastLines(run.err(), 2);
      return;
    }
    if (run.ExitDescription() == "exited with code 2") {
      // Refused before it ran: a damaged file is a loss to report.
      ++runs_refused;
      const std::string why = LastLines(run.err(), 2);
      if (failures.size() < 20) failures.push_back("a run refused the file: " + why);
      return;
    }
    ++runs_unfinished;  // stopped before its lap was over (the bench's end)
  };
  std::unique_ptr<ChildProcess> reader;
  double next_read_s = 0.0;
  auto collect_read = [&](ChildProcess& r) {
    r.Pump();
    if (r.ExitDescription().find("signal 9") != std::string::npos) return;
    ++reads;
    if (r.ExitDescription() != "exited with code 0") {
      ++reads_failed;
      if (read_error.empty()) read_error = r.err();
      if (r.err().find("malformed") != std::string::npos && failures.size() < 20) {
        failures.push_back("the sqlite3 tool: " + r.err());
      }
    }
  };

  std::mt19937 random(seed);
  std::uniform_real_distribution<double> interval(kill_min_s, kill_max_s);
  double next_kill_s = interval(random);
  int kill_number = 0;
  std::ofstream csv(out_dir / "soak.csv");
  csv << "t_s,after,pid,integrity,rows_acknowledged,rows_found,first_missing\n";
  auto record_check = [&](const std::string& after, int pid) {
    Check c = CheckFile(db, acked);
    // Each run draws its picture (some 140 kB, thousands of runs): not what is measured here.
    std::error_code ignored;
    fs::remove_all(dir / "pictures", ignored);
    c.t_s = now_s();
    c.after = after;
    c.pid = pid;
    csv << JsonNumber(c.t_s) << "," << c.after << "," << c.pid << "," << JsonString(c.integrity)
        << "," << c.acknowledged << "," << c.found << "," << JsonString(c.first_missing) << "\n";
    csv.flush();
    const std::string what =
        pid != 0 ? "kill -9 " + after + " (pid " + std::to_string(pid) + ")" : after;
    std::printf("  %7.1f s  %-26s  integrity_check %-4s  rows %zu of %zu acknowledged%s%s\n", c.t_s,
                what.c_str(), c.integrity == "ok" ? "ok" : "FAIL", c.found, c.acknowledged,
                c.integrity == "ok" ? "" : ("; " + c.integrity).c_str(),
                c.first_missing.empty() ? "" : ("; missing " + c.first_missing).c_str());
    std::fflush(stdout);
    checks.push_back(c);
  };

  bool gave_up = false;
  while (now_s() < duration_s && !gave_up) {
    // The study, resumed when it ended (killed here, or on its own).
    study->Pump();
    if (!study->Alive()) {
      if (!study_killed) {
        ++study_failures;
        if (failures.size() < 20) {
          failures.push_back("the study ended on its own (" + study->ExitDescription() +
                             "): " + LastLines(study->err(), 3));
        }
        if (study_failures >= kStudyFailuresAllowed) {
          gave_up = true;
          break;
        }
      } else {
        study_failures = 0;
      }
      study_killed = false;
      ++stats[Kind::kStudy].restarts;
      start_study();
    }
    // Two runs, each started again when it ends.
    for (int i = 0; i < 2; ++i) {
      if (runners[i] && runners[i]->Alive()) {
        runners[i]->Pump();
        continue;
      }
      if (runners[i]) {
        collect_run(*runners[i]);
        ++stats[Kind::kRun].restarts;
      }
      runners[i] = Start(haptel, run_words(i));
    }
    // The sqlite3 tool, every second.
    if (reader && !reader->Alive()) {
      collect_read(*reader);
      reader.reset();
    }
    if (!reader && now_s() >= next_read_s) {
      reader = Start(kSqliteTool,
                     {db.string(), "SELECT COUNT(*) FROM runs; SELECT COUNT(*) FROM study_notes;"});
      next_read_s = now_s() + kReadEvery_s;
    }

    if (now_s() >= next_kill_s) {
      // The first three kills take one of each kind; then any, at random.
      const Kind kind = kill_number < 3
                            ? static_cast<Kind>(kill_number)
                            : static_cast<Kind>(std::uniform_int_distribution<int>(0, 2)(random));
      int pid = 0;
      bool killed = false;
      if (kind == Kind::kStudy) {
        pid = study->pid();
        killed = KillNine(*study);
        study_killed = killed;
      } else if (kind == Kind::kRun) {
        ChildProcess& run = *runners[std::uniform_int_distribution<int>(0, 1)(random)];
        pid = run.pid();
        killed = KillNine(run);  // one that had just ended is collected and started again above
      } else {
        // A reader caught at a random point of its life: starting, reading, closing.
        for (int attempt = 0; attempt < 50 && !killed; ++attempt) {
          auto victim = Start(kSqliteTool, {db.string(),
                                            "SELECT COUNT(*) FROM runs; SELECT COUNT(*) FROM "
                                            "study_participants;"});
          std::this_thread::sleep_for(std::chrono::microseconds(
              std::uniform_int_distribution<int>(0, attempt < 10 ? 20000 : 2000)(random)));
          pid = victim->pid();
          killed = KillNine(*victim);
          if (!killed) collect_read(*victim);
        }
      }
      if (killed) {
        ++stats[kind].kills;
        ++kill_number;
        record_check(Name(kind), pid);
      }
      next_kill_s = now_s() + interval(random);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }

  // The end: the console's last post answered, every process stopped
  // (the runs save what they drove), the file looked at once more.
  console.Stop();
  for (auto& run : runners) {
    if (!run) continue;
    run->Terminate(kStopBound_s);
    collect_run(*run);
  }
  if (reader) {
    reader->Wait(kStopBound_s);
    collect_read(*reader);
  }
  study->Terminate(kStopBound_s);
  record_check("end: every process stopped", 0);
  const Check& last = checks.back();
  csv.close();

  int passed = 0;
  for (const Check& c : checks) passed += c.integrity == "ok" ? 1 : 0;
  const size_t lost = last.acknowledged - last.found;
  int checks_short = 0;  ///< checks that missed a row acknowledged before them
  for (const Check& c : checks) checks_short += c.found < c.acknowledged ? 1 : 0;
  size_t participants, notes, runs;
  {
    const std::lock_guard<std::mutex> lock(acked.mutex);
    participants = acked.participants.size();
    notes = acked.notes.size();
    runs = acked.runs.size();
  }
  stats[Kind::kReader].restarts = reads;  // each read is a process of its own
  bool each_kind = true;
  for (const Kind k : {Kind::kStudy, Kind::kRun, Kind::kReader})
    each_kind = each_kind && stats[k].kills > 0;
  const bool ok = !gave_up && passed == static_cast<int>(checks.size()) && lost == 0 &&
                  checks_short == 0 && runs_refused == 0 && each_kind && failures.empty();

  std::printf("\n  kind     kills  started again\n");
  for (const Kind k : {Kind::kStudy, Kind::kRun, Kind::kReader}) {
    std::printf("  %-7s  %5d  %13d\n", Name(k), stats[k].kills, stats[k].restarts);
  }
  std::printf(
      "\n  study: %d starts, %d resumed on the same file; console: %d posts, %d acknowledged "
      "(303)\n",
      study_starts, study_resumes, console.posts(), console.acknowledged());
  std::printf(
      "  runs: %d recorded, %d not saved (kept in a file)%s%s, %d refused the file, %d stopped "
      "unfinished at "
      "the end\n",
      runs_recorded, runs_not_saved,
      not_saved_why.empty() ? "" : ", first: ", LastLines(not_saved_why, 1).c_str(), runs_refused,
      runs_unfinished);
  std::printf("  sqlite3 reads: %d, %d failed%s%s\n", reads, reads_failed,
              read_error.empty() ? "" : ", first: ",
              read_error.empty() ? "" : LastLines(read_error, 1).c_str());
  std::printf("  integrity checks: %zu run, %d passed (after every kill and at the end)\n",
              checks.size(), passed);
  std::printf(
      "  rows acknowledged: %zu (participants %zu, notes %zu, runs %zu); found at the end: %zu; "
      "lost: %zu\n",
      last.acknowledged, participants, notes, runs, last.found, lost);
  if (checks_short > 0)
    std::printf("  FAILURE: %d checks missed rows acknowledged before them\n", checks_short);
  for (const std::string& f : failures) std::printf("  FAILURE: %s\n", f.c_str());
  if (gave_up)
    std::printf("  FAILURE: the study ended on its own %d times in a row: bench stopped\n",
                study_failures);
  if (!each_kind)
    std::printf("  FAILURE: not every kind of process was killed (a longer --duration?)\n");
  std::printf("  verdict: %s\n",
              ok ? "nothing lost, every check passed" : "LOSS OR DAMAGE (see above)");
  std::printf("\n  wrote %s\n", (out_dir / "soak.csv").c_str());

  if (json) {
    std::ostringstream o;
    o << "{\"duration_s\":" << JsonNumber(now_s())
      << ",\"kills\":{\"study\":" << stats[Kind::kStudy].kills
      << ",\"run\":" << stats[Kind::kRun].kills << ",\"reader\":" << stats[Kind::kReader].kills
      << "},\"kills_total\":" << kill_number << ",\"study_starts\":" << study_starts
      << ",\"study_resumes\":" << study_resumes << ",\"integrity_checks\":" << checks.size()
      << ",\"integrity_passed\":" << passed << ",\"rows_acknowledged\":" << last.acknowledged
      << ",\"rows_acknowledged_by_kind\":{\"participants\":" << participants
      << ",\"notes\":" << notes << ",\"runs\":" << runs << "},\"rows_found\":" << last.found
      << ",\"rows_lost\":" << lost << ",\"checks_missing_rows\":" << checks_short
      << ",\"console_posts\":" << console.posts() << ",\"runs_recorded\":" << runs_recorded
      << ",\"runs_not_saved\":" << runs_not_saved << ",\"runs_unfinished\":" << runs_unfinished
      << ",\"runs_refused\":" << runs_refused << ",\"reads\":" << reads
      << ",\"reads_failed\":" << reads_failed << ",\"failures\":" << failures.size()
      << ",\"ok\":" << (ok ? "true" : "false") << "}";
    std::printf("%s\n", JsonLine(o.str(), smoke).c_str());
  }
  return ok ? 0 : 1;
}

}  // namespace haptel::bench
