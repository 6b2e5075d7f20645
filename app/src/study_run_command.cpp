// `haptel study run FILE`'s command line: its options parsed into
// StudyRunOptions, then study::RunStudy (study/study_run.hpp) runs it.
#include <string>

#include "haptel/app/study_command.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/stop_signals.hpp"
#include "haptel/study/study_run.hpp"

namespace haptel::app {
namespace {

constexpr const char* kRunUsage =
    "usage: haptel study run FILE [options]   run an A/B study (config/studies/*.yaml)\n"
    "\n"
    "Runs the planned trials in order, each a session like `haptel run`, and records each\n"
    "as it finishes; run the same command again after a stop to resume at the first\n"
    "unfinished trial.\n"
    "options:\n"
    "  --database FILE   SQLite file (overrides the study's and the run configuration's)\n"
    "  --domain N        DDS domain id of the trials' vehicles (overrides the run "
    "configuration's)\n"
    "  --json            end with one JSON line: the trials and per-condition totals\n"
    "  --simulated-time  each trial in simulated time (`haptel run --simulated-time`): every\n"
    "                    part on one clock in this process, as fast as the CPU allows, the same\n"
    "                    lap for the same seed; synthetic studies only. The summary and the\n"
    "                    JSON's speedup say how much faster than real time the trials ran\n"
    "  --console         serve the experimenter's console (schedule, live trial) on 127.0.0.1;\n"
    "                    a person study always does: its trials start from it, its\n"
    "                    questionnaires are filled in there after each condition\n"
    "  --port N          the console's port (default 8470)\n"
    "  --bind ADDR       the console's address (default 127.0.0.1); beyond this machine\n"
    "                    (e.g. 0.0.0.0 for every interface) the page asks once for an access\n"
    "                    token, printed here, and HTTPS is required:\n"
    "  --tls DIR         serve HTTPS with DIR/console.pem and DIR/console.key (made by\n"
    "                    `haptel security init DIR --console NAME,...`)\n"
    "  --plain-http      beyond this machine without HTTPS (the token crosses the network in\n"
    "                    clear; only on a network you trust)\n"
    "  --verbose         the sessions' own progress lines\n";

study::StudyRunOptions ParseStudyRunArgs(int argc, const char* const* argv) {
  const Args args(argc, argv, {"database", "domain", "port", "bind", "tls"},
                  {"json", "verbose", "console", "plain-http", "simulated-time"});
  study::StudyRunOptions options;
  study::ConsoleOptions& console = options.console_options;
  console.port = args.Int("port", 1, 65535).value_or(console.port);
  console.host = args.Value("bind").value_or(console.host);
  console.plain_http = args.Flag("plain-http");
  if (const auto tls = args.Value("tls")) {
    const study::ConsoleCertificate certificate = study::FindConsoleCertificate(*tls);
    console.tls_certificate = certificate.certificate;
    console.tls_key = certificate.key;
    console.names = certificate.names;
  }
  options.console = args.Flag("console") || args.Value("port").has_value() ||
                    args.Value("bind").has_value() || args.Value("tls").has_value();
  if (const auto d = args.Int("domain", 0, 232)) options.domain = std::to_string(*d);
  if (args.positional().size() != 2 || args.positional()[0] != "run") {
    throw UsageError(args.positional().size() < 2
                         ? "missing the study file"
                         : "unexpected argument '" + args.positional()[2] + "'");
  }
  options.json = args.Flag("json");
  options.verbose = args.Flag("verbose");
  options.file = args.positional()[1];
  options.simulated_time = args.Flag("simulated-time");
  options.database = args.Value("database");
  return options;
}

}  // namespace

int StudyRunCommand(int argc, const char* const* argv) {
  // First: a signal while the files are read ends the study before its next trial.
  const std::atomic<bool>& interrupted = InstallStopSignals();
  return cli::Main({"haptel study run", kRunUsage}, argc, argv, [&] {
    const study::StudyRunOptions options =
        cli::ReadInput([&] { return ParseStudyRunArgs(argc, argv); });
    return study::RunStudy(options, interrupted);
  });
}

}  // namespace haptel::app
