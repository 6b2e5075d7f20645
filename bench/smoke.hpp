#pragma once
/// @file `--smoke`: every benchmark's short run, which the test suite makes
/// (tests/bench/test_bench_smoke.cpp) so that no benchmark can rot unnoticed.
///
/// A smoke run takes the same code path and writes the same outputs (table,
/// CSV, PNG, the JSON line) as the full run, on fewer points, shorter
/// durations and fewer inputs: seconds of wall time. What the full run
/// measures and its defaults do not change. Options given beside --smoke
/// still apply. Its figures are no measurements, and they say so: the table
/// begins with a SMOKE line, the JSON line with "smoke":true, and the files go
/// to build/bench/smoke/, never over a real run's.
#include <filesystem>
#include <string>

namespace haptel::bench {

/// The flag's name, as Args takes it.
inline constexpr const char* kSmokeFlag = "smoke";

/// Where a run writes its files: BenchDir() (build/bench/), or build/bench/smoke/
/// for a smoke run; created.
std::filesystem::path OutputDir(bool smoke);

/// For a smoke run, prints the output's first line on stdout: "haptel bench
/// NAME: SMOKE run (--smoke): <what was shortened, printf's `format`>; its
/// figures are no measurements". Nothing otherwise.
void PrintSmokeNote(const char* bench, bool smoke, const char* format, ...)
    __attribute__((format(printf, 3, 4)));

/// The JSON line's object `object` ("{…}"), with "smoke":true as its first
/// key for a smoke run; unchanged otherwise.
std::string JsonLine(const std::string& object, bool smoke);

}  // namespace haptel::bench
