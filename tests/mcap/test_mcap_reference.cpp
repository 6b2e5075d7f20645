// Our MCAP files read by the TypeScript reference reader (@mcap/core's
// indexed and stream readers, CRCs validated) through
// tests/mcap/mcap_reference_reader.mjs, whose JSON counts must match what
// was written; an `omgidl` + `cdr` channel is decoded against the file's own
// schema (@foxglove/omgidl-serialization), and a recovered file reads too.
#include <catch2/catch.hpp>
#include <cstdio>
#include <cstring>
#include <string>

#include "haptel/core/json.hpp"
#include "haptel/mcap/recover.hpp"
#include "haptel/mcap/writer.hpp"
#include "mcap_reference.hpp"
#include "test_env.hpp"

namespace fs = std::filesystem;
namespace mcap = haptel::mcap;

namespace {

/// A CDR (little-endian, plain) test::Point.
std::string Point(double x, double y) {
  std::string cdr("\x00\x01\x00\x00", 4);
  cdr.append(reinterpret_cast<const char*>(&x), 8);
  cdr.append(reinterpret_cast<const char*>(&y), 8);
  return cdr;
}

void WriteSession(const fs::path& path, mcap::Compression compression,
                  const fs::path& killed = {}) {
  mcap::WriterOptions options;
  options.profile = "haptel";
  options.compression = compression;
  options.chunk_size = 2048;
  mcap::Writer writer(path, options);
  const uint16_t point = writer.AddSchema("test::Point", "omgidl",
                                          "module test { struct Point { double x; double y; }; };");
  const uint16_t hands = writer.AddChannel(point, "/hands", "cdr");
  const uint16_t raw = writer.AddChannel(0, "/raw", "application/octet-stream");
  writer.AddMetadata("haptel", {{"version", "0.1.0"}});
  const std::string yaml = "a: 1\n";
  writer.AddAttachment("run.yaml", "application/yaml", 1, yaml.data(), yaml.size());
  for (uint32_t i = 0; i < 300; ++i) {
    const std::string p = Point(i * 0.5, -1.0 * i);
    const uint64_t t = 5'000'000'000ull + i * 1'000'000ull - (i % 11 == 3 ? 20'000'000ull : 0);
    writer.Write(hands, i, t, t, p.data(), p.size());
    if (i % 3 == 0) writer.Write(raw, i, t + 1, t + 1, &i, sizeof i);
  }
  if (!killed.empty()) {
    writer.Flush();
    fs::copy_file(path, killed, fs::copy_options::overwrite_existing);
  }
  writer.Close();
}

}  // namespace

TEST_CASE("the reference reader reads our files whole, CRCs checked, every CDR message decoded",
          "[mcap]") {
  const fs::path dir = haptel::test::ScratchDir("mcap-reference");
  for (const auto compression :
       {mcap::Compression::kZstd, mcap::Compression::kLz4, mcap::Compression::kNone}) {
    const fs::path path =
        dir / ("session-" + std::string(mcap::CompressionName(compression)) + ".mcap");
    WriteSession(path, compression);
    const std::string json = haptel::test::ReferenceRead(path, "--decode --dump /hands");
    INFO(json);
    CHECK_THAT(
        json,
        Catch::Contains(
            R"("messages":400,"per_topic":{"/hands":300,"/raw":100},"in_log_time_order":true,"channels":2,"schemas":1)"));
    CHECK_THAT(json,
               Catch::Contains(
                   R"("attachments":1,"metadata":1,"statistics_messages":400,"profile":"haptel")"));
    CHECK_THAT(json, Catch::Contains(R"("crc":{"data_section_ok":true,"summary_ok":true})"));
    CHECK_THAT(
        json,
        Catch::Contains(
            R"("stream":{"messages":400,"per_topic":{"/hands":300,"/raw":100},"attachments":1,"metadata":1,"footer":true,"done":true})"));
    CHECK_THAT(
        json,
        Catch::Contains(
            R"("decoded":{"ok":300,"per_topic":{"/hands":300},"failed":0,"skipped":100,"failures":[]})"));
  }
}

TEST_CASE("the reference reader reads a recovered file", "[mcap]") {
  const fs::path dir = haptel::test::ScratchDir("mcap-reference-recovered");
  WriteSession(dir / "closed.mcap", mcap::Compression::kZstd, dir / "killed.mcap");
  // Cut in the middle of the last chunk, as a SIGKILL mid-write leaves it.
  const auto size = fs::file_size(dir / "killed.mcap");
  fs::resize_file(dir / "killed.mcap", size - 300);
  const mcap::RecoverResult result = mcap::Recover(dir / "killed.mcap", dir / "recovered.mcap");
  REQUIRE(result.loss.truncated);
  REQUIRE(result.messages > 0);
  REQUIRE(result.messages < 400);
  const std::string json = haptel::test::ReferenceRead(dir / "recovered.mcap");
  INFO(json);
  CHECK(haptel::JsonFieldOf(json, "messages") == std::to_string(result.messages));
  CHECK_THAT(json, Catch::Contains(R"("statistics_messages":)" + std::to_string(result.messages)));
  CHECK_THAT(json, Catch::Contains(R"("crc":{"data_section_ok":true,"summary_ok":true})"));
  CHECK_THAT(json, Catch::Contains(R"("footer":true,"done":true)"));
}
