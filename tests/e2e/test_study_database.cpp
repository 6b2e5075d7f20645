// End to end: a study's database under what a lab does to it (issue 41).
//
// - Other processes open and close the study's file while the study holds
//   it (the sqlite3 tool, another `haptel run --database` on it): the
//   study's rows acknowledged after that survive a kill -9, and the file
//   stays intact. Closing a descriptor of the file anywhere in the study's
//   process dropped the process's locks, and the next process to close the
//   file deleted the WAL the study was still writing to.
// - A trial whose save fails (a full disk) ends the study saying the trial
//   was not saved, and the file its results are kept in says whose trial it
//   was.
//
// Behaviour only: the waits are generous bounds so a fault fails the test
// instead of hanging it.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "../study/console_client.hpp"
#include "child.hpp"
#include "file_size_limit.hpp"
#include "study_file.hpp"
#include "test_env.hpp"

using namespace haptel;
using haptel::test::Child;
namespace fs = std::filesystem;

namespace {

std::string Bin(const std::string& name) { return (test::BinDir() / name).string(); }

/// A read-only connection of the test's own, closed when it goes.
class Db {
 public:
  explicit Db(const fs::path& file) {
    if (sqlite3_open_v2(file.c_str(), &db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
      throw std::runtime_error("cannot open " + file.string() + ": " + sqlite3_errmsg(db_));
    }
    sqlite3_busy_timeout(db_, 10000);
  }
  ~Db() { sqlite3_close_v2(db_); }
  Db(const Db&) = delete;
  Db& operator=(const Db&) = delete;
  /// The first column of each row of `sql`, as text; a failing statement
  /// gives one row, its error (so a check on the rows names it).
  std::vector<std::string> Column(const std::string& sql) {
    sqlite3_stmt* stmt = nullptr;
    std::vector<std::string> rows;
    if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &stmt, nullptr) != SQLITE_OK) {
      return {std::string("error: ") + sqlite3_errmsg(db_)};
    }
    int rc;
    while ((rc = sqlite3_step(stmt)) == SQLITE_ROW) {
      const unsigned char* text = sqlite3_column_text(stmt, 0);
      rows.emplace_back(text != nullptr ? reinterpret_cast<const char*>(text) : "NULL");
    }
    if (rc != SQLITE_DONE) rows.push_back(std::string("error: ") + sqlite3_errmsg(db_));
    sqlite3_finalize(stmt);
    return rows;
  }

 private:
  sqlite3* db_ = nullptr;
};

/// `haptel run` in simulated time on `db`, to its end: the quickest real
/// writer of a run. Returns its JSON line.
std::string SimulatedRun(const fs::path& db, int domain) {
  Child run({Bin("haptel"), "run", "--config", "config/haptel.yaml", "--track",
             "config/tracks/test-short.yaml", "--interface", "gesture", "--view", "none",
             "--simulated-time", "--time-limit", "20", "--quiet", "--json", "--database",
             db.string(), "--domain", std::to_string(domain)});
  const int code = run.Wait(180.0);
  INFO("haptel run: exit " << code << "\n" << run.err());
  CHECK((code == 0 || code == 1));  // completed, or the time limit: recorded either way
  return run.LastLine();
}

}  // namespace

