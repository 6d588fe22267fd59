// Reads ROS 2 bags that `viosfm convert` wrote with Foxglove's TypeScript
// libraries, independently of viosfm's reader: @mcap/core (MCAP, every CRC
// validated, the indexed reader through the summary and the chunk indexes),
// sql.js (SQLite compiled to WebAssembly) for .db3, and
// @foxglove/rosmsg2-serialization decoding each message with the ros2msg
// definition the bag carries. Checks every image and IMU stamp, every IMU
// value and the image sizes against the EuRoC folder the bags were written
// from. Not part of `make test` (it needs npm packages):
//
//   mkdir /tmp/check && cd /tmp/check && npm install @mcap/core@2 \
//     @foxglove/rosmsg2-serialization@3 @foxglove/rosmsg@5 fzstd lz4js sql.js
//   NODE_PATH=/tmp/check/node_modules node scripts/check-ros2-bags.mjs FOLDER BAG...
import fs from "node:fs";
import path from "node:path";
import { createRequire } from "node:module";

const require = createRequire(path.join(process.env.NODE_PATH ?? ".", "x.js"));
const { McapStreamReader, McapIndexedReader } = require("@mcap/core");
const { MessageReader } = require("@foxglove/rosmsg2-serialization");
const { parse } = require("@foxglove/rosmsg");
const fzstd = require("fzstd");
const lz4 = require("lz4js");
const initSqlJs = require("sql.js");

const decompressHandlers = {
  zstd: (buffer) => fzstd.decompress(buffer),
  lz4: (buffer) => Uint8Array.from(lz4.decompress(buffer)),
};

function readCsv(file) {
  return fs.readFileSync(file, "utf8").split("\n")
    .filter((line) => line.trim() && !line.startsWith("#"))
    .map((line) => line.split(",").map((field) => field.trim()));
}

function stampNs(header) {
  return BigInt(header.stamp.sec) * 1000000000n + BigInt(header.stamp.nanosec);
}

// Messages as [topic, type, definition, bytes] from each container.
async function* mcapMessages(file) {
  const bytes = new Uint8Array(fs.readFileSync(file));
  // The streamed reader checks the chunk CRCs and the data section's.
  const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
  stream.append(bytes);
  const schemas = new Map();
  const channels = new Map();
  let streamed = 0;
  for (let record; (record = stream.nextRecord()); ) {
    if (record.type === "Schema") schemas.set(record.id, record);
    if (record.type === "Channel") channels.set(record.id, record);
    if (record.type === "Message") streamed++;
  }
  if (!stream.done()) throw new Error(`${file}: the streamed reader did not reach the end`);
  // The indexed reader goes through the summary, chunk and message indexes.
  const readable = {
    size: async () => BigInt(bytes.length),
    read: async (offset, size) => bytes.subarray(Number(offset), Number(offset + size)),
  };
  const indexed = await McapIndexedReader.Initialize({ readable, decompressHandlers });
  let count = 0;
  for await (const message of indexed.readMessages()) {
    const channel = indexed.channelsById.get(message.channelId);
    const schema = indexed.schemasById.get(channel.schemaId);
    count++;
    yield [channel.topic, schema.name, new TextDecoder().decode(schema.data), message.data];
  }
  if (count !== streamed) throw new Error(`${file}: ${count} indexed messages, ${streamed} streamed`);
  console.log(`${file}: MCAP ${indexed.header.profile}, library '${indexed.header.library}', ` +
              `${indexed.chunkIndexes.length} chunks, ${count} messages, CRCs valid`);
}

async function* db3Messages(file) {
  const SQL = await initSqlJs();
  const db = new SQL.Database(new Uint8Array(fs.readFileSync(file)));
  const definitions = new Map();
  for (const [type, encoding, text] of db.exec(
      "SELECT topic_type, encoding, encoded_message_definition FROM message_definitions")[0].values) {
    if (encoding !== "ros2msg") throw new Error(`${file}: ${type} encoded as ${encoding}`);
    definitions.set(type, text);
  }
  const topics = new Map();
  for (const [id, name, type, format] of db.exec(
      "SELECT id, name, type, serialization_format FROM topics")[0].values) {
    if (format !== "cdr") throw new Error(`${file}: topic ${name} serialized as ${format}`);
    topics.set(id, { name, type });
  }
  const statement = db.prepare("SELECT topic_id, data FROM messages ORDER BY timestamp, id");
  let count = 0;
  while (statement.step()) {
    const [topicId, data] = statement.get();
    const topic = topics.get(topicId);
    count++;
    yield [topic.name, topic.type, definitions.get(topic.type), data];
  }
  statement.free();
  const schema = db.exec("SELECT schema_version, ros_distro FROM schema")[0].values[0];
  console.log(`${file}: sqlite3 schema ${schema[0]} (${schema[1]}), ${count} messages`);
}

async function check(folder, bag) {
  const images = readCsv(path.join(folder, "mav0", "cam0", "data.csv"));
  const imu = readCsv(path.join(folder, "mav0", "imu0", "data.csv"));
  const readers = new Map();
  const seen = { image: [], imu: [] };
  let failures = 0;
  const fail = (what) => {
    if (failures++ < 10) console.log(`  MISMATCH ${what}`);
  };
  const messages = bag.endsWith(".mcap") ? mcapMessages(bag) : db3Messages(bag);
  for await (const [topic, type, definition, data] of messages) {
    if (!readers.has(type)) readers.set(type, new MessageReader(parse(definition, { ros2: true })));
    const message = readers.get(type).readMessage(data);
    if (type === "sensor_msgs/msg/Image") {
      const index = seen.image.length;
      seen.image.push(stampNs(message.header));
      if (message.encoding !== "mono8" || message.step !== message.width ||
          message.data.length !== message.width * message.height) {
        fail(`image ${index}: ${message.width}x${message.height} ${message.encoding}`);
      }
    } else if (type === "sensor_msgs/msg/Imu") {
      const index = seen.imu.length;
      seen.imu.push(stampNs(message.header));
      const row = imu[index].slice(1).map(Number);
      const got = [message.angular_velocity.x, message.angular_velocity.y,
                   message.angular_velocity.z, message.linear_acceleration.x,
                   message.linear_acceleration.y, message.linear_acceleration.z];
      if (got.some((value, i) => value !== row[i])) fail(`IMU ${index}: ${got} vs ${row}`);
    } else if (type !== "std_msgs/msg/String" && type !== "geometry_msgs/msg/PoseStamped") {
      fail(`unexpected type ${type} on ${topic}`);
    }
  }
  const compare = (what, got, rows) => {
    if (got.length !== rows.length) fail(`${rows.length} ${what} in the folder, ${got.length} in the bag`);
    rows.forEach((row, i) => {
      if (got[i] !== BigInt(row[0])) fail(`${what} ${i}: stamp ${got[i]} vs ${row[0]}`);
    });
  };
  compare("images", seen.image, images);
  compare("IMU samples", seen.imu, imu);
  console.log(`  ${seen.image.length} images, ${seen.imu.length} IMU samples: ` +
              (failures ? `${failures} mismatches` : "every stamp and IMU value equal to the folder's"));
  return failures === 0;
}

const [folder, ...bags] = process.argv.slice(2);
let ok = true;
for (const bag of bags) ok = (await check(folder, bag)) && ok;
process.exit(ok ? 0 : 1);
