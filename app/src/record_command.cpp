// `haptel record`: each mode is its own function (here or in a file beside
// this); RecordCommand only picks one by its options.
#include "haptel/app/record_command.hpp"

#include <cstdio>
#include <filesystem>
#include <string>

#include "haptel/core/args.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/command_line.hpp"
#include "haptel/mcap/recover.hpp"

namespace haptel::app {
namespace {

constexpr const char* kRecordUsage =
    "usage: haptel record --recover IN.mcap OUT.mcap\n"
    "\n"
    "--recover: writes OUT, a complete session file (summary and indexes rebuilt), from IN,\n"
    "one whose recording was killed before it was closed: every complete chunk survives,\n"
    "the torn tail is dropped and counted.\n";

}  // namespace

int RecordCommand(int argc, const char* const* argv) {
  if (cli::HasOption(argc, argv, "--recover")) return RecordRecoverCommand(argc, argv);
  return RecordDomainCommand(argc, argv);
}

int RecordRecoverCommand(int argc, const char* const* argv) {
  return cli::Main({"haptel record --recover", kRecordUsage}, argc, argv, [&] {
    std::filesystem::path in, out;
    cli::ReadInput([&] {
      const Args args(argc, argv, {}, {"recover"});
      if (args.positional().size() != 2) {
        throw UsageError(args.positional().size() < 2
                             ? "expected --recover IN.mcap OUT.mcap"
                             : "unexpected argument '" + args.positional()[2] + "'");
      }
      in = args.positional()[0];
      out = args.positional()[1];
      if (std::filesystem::exists(out) && std::filesystem::equivalent(in, out)) {
        throw UsageError("--recover: OUT must be another file than IN (" + in.string() + ")");
      }
    });
    // The input is read before anything is written: a file that is not MCAP
    // is bad input (exit 2) and leaves no OUT behind.
    const mcap::Reader reader = cli::ReadInput([&] { return mcap::Reader::Open(in); });
    const mcap::RecoverResult result = mcap::Recover(reader, out);
    std::printf("recovered %llu messages, %u attachments, %u metadata into %s\n",
                static_cast<unsigned long long>(result.messages), result.attachments,
                result.metadata, out.c_str());
    if (!result.loss.what.empty()) std::printf("%s: %s\n", in.c_str(), result.loss.what.c_str());
    std::fflush(stdout);
    return cli::kExitOk;
  });
}

}  // namespace haptel::app
