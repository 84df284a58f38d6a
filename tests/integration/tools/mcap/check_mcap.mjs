// Reads an MCAP file with @mcap/core, by its index (as Foxglove opens a local file) and front to
// back with CRC checks, decodes every message with protobufjs from the schema embedded in the file
// (Root.fromDescriptor over the FileDescriptorSet, as Foxglove does) and prints what it saw as one
// JSON object, with the Metadata records. zstd chunks are decompressed by the zstd command, not by
// our code.
//
// Message fields are named by the json_name the embedded descriptors give them, as a reader that
// expects protoc's descriptor sets does (protoc fills json_name for every field: measureTimeUs
// for measure_time_us): a field without one is an error, so a file whose descriptors lack them
// fails here. protobufjs itself ignores json_name (it names fields as declared), so the names are
// mapped here from the descriptors, not taken from protobufjs.
//
// node check_mcap.mjs FILE.mcap
import { execFileSync } from "node:child_process";
import { open } from "node:fs/promises";
import { createRequire } from "node:module";

import { McapIndexedReader, McapStreamReader } from "@mcap/core";

const require = createRequire(import.meta.url);
const protobuf = require("protobufjs");
const descriptor = require("protobufjs/ext/descriptor");

const decompressHandlers = {
  zstd: (data, size) => {
    const out = execFileSync("zstd", ["-d", "-c", "-q"], { input: data, maxBuffer: 1 << 30 });
    if (BigInt(out.length) !== size) throw new Error(`zstd gave ${out.length} bytes, the chunk says ${size}`);
    return new Uint8Array(out.buffer, out.byteOffset, out.length);
  },
};

const path = process.argv[2];
const handle = await open(path, "r");
const size = BigInt((await handle.stat()).size);
const readable = {
  size: async () => size,
  read: async (offset, length) => {
    const buf = Buffer.alloc(Number(length));
    await handle.read(buf, 0, Number(length), Number(offset));
    return buf;
  },
};

// "tactile.v1.TactileFrame.measure_time_us" -> "measureTimeUs", for every field of every message
// type (nested ones too) of a FileDescriptorSet; a field without json_name maps to undefined.
function jsonNames(set) {
  const names = new Map();
  const add = (scope, type) => {
    for (const f of type.field ?? []) names.set(`${scope}.${type.name}.${f.name}`, f.jsonName || undefined);
    for (const nested of type.nestedType ?? []) add(`${scope}.${type.name}`, nested);
  };
  for (const file of set.file) for (const type of file.messageType ?? []) add(file.package, type);
  return names;
}

// A decoded message as a plain object keyed by its fields' json_names (nested messages too).
function byJsonName(type, object, names) {
  const out = {};
  for (const field of type.fieldsArray) {
    const full = `${type.fullName.replace(/^\./, "")}.${field.name}`;
    const key = names.get(full);
    if (key === undefined) throw new Error(`${full}: no json_name in the embedded descriptor`);
    let value = object[field.name];
    field.resolve();
    if (field.resolvedType instanceof protobuf.Type && value !== undefined && value !== null) {
      const sub = field.resolvedType;
      value = field.repeated ? value.map((v) => byJsonName(sub, v, names)) : byJsonName(sub, value, names);
    }
    out[key] = value;
  }
  return out;
}

const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
const types = new Map();  // schema id -> { type: protobufjs Type, names: jsonNames() }
for (const [id, schema] of reader.schemasById) {
  if (schema.encoding !== "protobuf") throw new Error(`schema ${schema.name}: encoding ${schema.encoding}`);
  const set = descriptor.FileDescriptorSet.decode(schema.data);
  const root = protobuf.Root.fromDescriptor(set);
  types.set(id, { type: root.lookupType(schema.name), names: jsonNames(set) });
}

const out = { header: reader.header, channels: {}, statistics: {}, indexed: {}, stream: {}, messages: {}, metadata: {} };
for (const [id, ch] of reader.channelsById) {
  out.channels[ch.topic] = { schema: reader.schemasById.get(ch.schemaId).name, encoding: ch.messageEncoding };
}
const stats = reader.statistics;
out.statistics = {
  messageCount: Number(stats.messageCount),
  chunkCount: stats.chunkCount,
  perTopic: Object.fromEntries([...stats.channelMessageCounts].map(([id, n]) => [reader.channelsById.get(id).topic, Number(n)])),
  metadataCount: stats.metadataCount,
};
for await (const m of reader.readMetadata()) out.metadata[m.name] = Object.fromEntries(m.metadata);
out.chunkCompression = [...new Set(reader.chunkIndexes.map((c) => c.compression))];

for await (const m of reader.readMessages({ validateCrcs: true })) {
  const topic = reader.channelsById.get(m.channelId).topic;
  out.indexed[topic] = (out.indexed[topic] ?? 0) + 1;
  const { type, names } = types.get(reader.channelsById.get(m.channelId).schemaId);
  const decoded = type.toObject(type.decode(m.data), { longs: String, enums: String, bytes: String, defaults: true });
  const body = byJsonName(type, decoded, names);
  if (body.pixels !== undefined) body.pixels = Buffer.from(body.pixels, "base64").length;  // keep the output small
  (out.messages[topic] ??= []).push({ logTime: m.logTime.toString(), publishTime: m.publishTime.toString(), sequence: m.sequence, body });
}

// Front to back, every CRC checked, as a streaming reader (or `mcap doctor`) would.
const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
stream.append(new Uint8Array(await handle.readFile()));
const streamChannels = new Map();
let footer = false;
for (let r; (r = stream.nextRecord()); ) {
  if (r.type === "Channel") streamChannels.set(r.id, r.topic);
  if (r.type === "Message") {
    const topic = streamChannels.get(r.channelId);
    out.stream[topic] = (out.stream[topic] ?? 0) + 1;
  }
  if (r.type === "Metadata") out.streamMetadata = [...(out.streamMetadata ?? []), r.name];
  if (r.type === "Footer") footer = true;
}
if (!footer || !stream.done()) throw new Error("the stream reader did not reach the footer");
await handle.close();
process.stdout.write(JSON.stringify(out) + "\n");
