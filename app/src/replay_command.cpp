// `haptel replay`: each mode is its own function (here or in a file beside
// this); ReplayCommand only picks one by its options.
#include "haptel/app/replay_command.hpp"

#include <cstdio>
#include <string>
#include <string_view>

#include "haptel/core/args.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/mcap/info.hpp"
#include "haptel/mcap/reader.hpp"

namespace haptel::app {
namespace {

constexpr const char* kReplayUsage =
    "usage: haptel replay --info FILE.mcap [--json]\n"
    "\n"
    "--info: the session file's channels (topic, schema, encodings), message counts and\n"
    "rates, duration, chunks and their compression, attachments and metadata; a file whose\n"
    "recording was killed before it was closed is read by a scan and said to be truncated,\n"
    "with what was lost (`haptel record --recover` writes a complete copy).\n"
    "options:\n"
    "  --json    one JSON object instead of the table\n";

bool HasOption(int argc, const char* const* argv, std::string_view option) {
  for (int i = 1; i < argc; ++i) {
    if (argv[i] == option) return true;
  }
  return false;
}

}  // namespace

int ReplayCommand(int argc, const char* const* argv) {
  if (HasOption(argc, argv, "--info")) return ReplayInfoCommand(argc, argv);
  return cli::Main({"haptel replay", kReplayUsage}, argc, argv,
                   [&]() -> int { throw UsageError("expected --info FILE.mcap"); });
}

int ReplayInfoCommand(int argc, const char* const* argv) {
  return cli::Main({"haptel replay --info", kReplayUsage}, argc, argv, [&] {
    std::string path;
    bool json = false;
    cli::ReadInput([&] {
      const Args args(argc, argv, {}, {"info", "json"});
      if (args.positional().size() != 1) {
        throw UsageError(args.positional().empty()
                             ? "missing the session file (FILE.mcap)"
                             : "unexpected argument '" + args.positional()[1] + "'");
      }
      path = args.positional()[0];
      json = args.Flag("json");
    });
    const mcap::Reader reader = cli::ReadInput([&] { return mcap::Reader::Open(path); });
    const std::string text = json ? mcap::DescribeFileJson(reader) : mcap::DescribeFile(reader);
    std::fputs(text.c_str(), stdout);
    std::fflush(stdout);
    return cli::kExitOk;
  });
}

}  // namespace haptel::app
