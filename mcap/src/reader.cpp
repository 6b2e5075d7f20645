// The MCAP reader: the summary when the file has one, a linear scan of the
// data section when not (a recording killed before Close), so everything
// after Open works from the same in-memory summary.
#include "haptel/mcap/reader.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <queue>
#include <set>
#include <tuple>
#include <utility>

#include "codec.hpp"
#include "haptel/core/unique_fd.hpp"

namespace haptel::mcap {

using detail::Cursor;

namespace {

/// A Chunk record's fields ahead of its records.
struct ChunkHeader {
  uint64_t start_ns = 0, end_ns = 0, uncompressed_size = 0;
  uint32_t uncompressed_crc = 0;
  Compression compression = Compression::kNone;
  const uint8_t* records = nullptr;
  uint64_t records_size = 0;
};

ChunkHeader ParseChunkHeader(Cursor& c, const std::string& where) {
  ChunkHeader h;
  h.start_ns = c.U64();
  h.end_ns = c.U64();
  h.uncompressed_size = c.U64();
  h.uncompressed_crc = c.U32();
  h.compression = detail::CompressionFromField(c.String(), where);
  h.records_size = c.U64();
  h.records = c.Take(h.records_size);
  return h;
}

Schema ParseSchema(Cursor& c) {
  Schema s;
  s.id = c.U16();
  s.name = c.String();
  s.encoding = c.String();
  s.data = c.String();
  return s;
}

Channel ParseChannel(Cursor& c) {
  Channel ch;
  ch.id = c.U16();
  ch.schema_id = c.U16();
  ch.topic = c.String();
  ch.message_encoding = c.String();
  ch.metadata = c.StringMap();
  return ch;
}

std::string At(const std::filesystem::path& path, uint64_t offset) {
  return path.string() + " at byte " + std::to_string(offset);
}

/// Calls visit(opcode, content, size, offset) for each record of `records`
/// (a chunk's uncompressed records); a record running past the end throws.
template <class Visit>
void ForEachRecord(const uint8_t* records, size_t size, const std::string& where, Visit&& visit) {
  size_t at = 0;
  while (at < size) {
    if (size - at < detail::kRecordPrefix) {
      throw McapError(where + ": a record's header is cut at byte " + std::to_string(at) +
                      " of the chunk");
    }
    const uint8_t opcode = records[at];
    uint64_t length;
    std::memcpy(&length, records + at + 1, 8);
    if (length > size - at - detail::kRecordPrefix) {
      throw McapError(where + ": a record of " + std::to_string(length) + " bytes at byte " +
                      std::to_string(at) + " of the chunk runs past its end");
    }
    visit(opcode, records + at + detail::kRecordPrefix, length, at);
    at += detail::kRecordPrefix + length;
  }
}

}  // namespace

struct Reader::Impl {
  std::filesystem::path path;
  UniqueFd fd;
  uint64_t file_size = 0;
  Summary summary;
  std::string profile, library;
  Loss loss;
  bool has_footer = false;
  uint64_t data_end_offset = 0;  // where DataEnd starts (0: none found)
  uint64_t summary_start = 0, summary_offset_start = 0;
  uint32_t summary_crc = 0;
  mutable detail::Codec codec;

  void ReadAt(uint64_t offset, void* out, size_t size) const {
    size_t done = 0;
    while (done < size) {
      const ssize_t n = ::pread(fd.get(), static_cast<char*>(out) + done, size - done,
                                static_cast<off_t>(offset + done));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        throw McapError(At(path, offset + done) + ": cannot read " + std::to_string(size - done) +
                        " bytes" + (n < 0 ? std::string(": ") + std::strerror(errno) : ""));
      }
      done += static_cast<size_t>(n);
    }
  }
  std::string ReadString(uint64_t offset, size_t size) const {
    std::string out(size, '\0');
    ReadAt(offset, out.data(), size);
    return out;
  }

