#pragma once
/// @file The MCAP records Haptel reads and writes, as plain values (written
/// from the public specification, https://mcap.dev/spec; major version 0).
/// Times are nanoseconds (MCAP's Timestamp), offsets are bytes from the start
/// of the file.
#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace haptel::mcap {

/// A malformed, corrupt or unreadable MCAP file; the message names the file,
/// the byte offset and what was expected there.
class McapError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// How a chunk's records are compressed: zstd, LZ4 (the frame format) or not.
enum class Compression { kNone, kZstd, kLz4 };
/// The chunk's `compression` field: "", "zstd", "lz4".
std::string_view CompressionName(Compression compression);
/// "none" (or ""), "zstd", "lz4"; anything else throws std::invalid_argument
/// naming the value and the choices.
Compression ParseCompression(std::string_view name);

/// Record opcodes (the specification's table).
enum class Opcode : uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kAttachment = 0x09,
  kAttachmentIndex = 0x0A,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

/// How messages of a channel are described (`omgidl`, `jsonschema`, ...).
struct Schema {
  uint16_t id = 0;  // 0 is reserved: a channel with no schema
  std::string name;
  std::string encoding;
  std::string data;
};

/// A stream of messages: a topic, its encoding (`cdr`, `json`, ...) and schema.
struct Channel {
  uint16_t id = 0;
  uint16_t schema_id = 0;
  std::string topic;
  std::string message_encoding;
  std::map<std::string, std::string> metadata;
};

/// One message as the reader hands it out; `data` points into the reader's
/// buffer and is valid during the callback only.
struct MessageView {
  const Channel* channel = nullptr;
  uint32_t sequence = 0;
  uint64_t log_time_ns = 0;
  uint64_t publish_time_ns = 0;
  const uint8_t* data = nullptr;
  size_t size = 0;
};

/// Counts over the whole file (the Statistics record).
struct Statistics {
  uint64_t message_count = 0;
  uint16_t schema_count = 0;
  uint32_t channel_count = 0;
  uint32_t attachment_count = 0;
  uint32_t metadata_count = 0;
  uint32_t chunk_count = 0;
  uint64_t message_start_time_ns = 0;
  uint64_t message_end_time_ns = 0;
  std::map<uint16_t, uint64_t> channel_message_counts;
};

/// Where a chunk is and what it holds (the ChunkIndex record).
struct ChunkIndex {
  uint64_t message_start_time_ns = 0;
  uint64_t message_end_time_ns = 0;
  uint64_t chunk_start_offset = 0;
  uint64_t chunk_length = 0;  // the whole Chunk record, opcode and length included
  std::map<uint16_t, uint64_t> message_index_offsets;
  uint64_t message_index_length = 0;
  Compression compression = Compression::kNone;
  uint64_t compressed_size = 0;
  uint64_t uncompressed_size = 0;
};

/// A file stored in the recording (a configuration file, a calibration).
struct Attachment {
  uint64_t log_time_ns = 0;
  uint64_t create_time_ns = 0;
  std::string name;
  std::string media_type;
  std::string data;
};

struct AttachmentIndex {
  uint64_t offset = 0;
  uint64_t length = 0;
  uint64_t log_time_ns = 0;
  uint64_t create_time_ns = 0;
  uint64_t data_size = 0;
  std::string name;
  std::string media_type;
};

/// Named key-value pairs (Haptel's version, the command line, the study's
/// participant and condition).
struct Metadata {
  std::string name;
  std::map<std::string, std::string> metadata;
};

struct MetadataIndex {
  uint64_t offset = 0;
  uint64_t length = 0;
  std::string name;
};

/// What the summary section says (or a linear scan rebuilt).
struct Summary {
  std::map<uint16_t, Schema> schemas;
  std::map<uint16_t, Channel> channels;
  Statistics statistics;
  std::vector<ChunkIndex> chunk_indexes;  // in file order
  std::vector<AttachmentIndex> attachment_indexes;
  std::vector<MetadataIndex> metadata_indexes;
};

}  // namespace haptel::mcap
