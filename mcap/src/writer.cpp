// The MCAP writer: records go to a buffer that is written to the file when a
// chunk closes (or past 64 KiB), so the file only ever grows by whole records
// and a process killed between two writes leaves a scannable prefix.
#include "haptel/mcap/writer.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

#include "codec.hpp"
#include "haptel/core/log.hpp"
#include "haptel/core/unique_fd.hpp"

namespace haptel::mcap {

using detail::Bytes;

struct Writer::Impl {
  std::filesystem::path path;
  WriterOptions options;
  UniqueFd fd;
  bool closed = false;

  uint64_t file_offset = 0;  // bytes handed to the file
  std::string pending;       // whole records not yet handed to the file
  detail::Crc32 data_crc;    // over the data section, magic included

  std::map<uint16_t, Schema> schemas;
  std::map<uint16_t, Channel> channels;
  Statistics statistics;
  std::vector<ChunkIndex> chunk_indexes;
  std::vector<AttachmentIndex> attachment_indexes;
  std::vector<MetadataIndex> metadata_indexes;

  // The open chunk: its records uncompressed, its time span, and per channel
  // (log time, offset in the records) for its message indexes.
  std::string chunk_records;
  uint64_t chunk_start_ns = std::numeric_limits<uint64_t>::max();
  uint64_t chunk_end_ns = 0;
  std::map<uint16_t, std::vector<std::pair<uint64_t, uint64_t>>> chunk_message_index;
  std::string compressed;  // reused
  detail::Codec codec;

  std::string Where() const { return path.string(); }

  uint64_t position() const { return file_offset + pending.size(); }

  /// Appends whole records of the data section.
  void AppendData(std::string_view records) {
    data_crc.Update(records);
    pending.append(records);
  }

  void WriteOut() {
    size_t done = 0;
    while (done < pending.size()) {
      const ssize_t n = ::write(fd.get(), pending.data() + done, pending.size() - done);
      if (n < 0) {
        if (errno == EINTR) continue;
        throw std::runtime_error(Where() +
                                 ": cannot write the session file: " + std::strerror(errno));
      }
      done += static_cast<size_t>(n);
    }
    file_offset += pending.size();
    pending.clear();
  }

  void CheckOpen(const char* what) const {
    if (closed) throw std::logic_error(Where() + ": " + what + " after Close");
  }

  void CloseChunk() {
    if (chunk_records.empty()) return;
    const bool has_messages = !chunk_message_index.empty();
    if (!has_messages) chunk_start_ns = chunk_end_ns = 0;
    codec.Compress(options.compression, options.zstd_level, chunk_records, compressed);
    const uint64_t chunk_start = position();
    std::string record;
    record.reserve(compressed.size() + 64);
    Bytes out(record);
    const size_t length_at = out.Begin(Opcode::kChunk);
    out.U64(chunk_start_ns);
    out.U64(chunk_end_ns);
    out.U64(chunk_records.size());
    out.U32(detail::Crc32Of(chunk_records.data(), chunk_records.size()));
    out.String(CompressionName(options.compression));
    out.U64(compressed.size());
    out.Raw(compressed.data(), compressed.size());
    out.End(length_at);
    const uint64_t chunk_length = record.size();

    ChunkIndex index;
    index.message_start_time_ns = chunk_start_ns;
    index.message_end_time_ns = chunk_end_ns;
    index.chunk_start_offset = chunk_start;
    index.chunk_length = chunk_length;
    index.compression = options.compression;
    index.compressed_size = compressed.size();
    index.uncompressed_size = chunk_records.size();
    // The message indexes follow the chunk, one per channel, each in log-time
    // order (stable: ties keep the order written).
    for (auto& [channel_id, entries] : chunk_message_index) {
      std::stable_sort(entries.begin(), entries.end(),
                       [](const auto& a, const auto& b) { return a.first < b.first; });
      index.message_index_offsets[channel_id] = chunk_start + record.size();
      const size_t at = out.Begin(Opcode::kMessageIndex);
      out.U16(channel_id);
      out.U32(static_cast<uint32_t>(entries.size() * 16));
      for (const auto& [time, offset] : entries) {
        out.U64(time);
        out.U64(offset);
      }
      out.End(at);
    }
    index.message_index_length = record.size() - chunk_length;
    AppendData(record);
    chunk_indexes.push_back(std::move(index));
    ++statistics.chunk_count;

    chunk_records.clear();
    chunk_message_index.clear();
    chunk_start_ns = std::numeric_limits<uint64_t>::max();
    chunk_end_ns = 0;
    WriteOut();
  }

