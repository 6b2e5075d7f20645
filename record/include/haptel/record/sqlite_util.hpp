#pragma once
/// @file Small RAII helpers over SQLite's C API, shared by the run recorder
/// and the study store: handles, prepared statements, transactions that roll
/// back unless committed, ordered binding and reading, and one-line errors
/// that name the database file ("database FILE: what: SQLite's message").
#include <sqlite3.h>

#include <cstdint>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>

namespace haptel::sql {

struct DbCloser {
  void operator()(sqlite3* db) const noexcept { sqlite3_close_v2(db); }
};
using DbHandle = std::unique_ptr<sqlite3, DbCloser>;

struct StmtFinalizer {
  void operator()(sqlite3_stmt* stmt) const noexcept { sqlite3_finalize(stmt); }
};
using Stmt = std::unique_ptr<sqlite3_stmt, StmtFinalizer>;

/// Throws "database FILE: what" (one line).
[[noreturn]] inline void FailWith(const std::filesystem::path& file, std::string_view what) {
  throw std::runtime_error("database " + file.string() + ": " + std::string(what));
}

/// Throws naming the database file, what was being done, and SQLite's message
/// (with what a lock means: another connection holds the file).
[[noreturn]] inline void Fail(const std::filesystem::path& file, sqlite3* db,
                              std::string_view what) {
  std::string message(what);
  if (db != nullptr) {
    const int code = sqlite3_extended_errcode(db) & 0xff;
    if (code == SQLITE_NOTADB)
      FailWith(file, "is not a SQLite database (corrupt, or another kind of file)");
    message += ": " + std::string(sqlite3_errmsg(db));
    if (code == SQLITE_BUSY) message += " (another program holds it; gave up waiting)";
  }
  FailWith(file, message);
}

inline void Exec(const std::filesystem::path& file, sqlite3* db, const char* sql,
                 std::string_view what) {
  if (sqlite3_exec(db, sql, nullptr, nullptr, nullptr) != SQLITE_OK) Fail(file, db, what);
}

inline Stmt Prepare(const std::filesystem::path& file, sqlite3* db, const char* sql,
                    std::string_view what) {
  sqlite3_stmt* raw = nullptr;
  if (sqlite3_prepare_v2(db, sql, -1, &raw, nullptr) != SQLITE_OK) {
    sqlite3_finalize(raw);
    Fail(file, db, what);
  }
  return Stmt(raw);
}

/// Rolls back on scope exit unless committed. Works for read and write
/// transactions alike.
class Transaction {
 public:
  Transaction(const std::filesystem::path& file, sqlite3* db, const char* begin_sql)
      : file_(file), db_(db) {
    Exec(file_, db_, begin_sql, "cannot begin transaction");
  }
  ~Transaction() {
    if (!committed_ && sqlite3_get_autocommit(db_) == 0) {
      sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    }
  }
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;

  void Commit() {
    Exec(file_, db_, "COMMIT", "cannot commit transaction");
    committed_ = true;
  }

 private:
  const std::filesystem::path& file_;
  sqlite3* db_;
  bool committed_ = false;
};

/// Binds parameters 1, 2, ... in order, failing with the file name on error.
class Binder {
 public:
  Binder(const std::filesystem::path& file, sqlite3* db, sqlite3_stmt* stmt)
      : file_(file), db_(db), stmt_(stmt) {}

  Binder& Int(int64_t value) { return Check(sqlite3_bind_int64(stmt_, ++index_, value)); }
  Binder& Real(double value) { return Check(sqlite3_bind_double(stmt_, ++index_, value)); }
  /// `value`, or NULL when there is none to store (`present` false).
  Binder& RealOrNull(double value, bool present) {
    return present ? Real(value) : Check(sqlite3_bind_null(stmt_, ++index_));
  }
  /// `value`, or NULL when there is none to store (`present` false).
  Binder& IntOrNull(int64_t value, bool present) {
    return present ? Int(value) : Check(sqlite3_bind_null(stmt_, ++index_));
  }
  Binder& Text(const std::string& value) {
    return Check(sqlite3_bind_text64(stmt_, ++index_, value.data(), value.size(), SQLITE_TRANSIENT,
                                     SQLITE_UTF8));
  }

 private:
  Binder& Check(int rc) {
    if (rc != SQLITE_OK) Fail(file_, db_, "cannot bind parameter " + std::to_string(index_));
    return *this;
  }

  const std::filesystem::path& file_;
  sqlite3* db_;
  sqlite3_stmt* stmt_;
  int index_ = 0;
};

/// Reads columns 0, 1, ... in order.
class Reader {
 public:
  explicit Reader(sqlite3_stmt* stmt) : stmt_(stmt) {}

  int64_t Int() { return sqlite3_column_int64(stmt_, index_++); }
  bool Bool() { return Int() != 0; }
  /// The column's integer, or `null_value` for NULL.
  int64_t IntOr(int64_t null_value) {
    const int i = index_++;
    return sqlite3_column_type(stmt_, i) == SQLITE_NULL ? null_value
                                                        : sqlite3_column_int64(stmt_, i);
  }
  double Real() {
    const int i = index_++;
    if (sqlite3_column_type(stmt_, i) == SQLITE_NULL) {
      return std::numeric_limits<double>::quiet_NaN();
    }
    return sqlite3_column_double(stmt_, i);
  }
  std::string Text() {
    const int i = index_++;
    const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(stmt_, i));
    const int bytes = sqlite3_column_bytes(stmt_, i);
    return text == nullptr ? std::string() : std::string(text, static_cast<size_t>(bytes));
  }

 private:
  sqlite3_stmt* stmt_;
  int index_ = 0;
};

/// Steps a statement that returns no rows.
inline void StepDone(const std::filesystem::path& file, sqlite3* db, sqlite3_stmt* stmt,
                     std::string_view what) {
  if (sqlite3_step(stmt) != SQLITE_DONE) Fail(file, db, what);
}

/// ISO-8601 UTC with milliseconds, e.g. "2024-05-01T12:34:56.789Z".
inline std::string IsoUtc(int64_t wall_ns) {
  constexpr int64_t kNsPerS = 1'000'000'000;
  int64_t seconds = wall_ns / kNsPerS;
  int64_t remainder_ns = wall_ns % kNsPerS;
  if (remainder_ns < 0) {  // floor, so times before 1970 format correctly
    remainder_ns += kNsPerS;
    --seconds;
  }
  const auto t = static_cast<std::time_t>(seconds);
  std::tm tm{};
  if (gmtime_r(&t, &tm) == nullptr) return std::string();
  char buffer[64];
  const int n = std::snprintf(buffer, sizeof buffer, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ",
                              tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min,
                              tm.tm_sec, static_cast<int>(remainder_ns / 1'000'000));
  if (n < 0 || static_cast<size_t>(n) >= sizeof buffer) return std::string();
  return std::string(buffer, static_cast<size_t>(n));
}

}  // namespace haptel::sql