TEST_CASE(
    "a study's acknowledged rows survive other processes opening its database, and a kill -9") {
  const auto dir = test::ScratchDir("e2e-study-shared-db");
  const auto file = dir / "open.yaml";
  // A person study with no participants: they are added in the console, and
  // nothing else runs until a trial is started (none is).
  std::ofstream(file) << test::StudyFileHead("shared-db-e2e")
                      << "operators: person\n"
                         "conditions:\n"
                         "  - {name: first, interface: gesture}\n"
                         "  - {name: second, interface: gesture}\n"
                         "design: {order: fixed}\n"
                         "practice: false\n"
                         "trial_cap_s: 12\n";
  const auto db = dir / "shared.db";
  const int port = test::FreeLoopbackPort();
  Child study({Bin("haptel"), "study", "run", file.string(), "--database", db.string(), "--domain",
               std::to_string(test::UniqueDomain(61)), "--port", std::to_string(port)});
  test::ConsoleClient console("127.0.0.1", port);
  auto status = [&](const std::string& key) {
    const auto r = console.Get("/status.json");
    return r ? test::JsonField(r->body, key) : std::string();  // not serving yet
  };
  auto post = [&](const std::string& path, const httplib::Params& form) {
    const auto r = console.Post(path, form);
    return r ? r->status : 0;
  };
  REQUIRE(test::WaitFor(
      [&] {
        study.Pump();
        return status("waiting_for_participants") == "true" || !study.Alive();
      },
      60.0));
  INFO(study.err());
  // The study holds the file on two connections (its store and its console's).
  REQUIRE(post("/participants", {{"id", "P1"}}) == 303);

  // Another process reads the file and closes it: the sqlite3 tool.
  Child reader({"/usr/bin/sqlite3", db.string(), "SELECT COUNT(*) FROM study_participants"});
  REQUIRE(reader.Wait(60.0) == 0);
  CHECK(reader.LastLine() == "1");
  // The study's write-ahead log is still there: it is the study's to remove.
  CHECK(fs::exists(db.string() + "-wal"));
  CHECK(fs::exists(db.string() + "-shm"));

  // Another run saves into the same file, and closes it.
  const std::string first_run = SimulatedRun(db, test::UniqueDomain(62));
  CHECK(test::JsonField(first_run, "recorded") == "true");

  // More rows acknowledged by the study after the others have gone.
  REQUIRE(study.Alive());
  CHECK(post("/participants", {{"id", "P2"}}) == 303);
  CHECK(post("/notes",
             {{"participant", "P1"}, {"position", "0"}, {"text", "after the other run"}}) == 303);
  // And a second run writes while the study's last rows are still in its log.
  const std::string second_run = SimulatedRun(db, test::UniqueDomain(62));
  CHECK(test::JsonField(second_run, "recorded") == "true");

  // A power cut: no handler runs.
  REQUIRE(study.Alive());
  kill(study.pid(), SIGKILL);
  CHECK(study.Wait(30.0) == -SIGKILL);

  Db check(db);
  CHECK(check.Column("PRAGMA integrity_check") == std::vector<std::string>{"ok"});
  CHECK(check.Column("SELECT participant FROM study_participants ORDER BY participant") ==
        std::vector<std::string>{"P1", "P2"});
  CHECK(check.Column("SELECT text FROM study_notes") ==
        std::vector<std::string>{"after the other run"});
  CHECK(check.Column("SELECT id FROM runs ORDER BY id") ==
        std::vector<std::string>{test::JsonField(first_run, "run_id"),
                                 test::JsonField(second_run, "run_id")});
}
TEST_CASE(
    "a trial the database cannot take ends the study as not saved; its file says whose trial it "
    "was") {
  const auto dir = test::ScratchDir("e2e-study-full-disk");
  const auto file = dir / "full.yaml";
  std::ofstream(file) << test::StudyFileHead("full-disk-e2e")
                      << "operators: synthetic\n"
                         "conditions:\n"
                         "  - {name: first, interface: gesture}\n"
                         "  - {name: second, interface: gesture}\n"
                         "design: {order: fixed}\n"
                         "trial_cap_s: 10\n"
                         "profiles:\n"
                         "  plain: {steering_noise: 0.02, seed: 3}\n"
                         "participants:\n"
                         "  - {id: P7, profile: plain}\n";
  const auto db = dir / "study.db";
  const fs::path wal = db.string() + "-wal";
  // SIGXFSZ ignored here, and so in the study (a child keeps an ignored
  // signal ignored): its writes past the limit set below fail with EFBIG,
  // as on a full disk, instead of killing it. The limit itself stays.
  rlimit now{};
  REQUIRE(getrlimit(RLIMIT_FSIZE, &now) == 0);
  const test::FileSizeLimit inherited_by_the_study(now.rlim_cur);
  Child study({Bin("haptel"), "study", "run", file.string(), "--database", db.string(), "--domain",
               std::to_string(test::UniqueDomain(63)), "--verbose", "--json"});
  // Into the first trial's lap (the vehicle up and driving: every file of
  // the session's set-up written), then the disk is full: no file of the
  // study's may grow past the log's present end.
  REQUIRE(test::WaitFor(
      [&] {
        study.Pump();
        const auto at = study.err().find("trial 1/2");
        return (at != std::string::npos &&
                study.err().find("haptel-vehicle: info: vehicle", at) != std::string::npos) ||
               !study.Alive();
      },
      120.0));
  REQUIRE(study.Alive());
  const auto full_at = fs::file_size(wal);
  const rlimit full{full_at, now.rlim_max};
  REQUIRE(prlimit(study.pid(), RLIMIT_FSIZE, &full, nullptr) == 0);

  const int code = study.Wait(180.0);
  INFO("stdout:\n" << study.out() << "\nstderr:\n" << study.err());
  CHECK(code == 4);  // not recorded
  // The summary's stop line says what happened to the lap and to its save.
  const std::string out = study.out();
  CHECK(out.find("stopped: trial not saved") != std::string::npos);
  CHECK(out.find("participant P7, position 1, first") != std::string::npos);
  CHECK(out.find("the database failed") != std::string::npos);
  const std::string json = study.LastLine();
  CHECK(test::JsonField(json, "stopped").find("trial not saved") != std::string::npos);
  const fs::path unsaved = test::JsonField(json, "unsaved_file");
  CHECK(unsaved.parent_path() == dir);
  CHECK(out.find(unsaved.string()) != std::string::npos);

  // The kept run says whose trial it was.
  std::ifstream in(unsaved);
  const std::string kept((std::istreambuf_iterator<char>(in)), {});
  INFO("kept: " << kept.substr(0, 400));
  CHECK(kept.rfind("{\"trial\":{\"study\":\"full-disk-e2e\",\"participant\":\"P7\",\"position\":1,"
                   "\"condition\":"
                   "\"first\",\"repetition\":1",
                   0) == 0);
  CHECK(kept.find("\"path\":[{\"t_s\":") != std::string::npos);  // and the run itself, whole
  CHECK(kept.size() < full_at);                                  // written under the same limit

  // The file itself is intact, without the trial: resuming runs it again.
  Db check(db);
  CHECK(check.Column("PRAGMA integrity_check") == std::vector<std::string>{"ok"});
  CHECK(check.Column("SELECT COUNT(*) FROM study_trials") == std::vector<std::string>{"0"});
}