  /// A whole record at `offset` with the expected opcode; returns its content.
  std::string ReadRecord(uint64_t offset, uint64_t length, Opcode expected) const {
    if (offset + length > file_size || length < detail::kRecordPrefix) {
      throw McapError(At(path, offset) + ": an index points past the end of the file");
    }
    std::string record = ReadString(offset, length);
    uint64_t content;
    std::memcpy(&content, record.data() + 1, 8);
    if (static_cast<uint8_t>(record[0]) != static_cast<uint8_t>(expected) ||
        content != length - detail::kRecordPrefix) {
      throw McapError(At(path, offset) + ": expected a record of opcode " +
                      std::to_string(static_cast<int>(expected)) + " and length " +
                      std::to_string(length) + " as the index says");
    }
    return record.substr(detail::kRecordPrefix);
  }

  /// The chunk's records, decompressed and checked against its CRC.
  void LoadChunk(const std::string& content, const std::string& where, std::string& out,
                 ChunkHeader* header_out = nullptr) const {
    Cursor c(reinterpret_cast<const uint8_t*>(content.data()), content.size(), where);
    const ChunkHeader h = ParseChunkHeader(c, where);
    codec.Decompress(h.compression, h.records, h.records_size, h.uncompressed_size, out, where);
    if (h.uncompressed_crc != 0) {
      const uint32_t crc = detail::Crc32Of(out.data(), out.size());
      if (crc != h.uncompressed_crc) {
        throw McapError(where + ": chunk CRC mismatch (stored " +
                        std::to_string(h.uncompressed_crc) + ", computed " + std::to_string(crc) +
                        "): the chunk is corrupt");
      }
    }
    if (header_out != nullptr) *header_out = h;
  }

  void Open() {
    fd.reset(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
    if (!fd) throw McapError(path.string() + ": cannot open: " + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd.get(), &st) != 0) {
      throw McapError(path.string() + ": cannot stat: " + std::strerror(errno));
    }
    file_size = static_cast<uint64_t>(st.st_size);
    uint8_t magic[8]{};
    if (file_size < 8 || (ReadAt(0, magic, 8), std::memcmp(magic, detail::kMagic, 8) != 0)) {
      throw McapError(path.string() +
                      ": not an MCAP file (expected the magic 89 4D 43 41 50 30 0D 0A at byte 0)");
    }
    ReadFooter();
    if (has_footer && summary_start != 0) {
      ReadHeader();
      ReadSummary();
    } else {
      Scan();
    }
  }

  void ReadHeader() {
    if (file_size < 8 + detail::kRecordPrefix) return;
    std::string prefix = ReadString(8, detail::kRecordPrefix);
    uint64_t length;
    std::memcpy(&length, prefix.data() + 1, 8);
    if (prefix[0] != static_cast<char>(Opcode::kHeader) ||
        length > file_size - 8 - detail::kRecordPrefix) {
      throw McapError(At(path, 8) + ": expected the Header record");
    }
    const std::string content = ReadString(8 + detail::kRecordPrefix, length);
    const std::string where = At(path, 8) + " (Header)";
    Cursor c(reinterpret_cast<const uint8_t*>(content.data()), content.size(), where);
    profile = c.String();
    library = c.String();
  }

  void ReadFooter() {
    if (file_size < 8 + detail::kFooterRecord + 8) return;
    const uint64_t footer_at = file_size - 8 - detail::kFooterRecord;
    std::string tail = ReadString(footer_at, detail::kFooterRecord + 8);
    if (std::memcmp(tail.data() + detail::kFooterRecord, detail::kMagic, 8) != 0) return;
    uint64_t length;
    std::memcpy(&length, tail.data() + 1, 8);
    if (tail[0] != static_cast<char>(Opcode::kFooter) || length != detail::kFooterContent) return;
    const std::string where = At(path, footer_at) + " (Footer)";
    Cursor c(reinterpret_cast<const uint8_t*>(tail.data()) + detail::kRecordPrefix,
             detail::kFooterContent, where);
    summary_start = c.U64();
    summary_offset_start = c.U64();
    summary_crc = c.U32();
    if (summary_start > footer_at || summary_offset_start > footer_at) {
      throw McapError(where + ": the summary offsets point past the footer");
    }
    has_footer = true;
  }

