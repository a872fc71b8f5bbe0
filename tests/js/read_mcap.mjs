// Independent reader for the session logs (Foxglove's @mcap/core, zstd by fzstd).
//
// Usage: node tests/js/read_mcap.mjs FILE
// Prints one JSON object: {reader, complete, counts: {topic: n}, schemas: {topic: name},
// metadata: {name: {key: value}}, lastLogTimeNs, error}.
// A complete file is read through its index (McapIndexedReader); a file whose index cannot be
// read (cut off, no footer) is read front to back (McapStreamReader) up to its last whole record.
import { readFile } from "node:fs/promises";
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { decompress } from "fzstd";

const decompressHandlers = {
  zstd: (buffer, decompressedSize) => {
    const out = decompress(buffer);
    if (BigInt(out.byteLength) !== decompressedSize) {
      throw new Error(`zstd chunk: ${out.byteLength} bytes, expected ${decompressedSize}`);
    }
    return out;
  },
};

function bufferReadable(bytes) {
  return {
    size: async () => BigInt(bytes.byteLength),
    read: async (offset, size) => {
      if (offset + size > BigInt(bytes.byteLength)) {
        throw new Error(`read past the end: ${offset} + ${size}`);
      }
      return bytes.subarray(Number(offset), Number(offset + size));
    },
  };
}

function newResult(reader) {
  return { reader, complete: false, counts: {}, schemas: {}, metadata: {}, lastLogTimeNs: null,
           error: null };
}

function countMessage(result, topic, logTime) {
  result.counts[topic] = (result.counts[topic] ?? 0) + 1;
  if (result.lastLogTimeNs === null || logTime > BigInt(result.lastLogTimeNs)) {
    result.lastLogTimeNs = logTime.toString();
  }
}

async function readIndexed(bytes) {
  const reader = await McapIndexedReader.Initialize({
    readable: bufferReadable(bytes), decompressHandlers,
  });
  const result = newResult("indexed");
  for (const channel of reader.channelsById.values()) {
    result.schemas[channel.topic] = reader.schemasById.get(channel.schemaId)?.name ?? "";
    result.counts[channel.topic] = 0;
  }
  for await (const message of reader.readMessages({ validateCrcs: true })) {
    countMessage(result, reader.channelsById.get(message.channelId).topic, message.logTime);
  }
  for await (const record of reader.readMetadata()) {
    result.metadata[record.name] = Object.fromEntries(record.metadata);
  }
  result.complete = true;
  return result;
}

function readStream(bytes) {
  const reader = new McapStreamReader({ decompressHandlers, validateCrcs: true });
  const result = newResult("stream");
  const channels = new Map();
  const schemas = new Map();
  reader.append(bytes);
  try {
    for (let record; (record = reader.nextRecord()); ) {
      if (record.type === "Schema") {
        schemas.set(record.id, record.name);
      } else if (record.type === "Channel") {
        channels.set(record.id, record.topic);
        result.schemas[record.topic] = schemas.get(record.schemaId) ?? "";
        result.counts[record.topic] ??= 0;
      } else if (record.type === "Message") {
        countMessage(result, channels.get(record.channelId), record.logTime);
      } else if (record.type === "Metadata") {
        result.metadata[record.name] = Object.fromEntries(record.metadata);
      }
    }
  } catch (err) {
    result.error = String(err?.message ?? err);
  }
  result.complete = reader.done();
  return result;
}

async function main() {
  const file = process.argv[2];
  if (!file) {
    console.error("usage: node read_mcap.mjs FILE");
    process.exit(2);
  }
  const bytes = new Uint8Array(await readFile(file));
  let result;
  try {
    result = await readIndexed(bytes);
  } catch (err) {
    result = readStream(bytes);
    result.indexError = String(err?.message ?? err);
  }
  console.log(JSON.stringify(result));
}

await main();