  void Finish() {
    CloseChunk();
    std::string data_end;
    Bytes d(data_end);
    const size_t at = d.Begin(Opcode::kDataEnd);
    d.U32(data_crc.value());
    d.End(at);
    pending.append(data_end);

    // The summary: each kind of record in its own group, a SummaryOffset
    // record per group, then the footer and the closing magic.
    const uint64_t summary_start = position();
    std::string summary;
    Bytes s(summary);
    std::vector<std::pair<Opcode, std::pair<uint64_t, uint64_t>>> groups;
    auto group = [&](Opcode opcode, auto&& write_all) {
      const size_t begin = summary.size();
      write_all();
      if (summary.size() > begin) {
        groups.push_back({opcode, {summary_start + begin, summary.size() - begin}});
      }
    };
    group(Opcode::kSchema, [&] {
      for (const auto& [id, schema] : schemas) WriteSchema(s, schema);
    });
    group(Opcode::kChannel, [&] {
      for (const auto& [id, channel] : channels) WriteChannel(s, channel);
    });
    group(Opcode::kStatistics, [&] {
      const size_t r = s.Begin(Opcode::kStatistics);
      const Statistics& st = statistics;
      s.U64(st.message_count);
      s.U16(st.schema_count);
      s.U32(st.channel_count);
      s.U32(st.attachment_count);
      s.U32(st.metadata_count);
      s.U32(st.chunk_count);
      s.U64(st.message_start_time_ns);
      s.U64(st.message_end_time_ns);
      s.U16U64Map(st.channel_message_counts);
      s.End(r);
    });
    group(Opcode::kChunkIndex, [&] {
      for (const ChunkIndex& c : chunk_indexes) {
        const size_t r = s.Begin(Opcode::kChunkIndex);
        s.U64(c.message_start_time_ns);
        s.U64(c.message_end_time_ns);
        s.U64(c.chunk_start_offset);
        s.U64(c.chunk_length);
        s.U16U64Map(c.message_index_offsets);
        s.U64(c.message_index_length);
        s.String(CompressionName(c.compression));
        s.U64(c.compressed_size);
        s.U64(c.uncompressed_size);
        s.End(r);
      }
    });
    group(Opcode::kAttachmentIndex, [&] {
      for (const AttachmentIndex& a : attachment_indexes) {
        const size_t r = s.Begin(Opcode::kAttachmentIndex);
        s.U64(a.offset);
        s.U64(a.length);
        s.U64(a.log_time_ns);
        s.U64(a.create_time_ns);
        s.U64(a.data_size);
        s.String(a.name);
        s.String(a.media_type);
        s.End(r);
      }
    });
    group(Opcode::kMetadataIndex, [&] {
      for (const MetadataIndex& m : metadata_indexes) {
        const size_t r = s.Begin(Opcode::kMetadataIndex);
        s.U64(m.offset);
        s.U64(m.length);
        s.String(m.name);
        s.End(r);
      }
    });
    const uint64_t summary_offset_start = summary_start + summary.size();
    for (const auto& [opcode, span] : groups) {
      const size_t r = s.Begin(Opcode::kSummaryOffset);
      s.U8(static_cast<uint8_t>(opcode));
      s.U64(span.first);
      s.U64(span.second);
      s.End(r);
    }
    // The footer's CRC covers the summary, the summary offsets and the
    // footer's own fields up to the CRC.
    s.U8(static_cast<uint8_t>(Opcode::kFooter));
    s.U64(detail::kFooterContent);
    s.U64(summary_start);
    s.U64(summary_offset_start);
    s.U32(detail::Crc32Of(summary.data(), summary.size()));
    s.Raw(detail::kMagic, sizeof detail::kMagic);
    pending.append(summary);
    WriteOut();
    if (::fsync(fd.get()) != 0) {
      throw std::runtime_error(Where() +
                               ": cannot sync the session file to disk: " + std::strerror(errno));
    }
    if (::close(fd.release()) != 0) {
      throw std::runtime_error(Where() +
                               ": cannot close the session file: " + std::strerror(errno));
    }
  }