  void ReadSummary() {
    const uint64_t footer_at = file_size - 8 - detail::kFooterRecord;
    const std::string section = ReadString(summary_start, footer_at - summary_start);
    const auto* bytes = reinterpret_cast<const uint8_t*>(section.data());
    size_t at = 0;
    bool statistics_seen = false;
    while (at < section.size()) {
      const std::string where = At(path, summary_start + at);
      Cursor prefix(bytes + at, section.size() - at, where);
      const uint8_t opcode = prefix.U8();
      const uint64_t length = prefix.U64();
      Cursor c(prefix.Take(length), length, where);
      switch (static_cast<Opcode>(opcode)) {
        case Opcode::kSchema: {
          Schema s = ParseSchema(c);
          summary.schemas[s.id] = std::move(s);
          break;
        }
        case Opcode::kChannel: {
          Channel ch = ParseChannel(c);
          summary.channels[ch.id] = std::move(ch);
          break;
        }
        case Opcode::kStatistics: {
          Statistics& s = summary.statistics;
          s.message_count = c.U64();
          s.schema_count = c.U16();
          s.channel_count = c.U32();
          s.attachment_count = c.U32();
          s.metadata_count = c.U32();
          s.chunk_count = c.U32();
          s.message_start_time_ns = c.U64();
          s.message_end_time_ns = c.U64();
          s.channel_message_counts = c.U16U64Map();
          statistics_seen = true;
          break;
        }
        case Opcode::kChunkIndex: {
          ChunkIndex ci;
          ci.message_start_time_ns = c.U64();
          ci.message_end_time_ns = c.U64();
          ci.chunk_start_offset = c.U64();
          ci.chunk_length = c.U64();
          ci.message_index_offsets = c.U16U64Map();
          ci.message_index_length = c.U64();
          ci.compression = detail::CompressionFromField(c.String(), where);
          ci.compressed_size = c.U64();
          ci.uncompressed_size = c.U64();
          summary.chunk_indexes.push_back(std::move(ci));
          break;
        }
        case Opcode::kAttachmentIndex: {
          AttachmentIndex ai;
          ai.offset = c.U64();
          ai.length = c.U64();
          ai.log_time_ns = c.U64();
          ai.create_time_ns = c.U64();
          ai.data_size = c.U64();
          ai.name = c.String();
          ai.media_type = c.String();
          summary.attachment_indexes.push_back(std::move(ai));
          break;
        }
        case Opcode::kMetadataIndex: {
          MetadataIndex mi;
          mi.offset = c.U64();
          mi.length = c.U64();
          mi.name = c.String();
          summary.metadata_indexes.push_back(std::move(mi));
          break;
        }
        default:
          break;  // SummaryOffset and records this reader does not need
      }
      at += detail::kRecordPrefix + length;
    }
    if (summary_start >= 13) {
      // DataEnd (13 bytes) closes the data section just before the summary.
      std::string data_end = ReadString(summary_start - 13, 1);
      if (data_end[0] == static_cast<char>(Opcode::kDataEnd)) data_end_offset = summary_start - 13;
    }
    if (!statistics_seen) RebuildStatistics();
  }

  /// Statistics from the chunk indexes when the summary has none: counts need
  /// the message indexes, so every chunk is read (only for foreign files).
  void RebuildStatistics() {
    Statistics& s = summary.statistics;
    s = {};
    s.schema_count = static_cast<uint16_t>(summary.schemas.size());
    s.channel_count = static_cast<uint32_t>(summary.channels.size());
    s.attachment_count = static_cast<uint32_t>(summary.attachment_indexes.size());
    s.metadata_count = static_cast<uint32_t>(summary.metadata_indexes.size());
    s.chunk_count = static_cast<uint32_t>(summary.chunk_indexes.size());
    std::string records;
    for (const ChunkIndex& ci : summary.chunk_indexes) {
      const std::string where = At(path, ci.chunk_start_offset) + " (Chunk)";
      LoadChunk(ReadRecord(ci.chunk_start_offset, ci.chunk_length, Opcode::kChunk), where, records);
      CountMessages(records, where);
    }
  }

