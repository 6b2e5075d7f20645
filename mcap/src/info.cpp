#include "haptel/mcap/info.hpp"

#include <cstdio>
#include <map>
#include <set>

#include "haptel/core/json.hpp"

namespace haptel::mcap {
namespace {

double DurationS(const Statistics& s) {
  return s.message_count < 2 ? 0.0 : (s.message_end_time_ns - s.message_start_time_ns) * 1e-9;
}

/// Messages per second over the file's span (0 when it has no span).
double Rate(uint64_t count, double duration_s) { return duration_s > 0 ? count / duration_s : 0.0; }

std::string Compressions(const Summary& summary) {
  std::map<std::string, size_t> counts;
  for (const ChunkIndex& c : summary.chunk_indexes) {
    const std::string_view name = CompressionName(c.compression);
    ++counts[name.empty() ? "none" : std::string(name)];
  }
  std::string out;
  for (const auto& [name, n] : counts) {
    out += (out.empty() ? "" : ", ") + name + " " + std::to_string(n);
  }
  return out.empty() ? "none" : out;
}

std::string Format(const char* format, auto... args) {
  char line[512];
  std::snprintf(line, sizeof line, format, args...);
  return line;
}

}  // namespace

std::string DescribeFile(const Reader& reader) {
  const Summary& summary = reader.summary();
  const Statistics& st = summary.statistics;
  const double duration = DurationS(st);
  uint64_t compressed = 0, uncompressed = 0;
  for (const ChunkIndex& c : summary.chunk_indexes) {
    compressed += c.compressed_size;
    uncompressed += c.uncompressed_size;
  }
  std::string out;
  out += "file:        " + reader.path().string() + "\n";
  out += "library:     " + reader.library() +
         (reader.profile().empty() ? "" : " (profile " + reader.profile() + ")") + "\n";
  if (!reader.loss().what.empty()) out += "state:       " + reader.loss().what + "\n";
  out += Format("duration:    %.3f s (log times %.9f to %.9f s)\n", duration,
                st.message_start_time_ns * 1e-9, st.message_end_time_ns * 1e-9);
  out += Format("messages:    %llu\n", static_cast<unsigned long long>(st.message_count));
  out += Format("chunks:      %zu (%s), %.1f MB compressed from %.1f MB\n",
                summary.chunk_indexes.size(), Compressions(summary).c_str(), compressed * 1e-6,
                uncompressed * 1e-6);
  out += Format("channels:    %zu\n", summary.channels.size());
  for (const auto& [id, channel] : summary.channels) {
    const auto count = st.channel_message_counts.find(id);
    const uint64_t n = count == st.channel_message_counts.end() ? 0 : count->second;
    const auto schema = summary.schemas.find(channel.schema_id);
    const std::string schema_text =
        schema == summary.schemas.end()
            ? "no schema"
            : schema->second.name + " (" + schema->second.encoding + ")";
    out += Format("  %3u %-32s %10llu msgs %9.2f Hz  %s, %s\n", id, channel.topic.c_str(),
                  static_cast<unsigned long long>(n), Rate(n, duration),
                  channel.message_encoding.c_str(), schema_text.c_str());
  }
  out += Format("attachments: %zu\n", summary.attachment_indexes.size());
  for (const AttachmentIndex& a : summary.attachment_indexes) {
    out += Format("  %-40s %-24s %llu bytes\n", a.name.c_str(), a.media_type.c_str(),
                  static_cast<unsigned long long>(a.data_size));
  }
  out += Format("metadata:    %zu\n", summary.metadata_indexes.size());
  for (const MetadataIndex& index : summary.metadata_indexes) {
    const Metadata m = reader.ReadMetadata(index);
    out += "  " + m.name + "\n";
    for (const auto& [key, value] : m.metadata) out += "    " + key + ": " + value + "\n";
  }
  return out;
}

std::string DescribeFileJson(const Reader& reader) {
  const Summary& summary = reader.summary();
  const Statistics& st = summary.statistics;
  const double duration = DurationS(st);
  std::string out = "{\"file\":" + JsonString(reader.path().string());
  out += ",\"library\":" + JsonString(reader.library());
  out += ",\"profile\":" + JsonString(reader.profile());
  out += ",\"recovered\":" + std::string(reader.recovered() ? "true" : "false");
  out += ",\"loss\":{\"bytes\":" + std::to_string(reader.loss().bytes_lost) +
         ",\"chunks\":" + std::to_string(reader.loss().chunks_lost) +
         ",\"what\":" + JsonString(reader.loss().what) + "}";
  out += ",\"duration_s\":" + JsonNumber(duration);
  out += ",\"start_ns\":" + std::to_string(st.message_start_time_ns);
  out += ",\"end_ns\":" + std::to_string(st.message_end_time_ns);
  out += ",\"messages\":" + std::to_string(st.message_count);
  out += ",\"chunks\":" + std::to_string(summary.chunk_indexes.size());
  out += ",\"compression\":" + JsonString(Compressions(summary));
  out += ",\"channels\":[";
  bool first = true;
  for (const auto& [id, channel] : summary.channels) {
    const auto count = st.channel_message_counts.find(id);
    const uint64_t n = count == st.channel_message_counts.end() ? 0 : count->second;
    const auto schema = summary.schemas.find(channel.schema_id);
    out += std::string(first ? "" : ",") + "{\"id\":" + std::to_string(id) +
           ",\"topic\":" + JsonString(channel.topic) +
           ",\"message_encoding\":" + JsonString(channel.message_encoding) +
           ",\"schema\":" + JsonString(schema == summary.schemas.end() ? "" : schema->second.name) +
           ",\"schema_encoding\":" +
           JsonString(schema == summary.schemas.end() ? "" : schema->second.encoding) +
           ",\"messages\":" + std::to_string(n) + ",\"rate_hz\":" + JsonNumber(Rate(n, duration)) +
           "}";
    first = false;
  }
  out += "],\"attachments\":[";
  first = true;
  for (const AttachmentIndex& a : summary.attachment_indexes) {
    out += std::string(first ? "" : ",") + "{\"name\":" + JsonString(a.name) +
           ",\"media_type\":" + JsonString(a.media_type) +
           ",\"bytes\":" + std::to_string(a.data_size) + "}";
    first = false;
  }
  out += "],\"metadata\":[";
  first = true;
  for (const MetadataIndex& index : summary.metadata_indexes) {
    const Metadata m = reader.ReadMetadata(index);
    out += std::string(first ? "" : ",") + "{\"name\":" + JsonString(m.name) + ",\"values\":{";
    bool first_value = true;
    for (const auto& [key, value] : m.metadata) {
      out += std::string(first_value ? "" : ",") + JsonString(key) + ":" + JsonString(value);
      first_value = false;
    }
    out += "}}";
    first = false;
  }
  out += "]}\n";
  return out;
}

}  // namespace haptel::mcap