  static void WriteSchema(Bytes& out, const Schema& schema) {
    const size_t r = out.Begin(Opcode::kSchema);
    out.U16(schema.id);
    out.String(schema.name);
    out.String(schema.encoding);
    out.String(schema.data);  // uint32 length + bytes, as a string is
    out.End(r);
  }

  static void WriteChannel(Bytes& out, const Channel& channel) {
    const size_t r = out.Begin(Opcode::kChannel);
    out.U16(channel.id);
    out.U16(channel.schema_id);
    out.String(channel.topic);
    out.String(channel.message_encoding);
    out.StringMap(channel.metadata);
    out.End(r);
  }
};

Writer::Writer(const std::filesystem::path& path, WriterOptions options)
    : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  impl_->options = std::move(options);
  if (impl_->options.chunk_size == 0) {
    throw std::invalid_argument(path.string() + ": MCAP chunk_size: expected > 0 bytes, got 0");
  }
  impl_->fd.reset(::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644));
  if (!impl_->fd) {
    throw std::runtime_error(path.string() +
                             ": cannot create the session file: " + std::strerror(errno));
  }
  std::string start;
  Bytes out(start);
  out.Raw(detail::kMagic, sizeof detail::kMagic);
  const size_t r = out.Begin(Opcode::kHeader);
  out.String(impl_->options.profile);
  out.String(impl_->options.library);
  out.End(r);
  impl_->AppendData(start);
  impl_->WriteOut();
}

Writer::~Writer() {
  if (impl_ == nullptr || impl_->closed) return;
  try {
    Close();
  } catch (const std::exception& e) {
    log::Error(std::string("session file not completed: ") + e.what());
  }
}

uint16_t Writer::AddSchema(std::string name, std::string encoding, std::string data) {
  impl_->CheckOpen("AddSchema");
  const uint16_t id = static_cast<uint16_t>(impl_->schemas.size() + 1);
  Schema& schema = impl_->schemas[id];
  schema = {id, std::move(name), std::move(encoding), std::move(data)};
  std::string record;
  Bytes out(record);
  Impl::WriteSchema(out, schema);
  impl_->AppendData(record);
  ++impl_->statistics.schema_count;
  return id;
}

uint16_t Writer::AddChannel(uint16_t schema_id, std::string topic, std::string message_encoding,
                            std::map<std::string, std::string> metadata) {
  impl_->CheckOpen("AddChannel");
  if (schema_id != 0 && impl_->schemas.count(schema_id) == 0) {
    throw std::invalid_argument(impl_->Where() + ": channel '" + topic + "': unknown schema id " +
                                std::to_string(schema_id));
  }
  const uint16_t id = static_cast<uint16_t>(impl_->channels.size());
  Channel& channel = impl_->channels[id];
  channel = {id, schema_id, std::move(topic), std::move(message_encoding), std::move(metadata)};
  std::string record;
  Bytes out(record);
  Impl::WriteChannel(out, channel);
  impl_->AppendData(record);
  ++impl_->statistics.channel_count;
  impl_->statistics.channel_message_counts[id] = 0;
  return id;
}