  void CountMessages(const std::string& records, const std::string& where) {
    Statistics& s = summary.statistics;
    ForEachRecord(reinterpret_cast<const uint8_t*>(records.data()), records.size(), where,
                  [&](uint8_t opcode, const uint8_t* content, uint64_t size, size_t) {
                    if (opcode == static_cast<uint8_t>(Opcode::kSchema)) {
                      Cursor c(content, size, where);
                      Schema schema = ParseSchema(c);
                      summary.schemas.try_emplace(schema.id, std::move(schema));
                      return;
                    }
                    if (opcode == static_cast<uint8_t>(Opcode::kChannel)) {
                      Cursor c(content, size, where);
                      Channel channel = ParseChannel(c);
                      summary.channels.try_emplace(channel.id, std::move(channel));
                      return;
                    }
                    if (opcode != static_cast<uint8_t>(Opcode::kMessage)) return;
                    Cursor c(content, size, where);
                    const uint16_t channel = c.U16();
                    c.U32();
                    const uint64_t time = c.U64();
                    if (s.message_count == 0) {
                      s.message_start_time_ns = s.message_end_time_ns = time;
                    } else {
                      s.message_start_time_ns = std::min(s.message_start_time_ns, time);
                      s.message_end_time_ns = std::max(s.message_end_time_ns, time);
                    }
                    ++s.message_count;
                    ++s.channel_message_counts[channel];
                  });
  }

  /// Reads the data section record by record: what is whole is kept, a torn
  /// tail (or a chunk failing its CRC) is counted and skipped.
  void Scan() {
    loss.truncated = !has_footer;
    std::string records;
    uint64_t at = 8;
    bool header_seen = false;
    auto torn = [&](uint64_t from, bool chunk) {
      loss.bytes_lost += file_size - from;
      if (chunk) ++loss.chunks_lost;
    };
    while (at < file_size) {
      if (file_size - at < detail::kRecordPrefix) {  // cut inside a record's opcode and length
        uint8_t opcode = 0;
        ReadAt(at, &opcode, 1);
        torn(at, opcode == static_cast<uint8_t>(Opcode::kChunk));
        break;
      }
      uint8_t prefix[detail::kRecordPrefix];
      ReadAt(at, prefix, sizeof prefix);
      uint64_t length;
      std::memcpy(&length, prefix + 1, 8);
      const auto opcode = static_cast<Opcode>(prefix[0]);
      if (length > file_size - at - detail::kRecordPrefix) {
        torn(at, opcode == Opcode::kChunk);
        break;
      }
      const uint64_t record_length = detail::kRecordPrefix + length;
      const std::string where = At(path, at);
      if (opcode == Opcode::kDataEnd) {
        data_end_offset = at;
        break;
      }
      if (!header_seen && opcode != Opcode::kHeader) {
        throw McapError(At(path, 8) + ": expected the Header record");
      }
      if (opcode == Opcode::kFooter) break;  // a footer with no summary
      const std::string content = ReadString(at + detail::kRecordPrefix, length);
      Cursor c(reinterpret_cast<const uint8_t*>(content.data()), content.size(), where);
      switch (opcode) {
        case Opcode::kHeader:
          profile = c.String();
          library = c.String();
          header_seen = true;
          break;
        case Opcode::kSchema: {
          Schema s = ParseSchema(c);
          summary.schemas[s.id] = std::move(s);
          break;
        }
        case Opcode::kChannel: {
          Channel ch = ParseChannel(c);
          summary.channels[ch.id] = std::move(ch);
          break;
        }
        case Opcode::kChunk: {
          ChunkHeader h;
          try {
            LoadChunk(content, where + " (Chunk)", records, &h);
          } catch (const McapError&) {
            ++loss.chunks_lost;
            loss.bytes_lost += record_length;
            break;
          }
          ChunkIndex ci;
          ci.message_start_time_ns = h.start_ns;
          ci.message_end_time_ns = h.end_ns;
          ci.chunk_start_offset = at;
          ci.chunk_length = record_length;
          ci.compression = h.compression;
          ci.compressed_size = h.records_size;
          ci.uncompressed_size = h.uncompressed_size;
          summary.chunk_indexes.push_back(std::move(ci));
          CountMessages(records, where + " (Chunk)");
          break;
        }
        case Opcode::kAttachment: {
          AttachmentIndex ai;
          ai.offset = at;
          ai.length = record_length;
          ai.log_time_ns = c.U64();
          ai.create_time_ns = c.U64();
          ai.name = c.String();
          ai.media_type = c.String();
          ai.data_size = c.U64();
          summary.attachment_indexes.push_back(std::move(ai));
          break;
        }
        case Opcode::kMetadata:
          summary.metadata_indexes.push_back({at, record_length, c.String()});
          break;
        default:
          break;  // message indexes (rebuilt on demand), records outside chunks
      }
      at += record_length;
    }
    Statistics& s = summary.statistics;
    s.schema_count = static_cast<uint16_t>(summary.schemas.size());
    s.channel_count = static_cast<uint32_t>(summary.channels.size());
    s.attachment_count = static_cast<uint32_t>(summary.attachment_indexes.size());
    s.metadata_count = static_cast<uint32_t>(summary.metadata_indexes.size());
    s.chunk_count = static_cast<uint32_t>(summary.chunk_indexes.size());
    for (const auto& [id, channel] : summary.channels) s.channel_message_counts.try_emplace(id, 0);
    if (loss.truncated || loss.bytes_lost > 0) {
      loss.what = std::string(loss.truncated ? "truncated (not closed): " : "damaged: ") +
                  "read by a scan; " + std::to_string(loss.bytes_lost) + " bytes lost at the end" +
                  (loss.chunks_lost > 0 ? " (" + std::to_string(loss.chunks_lost) + " chunk" +
                                              (loss.chunks_lost == 1 ? "" : "s") + ")"
                                        : "");
    }
  }
};

