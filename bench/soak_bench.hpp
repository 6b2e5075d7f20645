#pragma once
/// @file `haptel bench soak`: the study database under concurrency (issue 41).
///
/// One SQLite file, shared as a lab shares `runs/haptel.db`:
/// - a person study with its console (`haptel study run --port`: two
///   connections in one process), to which this bench adds participants and
///   notes through real HTTP (form token from the console's page); each 303
///   is a row acknowledged;
/// - two concurrent `haptel run --simulated-time --database` loops, each run
///   started when the last ended; each JSON line with "recorded":true is a
///   run acknowledged (its id and the process that saved it);
/// - the sqlite3 tool reading the file every second (a process each time,
///   opening and closing the file);
/// - every 5-15 s (--kill-every MIN,MAX) a `kill -9` of one of them: the
///   study, one of the runs, or a reader caught at a random point of its
///   life; the first three kills take one of each kind. Then `PRAGMA
///   integrity_check` on a connection of the bench's own, and every row
///   acknowledged so far looked for; then the killed process is started
///   again (the study resumes, as `haptel study run` does on the same file).
/// At the end (--duration, default 600 s) every process is stopped, the
/// file checked once more, and every row acknowledged looked for.
///
/// Prints one line per kill and a table: kills by kind, integrity checks
/// run and passed, rows acknowledged and found (by kind). Writes
/// build/bench/soak.csv (one row per check); with --json the last stdout
/// line is {"duration_s":…,"kills":{"study":…,"run":…,"reader":…},
/// "integrity_checks":…,"integrity_passed":…,"rows_acknowledged":…,
/// "rows_found":…,"rows_lost":…,…}.
///
/// --smoke (smoke.hpp): 25 s, a kill every 3-5 s: still one of each kind,
/// each followed by its checks.
namespace haptel::bench {

/// `haptel bench soak [--duration S] [--kill-every MIN,MAX] [--seed N] [--port N]
/// [--domain D] [--smoke] [--json]`. Returns 0 when every check passed and
/// every acknowledged row was found (and each kind was killed at least
/// once), 1 otherwise, 2 for bad usage.
int BenchSoakMain(int argc, const char* const* argv);

}  // namespace haptel::bench
