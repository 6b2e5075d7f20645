// The programs' shared skeleton: --help, one line per error, the exit codes;
// and the stop signals, installed before anything is read.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <csignal>
#include <cstdio>
#include <string>
#include <vector>

#include "haptel/core/args.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/command_line.hpp"
#include "haptel/core/stop_signals.hpp"

namespace cli = haptel::cli;

namespace {

/// What one cli::Main call printed and returned.
struct Ran {
  int code = -1;
  std::string out;
  std::string err;
  bool body_ran = false;
};

/// Reads what was written to `file` since it was emptied.
std::string Drain(std::FILE* file) {
  std::fflush(file);
  std::rewind(file);
  std::string text;
  char buffer[256];
  while (size_t n = std::fread(buffer, 1, sizeof buffer, file)) text.append(buffer, n);
  return text;
}

/// Runs cli::Main with stdout and stderr sent to temporary files.
Ran Run(std::vector<const char*> argv, const std::function<int()>& body) {
  Ran ran;
  std::fflush(stdout);
  std::fflush(stderr);
  std::FILE* out = std::tmpfile();
  std::FILE* err = std::tmpfile();
  REQUIRE(out != nullptr);
  REQUIRE(err != nullptr);
  const int saved_out = dup(1);
  const int saved_err = dup(2);
  dup2(fileno(out), 1);
  dup2(fileno(err), 2);
  ran.code = cli::Main({"prog sub", "usage: prog sub [--x N]\n"}, static_cast<int>(argv.size()),
                       argv.data(), [&] {
                         ran.body_ran = true;
                         return body();
                       });
  std::fflush(stdout);
  std::fflush(stderr);
  dup2(saved_out, 1);
  dup2(saved_err, 2);
  close(saved_out);
  close(saved_err);
  ran.out = Drain(out);
  ran.err = Drain(err);
  std::fclose(out);
  std::fclose(err);
  return ran;
}

}  // namespace

TEST_CASE("cli::Main prints the usage for --help or -h and does not run the program") {
  for (const char* help : {"--help", "-h"}) {
    const Ran ran = Run({"sub", "--x", "1", help}, [] { return 0; });
    CHECK(ran.code == cli::kExitOk);
    CHECK_FALSE(ran.body_ran);
    CHECK(ran.out == "usage: prog sub [--x N]\n");
    CHECK(ran.err.empty());
  }
  // After "--" it is an argument, not a request for help.
  const Ran ran = Run({"sub", "--", "--help"}, [] { return 7; });
  CHECK(ran.body_ran);
  CHECK(ran.code == 7);
}

TEST_CASE("cli::Main maps what escapes the program to one line and an exit code") {
  SECTION("bad usage: 2, with a pointer to --help") {
    const Ran ran = Run({"sub"}, []() -> int { throw haptel::UsageError("unknown option --y"); });
    CHECK(ran.code == cli::kExitBadInput);
    CHECK(ran.err == "prog sub: unknown option --y (see prog sub --help)\n");
  }
  SECTION("other bad input: 2") {
    const Ran ran =
        Run({"sub"}, []() -> int { throw cli::InputError("a.yaml:3:1: key 'x': expected > 0"); });
    CHECK(ran.code == cli::kExitBadInput);
    CHECK(ran.err == "prog sub: a.yaml:3:1: key 'x': expected > 0\n");
  }
  SECTION("a failure while running: 1") {
    const Ran ran =
        Run({"sub"}, []() -> int { throw std::runtime_error("cannot bind 127.0.0.1:80"); });
    CHECK(ran.code == cli::kExitFailed);
    CHECK(ran.err == "prog sub: cannot bind 127.0.0.1:80\n");
  }
  SECTION("what the program returns, it returns") {
    const Ran ran = Run({"sub"}, [] { return cli::kExitLost; });
    CHECK(ran.code == cli::kExitLost);
    CHECK(ran.err.empty());
  }
}

TEST_CASE("cli::ReadInput turns whatever reading throws into bad input") {
  CHECK(cli::ReadInput([] { return 5; }) == 5);
  CHECK_THROWS_AS(cli::ReadInput([]() -> int { throw std::runtime_error("yaml: bad"); }),
                  cli::InputError);
  CHECK_THROWS_WITH(cli::ReadInput([]() -> int { throw std::out_of_range("stod"); }), "stod");
  // Its own kind passes through unchanged (a UsageError keeps its --help pointer).
  CHECK_THROWS_AS(cli::ReadInput([]() -> int { throw haptel::UsageError("x"); }),
                  haptel::UsageError);
}

TEST_CASE("The stop signals set the flag instead of ending the process") {
  const std::atomic<bool>& stop = haptel::InstallStopSignals();
  CHECK_FALSE(stop.load());
  REQUIRE(std::raise(SIGHUP) == 0);  // default action: the test process would die here
  CHECK(stop.load());
  CHECK(haptel::StopSignal() == SIGHUP);
  CHECK(&haptel::InstallStopSignals() == &stop);  // idempotent: the same flag
}

TEST_CASE("A command line written by cli::CommandLine reads back into its words") {
  const std::vector<const char*> argv = {"run", "--track", "my tracks/it's.yaml", "--json",
                                         "$HOME"};
  const std::string line = cli::CommandLine(static_cast<int>(argv.size()), argv.data());
  CHECK(line == "haptel run --track 'my tracks/it'\\''s.yaml' --json '$HOME'");
  const std::vector<std::string> words = cli::CommandLineWords(line);
  REQUIRE(words.size() == argv.size() + 1);
  CHECK(words[0] == "haptel");
  for (size_t i = 0; i < argv.size(); ++i) CHECK(words[i + 1] == argv[i]);
  CHECK_THROWS_AS(cli::CommandLineWords("haptel run 'open"), haptel::UsageError);
  // A mode's option is found as a word of its own, not inside another.
  CHECK(cli::HasOption(static_cast<int>(argv.size()), argv.data(), "--json"));
  CHECK_FALSE(cli::HasOption(static_cast<int>(argv.size()), argv.data(), "--js"));
  CHECK_FALSE(cli::HasOption(static_cast<int>(argv.size()), argv.data(), "run"));  // argv[0]
}