Reader Reader::Open(const std::filesystem::path& path) {
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->Open();
  return Reader(std::move(impl));
}

Reader::Reader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Reader::~Reader() = default;
Reader::Reader(Reader&&) noexcept = default;
Reader& Reader::operator=(Reader&&) noexcept = default;

const std::filesystem::path& Reader::path() const { return impl_->path; }
const Summary& Reader::summary() const { return impl_->summary; }
const std::map<uint16_t, Channel>& Reader::channels() const { return impl_->summary.channels; }
const std::map<uint16_t, Schema>& Reader::schemas() const { return impl_->summary.schemas; }
const Statistics& Reader::statistics() const { return impl_->summary.statistics; }
const std::string& Reader::profile() const { return impl_->profile; }
const std::string& Reader::library() const { return impl_->library; }
bool Reader::recovered() const { return impl_->loss.truncated; }
const Loss& Reader::loss() const { return impl_->loss; }

void Reader::ForEachMessage(uint64_t start_ns, uint64_t end_ns,
                            const std::vector<std::string>& topics,
                            const std::function<void(const MessageView&)>& callback) const {
  const Impl& r = *impl_;
  std::set<uint16_t> wanted;
  for (const auto& [id, channel] : r.summary.channels) {
    if (topics.empty() || std::find(topics.begin(), topics.end(), channel.topic) != topics.end()) {
      wanted.insert(id);
    }
  }
  if (wanted.empty() || start_ns >= end_ns) return;
  // The chunks whose time span meets [start, end), by start time: a chunk is
  // read only once every message before its start has been handed out.
  std::vector<const ChunkIndex*> chunks;
  for (const ChunkIndex& ci : r.summary.chunk_indexes) {
    if (ci.message_end_time_ns >= start_ns && ci.message_start_time_ns < end_ns) {
      bool any = ci.message_index_offsets.empty();  // rebuilt by a scan: not known
      for (const auto& [id, offset] : ci.message_index_offsets) any = any || wanted.count(id) > 0;
      if (any) chunks.push_back(&ci);
    }
  }
  std::stable_sort(chunks.begin(), chunks.end(), [](const ChunkIndex* a, const ChunkIndex* b) {
    return a->message_start_time_ns < b->message_start_time_ns;
  });

  struct Pending {
    uint64_t log_time;
    size_t chunk;   // order of the chunk in the file
    size_t offset;  // of the record in the chunk's records
    size_t slot;    // where the chunk's records are held
    bool operator>(const Pending& o) const {
      return std::tie(log_time, chunk, offset) > std::tie(o.log_time, o.chunk, o.offset);
    }
  };
  struct Loaded {
    std::string records;
    size_t remaining = 0;
  };
  std::priority_queue<Pending, std::vector<Pending>, std::greater<>> heap;
  std::vector<Loaded> slots;
  std::vector<size_t> free_slots;
  const ChunkIndex* first = r.summary.chunk_indexes.data();

  auto load = [&](const ChunkIndex& ci) {
    size_t slot;
    if (!free_slots.empty()) {
      slot = free_slots.back();
      free_slots.pop_back();
    } else {
      slot = slots.size();
      slots.emplace_back();
    }
    Loaded& loaded = slots[slot];
    const std::string where = At(r.path, ci.chunk_start_offset) + " (Chunk)";
    r.LoadChunk(r.ReadRecord(ci.chunk_start_offset, ci.chunk_length, Opcode::kChunk), where,
                loaded.records);
    loaded.remaining = 0;
    const size_t order = static_cast<size_t>(&ci - first);
    ForEachRecord(reinterpret_cast<const uint8_t*>(loaded.records.data()), loaded.records.size(),
                  where, [&](uint8_t opcode, const uint8_t* content, uint64_t size, size_t at) {
                    if (opcode != static_cast<uint8_t>(Opcode::kMessage) || size < 22) return;
                    uint16_t channel;
                    uint64_t time;
                    std::memcpy(&channel, content, 2);
                    std::memcpy(&time, content + 6, 8);
                    if (time < start_ns || time >= end_ns || wanted.count(channel) == 0) return;
                    heap.push({time, order, at, slot});
                    ++loaded.remaining;
                  });
    if (loaded.remaining == 0) {
      loaded.records.clear();
      free_slots.push_back(slot);
    }
  };

  size_t next = 0;
  while (true) {
    while (next < chunks.size() &&
           (heap.empty() || chunks[next]->message_start_time_ns <= heap.top().log_time)) {
      load(*chunks[next++]);
    }
    if (heap.empty()) break;
    const Pending p = heap.top();
    heap.pop();
    Loaded& loaded = slots[p.slot];
    const uint8_t* record = reinterpret_cast<const uint8_t*>(loaded.records.data()) + p.offset;
    uint64_t length;
    std::memcpy(&length, record + 1, 8);
    const uint8_t* content = record + detail::kRecordPrefix;
    MessageView view;
    uint16_t channel_id;
    std::memcpy(&channel_id, content, 2);
    std::memcpy(&view.sequence, content + 2, 4);
    std::memcpy(&view.log_time_ns, content + 6, 8);
    std::memcpy(&view.publish_time_ns, content + 14, 8);
    view.channel = &r.summary.channels.at(channel_id);
    view.data = content + 22;
    view.size = length - 22;
    callback(view);
    if (--loaded.remaining == 0) {
      loaded.records.clear();
      free_slots.push_back(p.slot);
    }
  }
}

