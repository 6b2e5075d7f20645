// The MCAP library: what is written is read back equal (every compression),
// every CRC catches a flipped byte, a file cut anywhere in its last chunk
// keeps every earlier chunk and recovers to a complete file, and seeking
// hands out exactly the messages of the interval, in log-time order.
#include <catch2/catch.hpp>
#include <cstring>
#include <fstream>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "file_size_limit.hpp"
#include "haptel/core/json.hpp"
#include "haptel/mcap/info.hpp"
#include "haptel/mcap/reader.hpp"
#include "haptel/mcap/recover.hpp"
#include "haptel/mcap/writer.hpp"
#include "test_env.hpp"

namespace mcap = haptel::mcap;
namespace fs = std::filesystem;

namespace {

struct Sent {
  uint16_t channel;
  uint32_t sequence;
  uint64_t log_time_ns;
  uint64_t publish_time_ns;
  std::string data;
  auto key() const { return std::tie(log_time_ns, channel, sequence, publish_time_ns, data); }
};

struct Sample {
  std::vector<Sent> sent;  // in the order written
  std::string attachment = std::string("track: test-short\n") + std::string(3000, 'x');
};

/// Two schemas, three channels (one without a schema), messages mostly in
/// time order with some written late (a stamp older than the one before),
/// small chunks so there are many, an attachment and metadata. With
/// `killed`, the file as a SIGKILL after the last Flush leaves it (no
/// summary, no footer) is copied there before the writer closes.
Sample WriteSample(const fs::path& path, mcap::Compression compression, const fs::path& killed = {},
                   size_t messages = 600) {
  Sample sample;
  mcap::WriterOptions options;
  options.profile = "haptel";
  options.compression = compression;
  options.chunk_size = 4096;
  mcap::Writer writer(path, options);
  const uint16_t point = writer.AddSchema("test::Point", "omgidl",
                                          "module test { struct Point { double x; double y; }; };");
  const uint16_t text = writer.AddSchema("test::Text", "jsonschema", R"({"type":"object"})");
  const uint16_t channels[3] = {
      writer.AddChannel(point, "/hands/right", "cdr", {{"rate_hz", "1000"}}),
      writer.AddChannel(text, "/events", "json"),
      writer.AddChannel(0, "/raw", "application/octet-stream")};
  writer.AddMetadata("haptel", {{"version", "0.1.0"}, {"command_line", "haptel run --session x"}});
  writer.AddAttachment("config/tracks/test-short.yaml", "application/yaml", 5,
                       sample.attachment.data(), sample.attachment.size());
  std::mt19937 rng(7);
  for (size_t i = 0; i < messages; ++i) {
    const uint16_t channel = channels[i % 3];
    uint64_t time = 1'000'000'000ull + i * 1'000'000ull;
    if (i % 17 == 5) time -= 40'000'000ull;  // late: 40 ms older than its neighbours
    std::string data(8 + rng() % 90, '\0');
    for (char& c : data) c = static_cast<char>(rng());
    sample.sent.push_back({channel, static_cast<uint32_t>(i), time, time + 7, data});
    writer.Write(channel, static_cast<uint32_t>(i), time, time + 7, data.data(), data.size());
  }
  if (!killed.empty()) {
    writer.Flush();
    fs::copy_file(path, killed, fs::copy_options::overwrite_existing);
  }
  writer.Close();
  return sample;
}

std::vector<Sent> ReadAll(const mcap::Reader& reader, uint64_t start = 0, uint64_t end = UINT64_MAX,
                          const std::vector<std::string>& topics = {}) {
  std::vector<Sent> got;
  reader.ForEachMessage(start, end, topics, [&](const mcap::MessageView& m) {
    got.push_back({m.channel->id, m.sequence, m.log_time_ns, m.publish_time_ns,
                   std::string(reinterpret_cast<const char*>(m.data), m.size)});
  });
  return got;
}

/// What a reader must hand out: `sent` filtered, in log-time order (ties
/// in the order written).
std::vector<Sent> Expected(std::vector<Sent> sent, uint64_t start = 0, uint64_t end = UINT64_MAX,
                           std::vector<uint16_t> channels = {0, 1, 2}) {
  std::erase_if(sent, [&](const Sent& s) {
    return s.log_time_ns < start || s.log_time_ns >= end ||
           std::find(channels.begin(), channels.end(), s.channel) == channels.end();
  });
  std::stable_sort(sent.begin(), sent.end(),
                   [](const Sent& a, const Sent& b) { return a.log_time_ns < b.log_time_ns; });
  return sent;
}

bool Same(const std::vector<Sent>& a, const std::vector<Sent>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i].key() != b[i].key()) return false;
  }
  return true;
}

std::string Bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void Put(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << bytes;
}

}  // namespace

