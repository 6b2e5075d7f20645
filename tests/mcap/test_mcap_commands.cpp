// `haptel replay --info` and `haptel record --recover`: their command lines
// and exit codes over the MCAP library.
#include <catch2/catch.hpp>
#include <fstream>

#include "haptel/app/record_command.hpp"
#include "haptel/app/replay_command.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/mcap/reader.hpp"
#include "haptel/mcap/writer.hpp"
#include "test_env.hpp"

namespace fs = std::filesystem;
namespace mcap = haptel::mcap;

TEST_CASE("haptel record --recover writes a complete file; replay --info reads either",
          "[mcap][app]") {
  const fs::path dir = haptel::test::ScratchDir("mcap-commands");
  const fs::path closed = dir / "closed.mcap", killed = dir / "killed.mcap", out = dir / "out.mcap";
  {
    mcap::Writer writer(closed);
    const uint16_t channel = writer.AddChannel(0, "/raw", "application/octet-stream");
    for (uint32_t i = 0; i < 50; ++i) writer.Write(channel, i, i * 1000, i * 1000, &i, sizeof i);
    writer.Flush();
    fs::copy_file(closed, killed);
  }
  const std::string in = killed.string(), out_text = out.string();
  const char* recover[] = {"record", "--recover", in.c_str(), out_text.c_str()};
  REQUIRE(haptel::app::RecordCommand(4, recover) == haptel::cli::kExitOk);
  const mcap::Reader reader = mcap::Reader::Open(out);
  CHECK_FALSE(reader.recovered());
  CHECK(reader.statistics().message_count == 50);
  CHECK(reader.Verify().empty());

  const char* info[] = {"replay", "--info", in.c_str()};
  CHECK(haptel::app::ReplayCommand(3, info) == haptel::cli::kExitOk);
  const std::string not_mcap = haptel::test::WriteFile(dir / "x.mcap", "no").string();
  const char* bad[] = {"record", "--recover", not_mcap.c_str(), out_text.c_str()};
  CHECK(haptel::app::RecordCommand(4, bad) == haptel::cli::kExitBadInput);
  const char* same[] = {"record", "--recover", in.c_str(), in.c_str()};
  CHECK(haptel::app::RecordCommand(4, same) == haptel::cli::kExitBadInput);
  const char* missing[] = {"replay", "--info"};
  CHECK(haptel::app::ReplayCommand(2, missing) == haptel::cli::kExitBadInput);
}
