#pragma once
/// @file Writes an MCAP file: chunked (zstd, LZ4 or none), each chunk followed
/// by its message indexes, then a summary (schemas, channels, statistics,
/// chunk, attachment and metadata indexes) with summary offsets, and the
/// footer. Every CRC the specification defines is written: each chunk's
/// uncompressed CRC, each attachment's, the data section's and the summary's.
///
/// Not for the servo loop: Write copies into the open chunk and compresses
/// it when full (a recorder thread calls it). One thread at a time.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>

#include "haptel/mcap/records.hpp"

namespace haptel::mcap {

struct WriterOptions {
  /// The Header's profile ("" for none; a name such as "haptel").
  std::string profile;
  /// The Header's library: who wrote the file.
  std::string library = "haptel";
  Compression compression = Compression::kZstd;
  /// A chunk is closed (compressed and written) once its uncompressed records
  /// reach this many bytes. Smaller chunks lose less on a crash and seek
  /// finer; larger ones compress better.
  uint64_t chunk_size = 1 << 20;
  /// zstd's level (1: fast, what a live recording wants).
  int zstd_level = 1;
};

class Writer {
 public:
  /// Creates (or truncates) `path` and writes the magic and the Header.
  /// Throws std::runtime_error naming the file when it cannot.
  explicit Writer(const std::filesystem::path& path, WriterOptions options = {});
  /// Closes the file if Close was not called (errors are logged: a destructor
  /// cannot throw; call Close to know).
  ~Writer();
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  /// Registers a schema (written to the data section at once) and returns its
  /// id (1, 2, ...).
  uint16_t AddSchema(std::string name, std::string encoding, std::string data);
  /// Registers a channel on `schema_id` (0: no schema) and returns its id
  /// (0, 1, ...). An unknown schema id throws std::invalid_argument.
  uint16_t AddChannel(uint16_t schema_id, std::string topic, std::string message_encoding,
                      std::map<std::string, std::string> metadata = {});
  /// Appends a message to the open chunk (log times need not be in order).
  /// An unknown channel id throws std::invalid_argument.
  void Write(uint16_t channel_id, uint32_t sequence, uint64_t log_time_ns, uint64_t publish_time_ns,
             const void* data, size_t size);
  /// Stores a file in the data section (outside any chunk), with its CRC.
  void AddAttachment(std::string name, std::string media_type, uint64_t log_time_ns,
                     const void* data, size_t size);
  /// Stores named key-value pairs in the data section.
  void AddMetadata(std::string name, std::map<std::string, std::string> metadata);
  /// Closes the open chunk and hands everything written so far to the
  /// operating system: a SIGKILL after Flush loses nothing before it.
  void Flush();
  /// Closes the open chunk, writes DataEnd, the summary and the footer, syncs
  /// the file to disk and closes it. Idempotent.
  void Close();

  const std::filesystem::path& path() const;
  /// Bytes written to the file so far (the open chunk not included).
  uint64_t bytes_written() const;
  /// What has been written so far (message counts per channel, times).
  const Statistics& statistics() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace haptel::mcap