TEST_CASE("an MCAP file is read back as written, with every compression", "[mcap]") {
  const fs::path dir = haptel::test::ScratchDir("mcap-roundtrip");
  for (const auto compression :
       {mcap::Compression::kZstd, mcap::Compression::kLz4, mcap::Compression::kNone}) {
    const std::string name = std::string(mcap::CompressionName(compression));
    INFO("compression " << (name.empty() ? "none" : name));
    const fs::path path = dir / ("roundtrip-" + name + ".mcap");
    const Sample sample = WriteSample(path, compression);
    const mcap::Reader reader = mcap::Reader::Open(path);
    CHECK_FALSE(reader.recovered());
    CHECK(reader.profile() == "haptel");
    CHECK(reader.library() == "haptel");
    REQUIRE(reader.schemas().size() == 2);
    CHECK(reader.schemas().at(1).name == "test::Point");
    CHECK(reader.schemas().at(1).encoding == "omgidl");
    CHECK(reader.schemas().at(2).data == R"({"type":"object"})");
    REQUIRE(reader.channels().size() == 3);
    CHECK(reader.channels().at(0).topic == "/hands/right");
    CHECK(reader.channels().at(0).metadata.at("rate_hz") == "1000");
    CHECK(reader.channels().at(2).schema_id == 0);
    const mcap::Statistics& st = reader.statistics();
    CHECK(st.message_count == 600);
    CHECK(st.channel_message_counts.at(1) == 200);
    CHECK(st.message_start_time_ns == 1'000'000'000ull + 5 * 1'000'000ull - 40'000'000ull);  // late
    CHECK(st.message_end_time_ns == 1'000'000'000ull + 599 * 1'000'000ull);
    CHECK(st.chunk_count > 5);
    CHECK(reader.summary().chunk_indexes.front().compression == compression);
    CHECK(Same(ReadAll(reader), Expected(sample.sent)));
    REQUIRE(reader.summary().attachment_indexes.size() == 1);
    const mcap::Attachment attachment =
        reader.ReadAttachment(reader.summary().attachment_indexes[0]);
    CHECK(attachment.name == "config/tracks/test-short.yaml");
    CHECK(attachment.media_type == "application/yaml");
    CHECK(attachment.data == sample.attachment);
    REQUIRE(reader.summary().metadata_indexes.size() == 1);
    const mcap::Metadata metadata = reader.ReadMetadata(reader.summary().metadata_indexes[0]);
    CHECK(metadata.name == "haptel");
    CHECK(metadata.metadata.at("command_line") == "haptel run --session x");
    CHECK(reader.Verify().empty());
  }
}

TEST_CASE("a flipped byte anywhere is caught by a CRC", "[mcap]") {
  const fs::path dir = haptel::test::ScratchDir("mcap-crc");
  const fs::path good = dir / "good.mcap";
  WriteSample(good, mcap::Compression::kNone);
  const std::string bytes = Bytes(good);
  const mcap::Reader reader = mcap::Reader::Open(good);
  const mcap::ChunkIndex chunk = reader.summary().chunk_indexes.at(2);
  const mcap::AttachmentIndex attachment = reader.summary().attachment_indexes.at(0);

  SECTION("in a chunk's records: Verify and reading that chunk say so") {
    std::string damaged = bytes;
    damaged[chunk.chunk_start_offset + chunk.chunk_length - 50] ^= 0x10;  // a message's bytes
    Put(dir / "chunk.mcap", damaged);
    const mcap::Reader bad = mcap::Reader::Open(dir / "chunk.mcap");
    const auto problems = bad.Verify();
    REQUIRE_FALSE(problems.empty());
    const std::string all = Catch::Detail::stringify(problems);
    CHECK_THAT(all, Catch::Contains("data section CRC mismatch"));
    CHECK_THAT(all,
               Catch::Contains("chunk.mcap at byte " + std::to_string(chunk.chunk_start_offset) +
                               " (Chunk): chunk CRC mismatch"));
    CHECK_THROWS_WITH(ReadAll(bad), Catch::Contains("chunk CRC mismatch"));
  }
  SECTION("in an attachment: reading it says so") {
    std::string damaged = bytes;
    damaged[attachment.offset + attachment.length - 100] ^= 0x01;
    Put(dir / "attachment.mcap", damaged);
    const mcap::Reader bad = mcap::Reader::Open(dir / "attachment.mcap");
    CHECK_THROWS_WITH(bad.ReadAttachment(bad.summary().attachment_indexes.at(0)),
                      Catch::Contains("attachment 'config/tracks/test-short.yaml' CRC mismatch"));
    CHECK_FALSE(bad.Verify().empty());
  }
  SECTION("in a message index: the data section's CRC says so") {
    std::string damaged = bytes;
    damaged[chunk.message_index_offsets.begin()->second + 12] ^= 0x01;  // an entry's time
    Put(dir / "index.mcap", damaged);
    const auto problems = mcap::Reader::Open(dir / "index.mcap").Verify();
    REQUIRE_FALSE(problems.empty());
    CHECK_THAT(problems[0], Catch::Contains("data section CRC mismatch"));
  }
  SECTION("in the summary: the footer's CRC says so") {
    std::string damaged = bytes;
    // A byte of the last chunk index's compressed size: the summary still parses.
    damaged[bytes.size() - 8 - 29 - 16 - 1 - 10] ^= 0x01;
    Put(dir / "summary.mcap", damaged);
    const auto problems = mcap::Reader::Open(dir / "summary.mcap").Verify();
    REQUIRE_FALSE(problems.empty());
    CHECK_THAT(Catch::Detail::stringify(problems), Catch::Contains("summary CRC mismatch"));
  }
}

TEST_CASE("a file cut anywhere in its last chunk keeps every earlier chunk and recovers whole",
          "[mcap]") {
  const fs::path dir = haptel::test::ScratchDir("mcap-cut");
  for (const auto compression : {mcap::Compression::kZstd, mcap::Compression::kLz4}) {
    const fs::path full = dir / "full.mcap";
    const Sample sample = WriteSample(dir / "closed.mcap", compression, full);
    const std::string bytes = Bytes(full);
    const mcap::Reader whole = mcap::Reader::Open(full);
    REQUIRE(whole.recovered());
    CHECK(whole.statistics().message_count == 600);
    CHECK(Same(ReadAll(whole), Expected(sample.sent)));
    const mcap::ChunkIndex last = whole.summary().chunk_indexes.back();
    const size_t chunks = whole.summary().chunk_indexes.size();
    // The messages of every chunk but the last.
    Put(dir / "without-last.mcap", bytes.substr(0, last.chunk_start_offset));
    const uint64_t before_last =
        mcap::Reader::Open(dir / "without-last.mcap").statistics().message_count;
    REQUIRE(before_last < 600);
    // Cut at a sample of offsets through the last chunk and its indexes.
    const uint64_t from = last.chunk_start_offset + 1, to = bytes.size() - 1;
    for (uint64_t at = from; at <= to; at += std::max<uint64_t>(1, (to - from) / 23)) {
      INFO("cut at byte " << at << " of " << bytes.size());
      const fs::path cut = dir / "cut.mcap";
      Put(cut, bytes.substr(0, at));
      const mcap::Reader reader = mcap::Reader::Open(cut);
      CHECK(reader.recovered());
      CHECK(reader.summary().chunk_indexes.size() >= chunks - 1);
      const uint64_t chunk_end = last.chunk_start_offset + last.chunk_length;
      const bool chunk_torn = at < chunk_end;
      CHECK(reader.statistics().message_count == (chunk_torn ? before_last : 600));
      CHECK(reader.statistics().attachment_count == 1);
      CHECK(reader.loss().chunks_lost == (chunk_torn ? 1u : 0u));
      if (chunk_torn) {
        CHECK(reader.loss().bytes_lost == at - last.chunk_start_offset);
      } else {  // a message index after the chunk is torn
        CHECK(reader.loss().bytes_lost <= at - chunk_end);
      }
      CHECK_THAT(reader.loss().what, Catch::Contains("truncated"));

      const fs::path out = dir / "recovered.mcap";
      const mcap::RecoverResult result = mcap::Recover(cut, out);
      CHECK(result.messages == reader.statistics().message_count);
      const mcap::Reader recovered = mcap::Reader::Open(out);
      CHECK_FALSE(recovered.recovered());
      CHECK(recovered.Verify().empty());
      CHECK(recovered.statistics().message_count == reader.statistics().message_count);
      CHECK(Same(ReadAll(recovered), ReadAll(reader)));
      CHECK(recovered.channels().size() == 3);
      CHECK(recovered.ReadAttachment(recovered.summary().attachment_indexes.at(0)).data ==
            sample.attachment);
      CHECK(recovered.summary().metadata_indexes.size() == 1);
    }
  }
}

TEST_CASE("seeking hands out exactly the messages of the interval and topics, in log-time order",
          "[mcap]") {
  const fs::path dir = haptel::test::ScratchDir("mcap-seek");
  const fs::path path = dir / "seek.mcap";
  const Sample sample = WriteSample(path, mcap::Compression::kZstd);
  const mcap::Reader reader = mcap::Reader::Open(path);
  std::mt19937 rng(11);
  for (int i = 0; i < 40; ++i) {
    const uint64_t start = 950'000'000ull + rng() % 700'000'000ull;
    const uint64_t end = start + rng() % 120'000'000ull;
    INFO("[" << start << ", " << end << ")");
    CHECK(Same(ReadAll(reader, start, end), Expected(sample.sent, start, end)));
    CHECK(Same(ReadAll(reader, start, end, {"/events", "/raw"}),
               Expected(sample.sent, start, end, {1, 2})));
  }
  CHECK(ReadAll(reader, 0, 1'000'000'000ull - 40'000'000ull).empty());
  CHECK(ReadAll(reader, 0, UINT64_MAX, {"/no/such/topic"}).empty());
  // The late messages come out in their place, not where they were written.
  const auto all = ReadAll(reader);
  CHECK(std::is_sorted(all.begin(), all.end(),
                       [](const Sent& a, const Sent& b) { return a.log_time_ns < b.log_time_ns; }));
}

TEST_CASE("what cannot be written or read is said, naming the file", "[mcap]") {
  const fs::path dir = haptel::test::ScratchDir("mcap-errors");
  SECTION("a folder that is not there") {
    CHECK_THROWS_WITH(mcap::Writer(dir / "gone" / "s.mcap"),
                      Catch::Contains("gone/s.mcap: cannot create the session file"));
  }
  SECTION("a full disk: the write that fails throws, and the file keeps what was written whole") {
    const fs::path path = dir / "full.mcap";
    mcap::WriterOptions options;
    options.chunk_size = 1024;
    mcap::Writer writer(path, options);
    const uint16_t channel = writer.AddChannel(0, "/raw", "application/octet-stream");
    const std::string data(200, 'a');
    std::string error;
    {
      haptel::test::FileSizeLimit limit(20'000);
      try {
        for (uint32_t i = 0; i < 1000; ++i)
          writer.Write(channel, i, i, i, data.data(), data.size());
      } catch (const std::runtime_error& e) {
        error = e.what();
      }
    }
    CHECK_THAT(error, Catch::Contains("full.mcap: cannot write the session file: File too large"));
    CHECK(mcap::Reader::Open(path).statistics().message_count > 0);
  }
  SECTION("not an MCAP file") {
    Put(dir / "not.mcap", "hello, this is not MCAP at all");
    CHECK_THROWS_WITH(mcap::Reader::Open(dir / "not.mcap"),
                      Catch::Contains("not.mcap: not an MCAP file"));
  }
  SECTION("an unknown channel or schema") {
    mcap::Writer writer(dir / "w.mcap");
    CHECK_THROWS_WITH(writer.AddChannel(4, "/x", "cdr"), Catch::Contains("unknown schema id 4"));
    CHECK_THROWS_WITH(writer.Write(3, 0, 0, 0, "", 0), Catch::Contains("unknown channel id 3"));
  }
  SECTION("a compression nobody knows") {
    CHECK_THROWS_WITH(mcap::ParseCompression("gzip"),
                      Catch::Contains("expected zstd, lz4 or none, got 'gzip'"));
    CHECK(mcap::ParseCompression("lz4") == mcap::Compression::kLz4);
  }
}

TEST_CASE("--info describes a session file: channels, counts, rates, attachments, truncation",
          "[mcap]") {
  const fs::path dir = haptel::test::ScratchDir("mcap-info");
  WriteSample(dir / "closed.mcap", mcap::Compression::kLz4, dir / "killed.mcap");
  const std::string text = mcap::DescribeFile(mcap::Reader::Open(dir / "closed.mcap"));
  CHECK_THAT(text, Catch::Contains("/hands/right"));
  CHECK_THAT(text, Catch::Contains("test::Point (omgidl)"));
  // 200 messages on /events over 0.634 s (a late one at 0.965 s to the last at 1.599 s).
  CHECK_THAT(text, Catch::Contains("duration:    0.634 s"));
  CHECK_THAT(text, Catch::Contains("200 msgs    315.46 Hz  json, test::Text (jsonschema)"));
  CHECK_THAT(text, Catch::Contains("lz4"));
  CHECK_THAT(text, Catch::Contains("config/tracks/test-short.yaml"));
  CHECK_THAT(text, Catch::Contains("command_line: haptel run --session x"));
  CHECK_THAT(text, !Catch::Contains("truncated"));
  const mcap::Reader killed = mcap::Reader::Open(dir / "killed.mcap");
  CHECK_THAT(mcap::DescribeFile(killed), Catch::Contains("truncated (not closed)"));
  const std::string json = mcap::DescribeFileJson(killed);
  CHECK_THAT(json, Catch::Contains("\"recovered\":true"));
  CHECK_THAT(json,
             Catch::Contains(
                 "\"topic\":\"/events\",\"message_encoding\":\"json\",\"schema\":\"test::Text\""));
  CHECK(haptel::JsonFieldOf(json, "messages") == "600");
}
