#pragma once
/// @file Reads an MCAP file. Open uses the summary section when the file has
/// one; a file without (a recording killed before Close) is scanned from the
/// start: every complete chunk is read, a torn last record is counted and
/// skipped, and the summary is rebuilt in memory, so reading afterwards is the
/// same either way.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "haptel/mcap/records.hpp"

namespace haptel::mcap {

/// What Open found missing or damaged (all zero for a complete file).
struct Loss {
  bool truncated = false;    // no footer: the file was not closed
  uint64_t bytes_lost = 0;   // the torn tail (and damaged chunks) skipped
  uint32_t chunks_lost = 0;  // chunks skipped: torn, or failing their CRC
  std::string what;          // a sentence for the user; empty when nothing was lost
};

class Reader {
 public:
  /// Opens `path`; throws McapError (naming the file) when it is not MCAP or
  /// its summary is malformed.
  static Reader Open(const std::filesystem::path& path);
  ~Reader();
  Reader(Reader&&) noexcept;
  Reader& operator=(Reader&&) noexcept;

  const std::filesystem::path& path() const;
  const Summary& summary() const;
  const std::map<uint16_t, Channel>& channels() const;
  const std::map<uint16_t, Schema>& schemas() const;
  const Statistics& statistics() const;
  /// The Header's profile and library.
  const std::string& profile() const;
  const std::string& library() const;
  /// True when the file had to be scanned because it was not closed (no
  /// summary, no footer); loss() says what was lost.
  bool recovered() const;
  const Loss& loss() const;

  /// Calls `callback` for every message with log time in [start_ns, end_ns)
  /// on one of `topics` (empty: all), in log-time order (ties in file order).
  /// Only the chunks whose time range meets the interval are read, found by
  /// the chunk indexes. A chunk failing its CRC throws McapError.
  void ForEachMessage(uint64_t start_ns, uint64_t end_ns, const std::vector<std::string>& topics,
                      const std::function<void(const MessageView&)>& callback) const;
  /// Every message, in log-time order.
  void ForEachMessage(const std::function<void(const MessageView&)>& callback) const {
    ForEachMessage(0, std::numeric_limits<uint64_t>::max(), {}, callback);
  }

  /// The attachment an index points at (its CRC checked: McapError if bad).
  Attachment ReadAttachment(const AttachmentIndex& index) const;
  Metadata ReadMetadata(const MetadataIndex& index) const;

  /// Reads the whole file and checks every CRC it carries (the data
  /// section's, the summary's, each chunk's, each attachment's) and that the
  /// indexes point at what they say. Returns one line per problem (empty:
  /// the file is sound).
  std::vector<std::string> Verify() const;

 private:
  struct Impl;
  explicit Reader(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace haptel::mcap
