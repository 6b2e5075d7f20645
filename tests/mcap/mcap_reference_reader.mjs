// Reads an MCAP file with the TypeScript reference reader (@mcap/core: its
// McapIndexedReader and McapStreamReader, CRCs validated) and prints what it
// found as one JSON line, for a C++ test to compare with what was written.
//
//   node mcap_reference_reader.mjs FILE.mcap [--decode]
//
// --decode: every message of a channel with an `omgidl` schema and `cdr`
// encoding is decoded against the file's own schema with
// @foxglove/omgidl-serialization; counts and the first failures are reported.
//
// The packages come from HAPTEL_NODE_TOOLS (scripts/test installs them
// there: `npm install --prefix build/node-tools`). Exit 1 on any error.
import { readFileSync } from "node:fs";
import { createRequire } from "node:module";
import path from "node:path";

const tools = process.env.HAPTEL_NODE_TOOLS;
if (!tools) {
  console.error("HAPTEL_NODE_TOOLS is not set (the folder scripts/test installs @mcap/core into)");
  process.exit(2);
}
const require = createRequire(path.join(path.resolve(tools), "node_modules", "index.js"));
const { McapIndexedReader, McapStreamReader } = require("@mcap/core");
const { loadDecompressHandlers } = require("@mcap/support");
const { crc32 } = require("@foxglove/crc");

const file = process.argv[2];
const decode = process.argv.includes("--decode");
const bytes = new Uint8Array(readFileSync(file));
const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
const decompressHandlers = await loadDecompressHandlers();
const result = { file, indexed: {}, stream: {}, crc: {} };

function count(map, key) {
  map[key] = (map[key] ?? 0) + 1;
}

// The indexed reader: summary, chunk indexes, message indexes, CRCs.
const readable = {
  size: async () => BigInt(bytes.byteLength),
  read: async (offset, size) => bytes.subarray(Number(offset), Number(offset + size)),
};
const indexed = await McapIndexedReader.Initialize({ readable, decompressHandlers });
{
  const perTopic = {};
  let messages = 0;
  let lastTime = -1n;
  let ordered = true;
  for await (const m of indexed.readMessages({ validateCrcs: true })) {
    count(perTopic, indexed.channelsById.get(m.channelId).topic);
    if (m.logTime < lastTime) ordered = false;
    lastTime = m.logTime;
    ++messages;
  }
  let attachments = 0;
  for await (const _ of indexed.readAttachments({ validateCrcs: true })) ++attachments;
  let metadata = 0;
  for await (const _ of indexed.readMetadata()) ++metadata;
  result.indexed = {
    messages,
    per_topic: perTopic,
    in_log_time_order: ordered,
    channels: indexed.channelsById.size,
    schemas: indexed.schemasById.size,
    chunks: indexed.chunkIndexes.length,
    attachments,
    metadata,
    statistics_messages: Number(indexed.statistics?.messageCount ?? -1n),
    profile: indexed.header.profile,
  };
  // The data section's CRC (DataEnd) and the summary's (Footer), computed here.
  const dataEnd = Number(indexed.dataEndOffset);
  result.crc.data_section_ok =
    indexed.dataSectionCrc === undefined || indexed.dataSectionCrc === 0
      ? null
      : crc32(bytes.subarray(0, dataEnd)) === indexed.dataSectionCrc;
  const footerAt = bytes.byteLength - 8 - 29;
  const summaryStart = Number(view.getBigUint64(footerAt + 9, true));
  const summaryCrc = view.getUint32(footerAt + 9 + 16, true);
  result.crc.summary_ok =
    summaryCrc === 0 ? null : crc32(bytes.subarray(summaryStart, footerAt + 9 + 16)) === summaryCrc;
}

// The stream reader: every record in file order, chunk CRCs validated.
{
  const reader = new McapStreamReader({ decompressHandlers, validateCrcs: true });
  reader.append(bytes);
  const perTopic = {};
  const channels = new Map();
  const schemas = new Map();
  let messages = 0, attachments = 0, metadata = 0, footer = false;
  const decoded = { ok: 0, failed: 0, skipped: 0, failures: [] };
  const decoders = new Map();
  let omgidl;
  if (decode) {
    const { parseIDL } = require("@foxglove/omgidl-parser");
    const { MessageReader } = require("@foxglove/omgidl-serialization");
    omgidl = { parseIDL, MessageReader };
  }
  for (let record; (record = reader.nextRecord()); ) {
    switch (record.type) {
      case "Schema": schemas.set(record.id, record); break;
      case "Channel": channels.set(record.id, record); break;
      case "Attachment": ++attachments; break;
      case "Metadata": ++metadata; break;
      case "Footer": footer = true; break;
      case "Message": {
        ++messages;
        const channel = channels.get(record.channelId);
        count(perTopic, channel.topic);
        if (!decode) break;
        const schema = schemas.get(channel.schemaId);
        if (schema?.encoding !== "omgidl" || channel.messageEncoding !== "cdr") {
          ++decoded.skipped;
          break;
        }
        try {
          let decoder = decoders.get(schema.id);
          if (!decoder) {
            const text = new TextDecoder().decode(schema.data);
            decoder = new omgidl.MessageReader(schema.name, omgidl.parseIDL(text));
            decoders.set(schema.id, decoder);
          }
          decoder.readMessage(record.data);
          ++decoded.ok;
        } catch (e) {
          ++decoded.failed;
          if (decoded.failures.length < 5) decoded.failures.push(`${channel.topic}: ${e.message}`);
        }
        break;
      }
    }
  }
  result.stream = { messages, per_topic: perTopic, attachments, metadata, footer, done: reader.done() };
  if (decode) result.decoded = decoded;
}
console.log(JSON.stringify(result));
