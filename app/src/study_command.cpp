// `haptel study`: the study's subcommands, each in its own file beside this.
#include "haptel/app/study_command.hpp"

#include <string>

#include "haptel/core/args.hpp"
#include "haptel/core/cli.hpp"

namespace haptel::app {
namespace {
constexpr const char* kUsage =
    "usage: haptel study run FILE [options]          run an A/B study (--help for options)\n"
    "       haptel study report DATABASE --study NAME  tables, statistics, plots (--help for "
    "options)\n"
    "       haptel study power FILE [options]        participants needed: power by simulation "
    "(--help)\n";
}  // namespace

int StudyCommand(int argc, const char* const* argv) {
  const std::string sub = argc > 1 ? argv[1] : "";
  if (sub == "run") return StudyRunCommand(argc, argv);
  if (sub == "report") return StudyReportCommand(argc, argv);
  if (sub == "power") return StudyPowerCommand(argc, argv);
  return cli::Main({"haptel study", kUsage}, argc, argv, [&]() -> int {
    throw UsageError(sub.empty() ? "missing command (run, report, power)"
                                 : "unknown command '" + sub + "' (run, report, power)");
  });
}

}  // namespace haptel::app
