// Recovery: what a scan of the truncated file found, written again through
// the writer, so the new file's indexes and summary are the writer's own.
#include "haptel/mcap/recover.hpp"

#include <stdexcept>

#include "haptel/mcap/writer.hpp"

namespace haptel::mcap {

RecoverResult Recover(const Reader& in, const std::filesystem::path& out) {
  std::error_code ignored;
  if (std::filesystem::equivalent(in.path(), out, ignored)) {
    throw std::invalid_argument(out.string() + ": recovery must write another file than its input");
  }
  const Summary& summary = in.summary();
  WriterOptions options;
  options.profile = in.profile();
  options.library = in.library();
  options.compression = summary.chunk_indexes.empty() ? Compression::kZstd
                                                      : summary.chunk_indexes.front().compression;
  Writer writer(out, options);
  // The writer numbers schemas from 1 and channels from 0 in the order
  // added: a file of ours keeps its ids, another's is renumbered.
  std::map<uint16_t, uint16_t> schema_ids{{0, 0}};
  for (const auto& [id, schema] : summary.schemas) {
    schema_ids[id] = writer.AddSchema(schema.name, schema.encoding, schema.data);
  }
  std::map<uint16_t, uint16_t> channel_ids;
  for (const auto& [id, channel] : summary.channels) {
    const auto schema = schema_ids.find(channel.schema_id);
    channel_ids[id] = writer.AddChannel(schema == schema_ids.end() ? 0 : schema->second,
                                        channel.topic, channel.message_encoding, channel.metadata);
  }
  RecoverResult result;
  result.loss = in.loss();
  in.ForEachMessage([&](const MessageView& m) {
    writer.Write(channel_ids.at(m.channel->id), m.sequence, m.log_time_ns, m.publish_time_ns,
                 m.data, m.size);
    ++result.messages;
  });
  for (const AttachmentIndex& index : summary.attachment_indexes) {
    try {
      const Attachment a = in.ReadAttachment(index);
      writer.AddAttachment(a.name, a.media_type, a.log_time_ns, a.data.data(), a.data.size());
      ++result.attachments;
    } catch (const McapError& e) {  // a damaged attachment is left out, and said
      result.loss.what += std::string(result.loss.what.empty() ? "" : "; ") + e.what();
    }
  }
  for (const MetadataIndex& index : summary.metadata_indexes) {
    Metadata m = in.ReadMetadata(index);
    writer.AddMetadata(std::move(m.name), std::move(m.metadata));
    ++result.metadata;
  }
  writer.Close();
  return result;
}

RecoverResult Recover(const std::filesystem::path& in, const std::filesystem::path& out) {
  const Reader reader = Reader::Open(in);
  return Recover(reader, out);
}

}  // namespace haptel::mcap
