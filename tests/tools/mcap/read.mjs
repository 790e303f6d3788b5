// Open an MCAP file as Foxglove does: @mcap/core's McapIndexedReader (summary, chunk indexes),
// each channel's ros2msg schema parsed by @foxglove/rosmsg and its CDR messages decoded by
// @foxglove/rosmsg2-serialization. Prints one JSON object on stdout; exits 1 with the error
// on stderr if the file cannot be read that way.
//
//   node read.mjs FILE.mcap
import { open } from "node:fs/promises";
import { McapIndexedReader } from "@mcap/core";
import { parse } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";

const handle = await open(process.argv[2], "r");
const readable = {
  size: async () => BigInt((await handle.stat()).size),
  read: async (offset, length) => {
    const buf = new Uint8Array(Number(length));
    await handle.read(buf, 0, Number(length), Number(offset));
    return buf;
  },
};
try {
  const reader = await McapIndexedReader.Initialize({ readable });
  const decoders = new Map();
  const channels = {};
  for (const [id, ch] of reader.channelsById) {
    const schema = reader.schemasById.get(ch.schemaId);
    channels[ch.topic] = { encoding: ch.messageEncoding, schema: schema?.name, schemaEncoding: schema?.encoding };
    if (ch.messageEncoding === "cdr" && schema?.encoding === "ros2msg") {
      const text = new TextDecoder().decode(schema.data);
      decoders.set(id, new MessageReader(parse(text, { ros2: true })));
    }
  }
  const messages = [];
  for await (const m of reader.readMessages()) {
    const decoder = decoders.get(m.channelId);
    const topic = reader.channelsById.get(m.channelId).topic;
    messages.push({ topic, logTime: String(m.logTime), message: decoder ? decoder.readMessage(m.data) : null });
  }
  const out = {
    profile: reader.header.profile,
    library: reader.header.library,
    chunks: reader.chunkIndexes.length,
    statistics: reader.statistics
      ? { messageCount: Number(reader.statistics.messageCount), channelCount: reader.statistics.channelCount }
      : null,
    metadata: [],
    channels,
    messages,
  };
  for await (const md of reader.readMetadata()) {
    out.metadata.push({ name: md.name, metadata: Object.fromEntries(md.metadata) });
  }
  // bigint (uint64 fields) as numbers, for JSON
  process.stdout.write(JSON.stringify(out, (_, v) => (typeof v === "bigint" ? Number(v) : v)));
} catch (e) {
  process.stderr.write(`${e?.stack ?? e}\n`);
  process.exitCode = 1;
} finally {
  await handle.close();
}