Attachment Reader::ReadAttachment(const AttachmentIndex& index) const {
  const std::string where = At(impl_->path, index.offset) + " (Attachment)";
  const std::string content = impl_->ReadRecord(index.offset, index.length, Opcode::kAttachment);
  Cursor c(reinterpret_cast<const uint8_t*>(content.data()), content.size(), where);
  Attachment a;
  a.log_time_ns = c.U64();
  a.create_time_ns = c.U64();
  a.name = c.String();
  a.media_type = c.String();
  const uint64_t size = c.U64();
  a.data.assign(reinterpret_cast<const char*>(c.Take(size)), size);
  const size_t crc_at = c.at();
  const uint32_t stored = c.U32();
  if (stored != 0) {
    const uint32_t crc = detail::Crc32Of(content.data(), crc_at);
    if (crc != stored) {
      throw McapError(where + ": attachment '" + a.name + "' CRC mismatch (stored " +
                      std::to_string(stored) + ", computed " + std::to_string(crc) +
                      "): it is corrupt");
    }
  }
  return a;
}

Metadata Reader::ReadMetadata(const MetadataIndex& index) const {
  const std::string where = At(impl_->path, index.offset) + " (Metadata)";
  const std::string content = impl_->ReadRecord(index.offset, index.length, Opcode::kMetadata);
  Cursor c(reinterpret_cast<const uint8_t*>(content.data()), content.size(), where);
  Metadata m;
  m.name = c.String();
  m.metadata = c.StringMap();
  return m;
}