void Writer::Write(uint16_t channel_id, uint32_t sequence, uint64_t log_time_ns,
                   uint64_t publish_time_ns, const void* data, size_t size) {
  Impl& w = *impl_;
  w.CheckOpen("Write");
  const auto counted = w.statistics.channel_message_counts.find(channel_id);
  if (counted == w.statistics.channel_message_counts.end()) {
    throw std::invalid_argument(w.Where() + ": message on unknown channel id " +
                                std::to_string(channel_id));
  }
  const uint64_t offset = w.chunk_records.size();
  Bytes out(w.chunk_records);
  out.U8(static_cast<uint8_t>(Opcode::kMessage));
  out.U64(2 + 4 + 8 + 8 + size);
  out.U16(channel_id);
  out.U32(sequence);
  out.U64(log_time_ns);
  out.U64(publish_time_ns);
  out.Raw(data, size);
  w.chunk_message_index[channel_id].emplace_back(log_time_ns, offset);
  w.chunk_start_ns = std::min(w.chunk_start_ns, log_time_ns);
  w.chunk_end_ns = std::max(w.chunk_end_ns, log_time_ns);

  Statistics& st = w.statistics;
  if (st.message_count == 0) {
    st.message_start_time_ns = st.message_end_time_ns = log_time_ns;
  } else {
    st.message_start_time_ns = std::min(st.message_start_time_ns, log_time_ns);
    st.message_end_time_ns = std::max(st.message_end_time_ns, log_time_ns);
  }
  ++st.message_count;
  ++counted->second;
  if (w.chunk_records.size() >= w.options.chunk_size) w.CloseChunk();
}

void Writer::AddAttachment(std::string name, std::string media_type, uint64_t log_time_ns,
                           const void* data, size_t size) {
  Impl& w = *impl_;
  w.CheckOpen("AddAttachment");
  AttachmentIndex index;
  index.offset = w.position();
  index.log_time_ns = log_time_ns;
  index.create_time_ns = log_time_ns;
  index.data_size = size;
  index.name = name;
  index.media_type = media_type;
  std::string record;
  Bytes out(record);
  const size_t r = out.Begin(Opcode::kAttachment);
  out.U64(log_time_ns);
  out.U64(log_time_ns);  // create time: when it was stored
  out.String(name);
  out.String(media_type);
  out.U64(size);
  out.Raw(data, size);
  // The CRC covers every field before it (the record's content so far).
  out.U32(detail::Crc32Of(record.data() + detail::kRecordPrefix,
                          record.size() - detail::kRecordPrefix));
  out.End(r);
  index.length = record.size();
  w.AppendData(record);
  w.attachment_indexes.push_back(std::move(index));
  ++w.statistics.attachment_count;
  if (w.pending.size() > (64u << 10)) w.WriteOut();
}

void Writer::AddMetadata(std::string name, std::map<std::string, std::string> metadata) {
  Impl& w = *impl_;
  w.CheckOpen("AddMetadata");
  MetadataIndex index{w.position(), 0, name};
  std::string record;
  Bytes out(record);
  const size_t r = out.Begin(Opcode::kMetadata);
  out.String(name);
  out.StringMap(metadata);
  out.End(r);
  index.length = record.size();
  w.AppendData(record);
  w.metadata_indexes.push_back(std::move(index));
  ++w.statistics.metadata_count;
}

void Writer::Flush() {
  impl_->CheckOpen("Flush");
  impl_->CloseChunk();
  impl_->WriteOut();
}

void Writer::Close() {
  if (impl_->closed) return;
  impl_->closed = true;  // a failed Close is not tried again by the destructor
  impl_->Finish();
}

const std::filesystem::path& Writer::path() const { return impl_->path; }
uint64_t Writer::bytes_written() const { return impl_->file_offset; }
const Statistics& Writer::statistics() const { return impl_->statistics; }

}  // namespace haptel::mcap
