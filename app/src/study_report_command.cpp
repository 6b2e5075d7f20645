// `haptel study report DATABASE --study NAME`'s command line: the tables,
// the statistics, and the files (CSV, PNG, HTML) for one study, as
// study/report/ computes and writes them.
#include <cstdio>
#include <string>

#include "haptel/app/study_command.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/study/report.hpp"

namespace haptel::app {
namespace {

constexpr const char* kReportUsage =
    "usage: haptel study report DATABASE --study NAME [options]\n"
    "\n"
    "Prints each condition's table (lap time as scored, per-participant rank, obstacles), the\n"
    "Friedman test (its exact permutation p for small studies, the chi2 approximation past\n"
    "that; the output says which), Kendall's W and a post-hoc test, the mixed model\n"
    "log(lap time) ~ condition + position + (1 | participant) (REML; Satterthwaite t tests\n"
    "against the first condition, Satterthwaite's F test of the condition), each lap's\n"
    "percentage over the track's reference lap, and writes trials.csv, answers.csv,\n"
    "summary.csv, lap_times.png, ranks.png, ratings.png (with scored questionnaires),\n"
    "model_means.png and index.html.\n"
    "options:\n"
    "  --study NAME          the study (its file's 'name')\n"
    "  --out DIR             where the files go (default <database dir>/report-<study>/)\n"
    "  --post-hoc METHOD     nemenyi (default; critical difference of mean ranks, alpha 0.05)\n"
    "                        or wilcoxon-holm (pairwise signed-rank tests, Holm-adjusted)\n"
    "  --json                end with one JSON line: per-condition totals and mean ranks,\n"
    "                        friedman_chi2, friedman_p (exact when cheap, else the chi2\n"
    "                        approximation), friedman_p_exact, friedman_p_asymptotic,\n"
    "                        kendall_w, the post-hoc pairs,\n"
    "                        lmm (per condition estimate, ci_low, ci_high, p), baseline\n";

}  // namespace

int StudyReportCommand(int argc, const char* const* argv) {
  return cli::Main({"haptel study report", kReportUsage}, argc, argv, [&] {
    std::filesystem::path database;
    std::string name;
    std::filesystem::path out;
    study::PostHocMethod method = study::PostHocMethod::kNemenyi;
    bool json = false;
    cli::ReadInput([&] {
      const Args args(argc, argv, {"study", "out", "post-hoc"}, {"json"});
      if (args.positional().size() != 2 || args.positional()[0] != "report") {
        throw UsageError(args.positional().size() < 2
                             ? "missing the database file"
                             : "unexpected argument '" + args.positional()[2] + "'");
      }
      database = args.positional()[1];
      const auto study = args.Value("study");
      if (!study) throw UsageError("--study NAME is required");
      name = *study;
      out = args.Value("out").value_or((database.parent_path() / ("report-" + name)).string());
      const std::string post_hoc = args.Value("post-hoc").value_or("nemenyi");
      if (post_hoc == "wilcoxon-holm") {
        method = study::PostHocMethod::kWilcoxonHolm;
      } else if (post_hoc != "nemenyi") {
        throw UsageError("option --post-hoc: expected nemenyi or wilcoxon-holm, got '" + post_hoc +
                         "'");
      }
      json = args.Flag("json");
    });
    const study::StudyResults results =
        cli::ReadInput([&] { return study::LoadStudyResults(database, name); });
    const study::StudyReport report = study::ComputeReport(results, method);
    const study::ReportFiles files = study::WriteReport(results, report, out);
    std::printf("%s\n  report: %s\n", study::FormatReport(results, report).c_str(),
                files.html.c_str());
    if (json) std::printf("%s\n", study::ReportJson(results, report, files).c_str());
    std::fflush(stdout);
    return cli::kExitOk;
  });
}

}  // namespace haptel::app