std::vector<std::string> Reader::Verify() const {
  const Impl& r = *impl_;
  std::vector<std::string> problems;
  auto check = [&](auto&& step) {
    try {
      step();
    } catch (const std::exception& e) {
      problems.push_back(e.what());
    }
  };
  if (r.loss.truncated || r.loss.bytes_lost > 0)
    problems.push_back(r.path.string() + ": " + r.loss.what);
  // The data section's CRC, streamed (the file may be larger than memory).
  if (r.data_end_offset != 0) {
    check([&] {
      const std::string where = At(r.path, r.data_end_offset) + " (DataEnd)";
      const std::string content =
          r.ReadRecord(r.data_end_offset, detail::kRecordPrefix + 4, Opcode::kDataEnd);
      uint32_t stored;
      std::memcpy(&stored, content.data(), 4);
      if (stored == 0) return;
      detail::Crc32 crc;
      std::string block;
      for (uint64_t at = 0; at < r.data_end_offset; at += 1 << 20) {
        block = r.ReadString(at, std::min<uint64_t>(1 << 20, r.data_end_offset - at));
        crc.Update(block);
      }
      if (crc.value() != stored) {
        throw McapError(where + ": data section CRC mismatch (stored " + std::to_string(stored) +
                        ", computed " + std::to_string(crc.value()) + ")");
      }
    });
  }
  if (r.has_footer && r.summary_start != 0 && r.summary_crc != 0) {
    check([&] {
      const uint64_t footer_at = r.file_size - 8 - detail::kFooterRecord;
      const std::string bytes =
          r.ReadString(r.summary_start, footer_at - r.summary_start + detail::kRecordPrefix + 16);
      const uint32_t crc = detail::Crc32Of(bytes.data(), bytes.size());
      if (crc != r.summary_crc) {
        throw McapError(At(r.path, r.summary_start) + ": summary CRC mismatch (stored " +
                        std::to_string(r.summary_crc) + ", computed " + std::to_string(crc) + ")");
      }
    });
  }
  std::string records;
  uint64_t messages = 0;
  for (const ChunkIndex& ci : r.summary.chunk_indexes) {
    check([&] {
      const std::string where = At(r.path, ci.chunk_start_offset) + " (Chunk)";
      r.LoadChunk(r.ReadRecord(ci.chunk_start_offset, ci.chunk_length, Opcode::kChunk), where,
                  records);
      std::map<uint64_t, std::pair<uint16_t, uint64_t>> by_offset;  // offset -> channel, time
      ForEachRecord(reinterpret_cast<const uint8_t*>(records.data()), records.size(), where,
                    [&](uint8_t opcode, const uint8_t* content, uint64_t size, size_t at) {
                      if (opcode != static_cast<uint8_t>(Opcode::kMessage)) return;
                      Cursor c(content, size, where);
                      const uint16_t channel = c.U16();
                      c.U32();
                      by_offset[at] = {channel, c.U64()};
                      ++messages;
                    });
      // Each message index entry names a message of its channel at its time.
      for (const auto& [channel, offset] : ci.message_index_offsets) {
        const std::string index_where = At(r.path, offset) + " (MessageIndex)";
        std::string prefix = r.ReadString(offset, detail::kRecordPrefix);
        uint64_t length;
        std::memcpy(&length, prefix.data() + 1, 8);
        const std::string content =
            r.ReadRecord(offset, detail::kRecordPrefix + length, Opcode::kMessageIndex);
        Cursor c(reinterpret_cast<const uint8_t*>(content.data()), content.size(), index_where);
        if (c.U16() != channel) throw McapError(index_where + ": indexes another channel");
        const uint32_t bytes = c.U32();
        for (uint32_t i = 0; i < bytes / 16; ++i) {
          const uint64_t time = c.U64();
          const uint64_t at = c.U64();
          const auto found = by_offset.find(at);
          if (found == by_offset.end() || found->second != std::make_pair(channel, time)) {
            throw McapError(index_where + ": entry " + std::to_string(i) +
                            " does not point at its message");
          }
        }
      }
    });
  }
  if (messages != r.summary.statistics.message_count) {
    problems.push_back(r.path.string() + ": the statistics count " +
                       std::to_string(r.summary.statistics.message_count) +
                       " messages, the chunks hold " + std::to_string(messages));
  }
  for (const AttachmentIndex& ai : r.summary.attachment_indexes) {
    check([&] { ReadAttachment(ai); });
  }
  return problems;
}

}  // namespace haptel::mcap
