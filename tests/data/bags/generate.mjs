// Writes the ROS bag fixtures of this folder with writers that are not the project's: MCAP files
// with @mcap/core's McapWriter, rosbag2 SQLite files with sql.js, messages serialised by
// @foxglove/rosmsg2-serialization (CDR) and @foxglove/rosmsg-serialization (ROS 1); ROS 1 bags
// by their specification, read back by @foxglove/rosbag before they are kept. The data: 30 scans and 31 odometry poses from the first
// 31 laser messages of data/carmen/intel-corrected.log.gz (README.md in this folder says which
// and how; tests/robot/bag_test.cpp checks the readers against the same values).
//
//   cd tests/data/bags && npm ci && node generate.mjs
import fs from "node:fs";
import path from "node:path";
import zlib from "node:zlib";
import { fileURLToPath } from "node:url";

import { McapWriter } from "@mcap/core";
import { md5, parse } from "@foxglove/rosmsg";
import { MessageWriter as Ros1Writer } from "@foxglove/rosmsg-serialization";
import { MessageWriter } from "@foxglove/rosmsg2-serialization";
import { Bag } from "@foxglove/rosbag";
import rosbagNode from "@foxglove/rosbag/dist/cjs/node/index.js";
import Bzip2 from "@foxglove/wasm-bz2";
import lz4Decompress from "@foxglove/wasm-lz4";
import compressjs from "compressjs";
import * as zstd from "@foxglove/wasm-zstd";
import lz4 from "lz4js";
import initSqlJs from "sql.js";

const here = path.dirname(fileURLToPath(import.meta.url));
const root = path.resolve(here, "../../..");

// ---- the data -----------------------------------------------------------------------------------
// Scan k is laser message k stamped 1 ms after it; odometry j the pose of laser message j, at its
// time: each scan's pose is interpolated between two odometry messages.
const SCANS = 30, ODOMS = 31, SCAN_DELAY = 0.001;
const text = zlib.gunzipSync(fs.readFileSync(path.join(root, "data/carmen/intel-corrected.log.gz")));
const flaser = text.toString("latin1").split("\n").filter((l) => l.startsWith("FLASER "))
  .map((l) => {
    const f = l.trim().split(/\s+/);
    const n = Number(f[1]);
    return {
      ranges: f.slice(2, 2 + n).map(Number),
      pose: f.slice(2 + n, 5 + n).map(Number),
      time: Number(f[8 + n]),
    };
  });

// A time [s] as ROS stamps it: whole seconds and nanoseconds.
const stamp = (t) => {
  const sec = Math.floor(t);
  const nanosec = Math.round((t - sec) * 1e9);
  return { sec, nanosec, nsec: nanosec };  // ROS 2's and ROS 1's names
};
const ns = (s) => BigInt(s.sec) * 1000000000n + BigInt(s.nanosec);
const quat = (yaw) => ({ x: 0, y: 0, z: Math.sin(yaw / 2), w: Math.cos(yaw / 2) });

// ---- message definitions (ROS 2 interfaces) -------------------------------------------------------
const SEP = "\n================================================================================\nMSG: ";
const HEADER = "std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id" + SEP +
  "builtin_interfaces/Time\nint32 sec\nuint32 nanosec";
const POSE = "geometry_msgs/Pose\nPoint position\nQuaternion orientation" + SEP +
  "geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z" + SEP +
  "geometry_msgs/Quaternion\nfloat64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1";
const VECTOR3 = "geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z";
const DEFS = {
  "sensor_msgs/msg/LaserScan":
    "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\nfloat32 angle_increment\n" +
    "float32 time_increment\nfloat32 scan_time\nfloat32 range_min\nfloat32 range_max\n" +
    "float32[] ranges\nfloat32[] intensities" + SEP + HEADER,
  "nav_msgs/msg/Odometry":
    "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\n" +
    "geometry_msgs/TwistWithCovariance twist" + SEP + HEADER + SEP +
    "geometry_msgs/PoseWithCovariance\nPose pose\nfloat64[36] covariance" + SEP + POSE + SEP +
    "geometry_msgs/TwistWithCovariance\nTwist twist\nfloat64[36] covariance" + SEP +
    "geometry_msgs/Twist\nVector3 linear\nVector3 angular" + SEP + VECTOR3,
  "geometry_msgs/msg/PoseStamped":
    "std_msgs/Header header\ngeometry_msgs/Pose pose" + SEP + HEADER + SEP + POSE,
  "tf2_msgs/msg/TFMessage":
    "geometry_msgs/TransformStamped[] transforms" + SEP +
    "geometry_msgs/TransformStamped\nstd_msgs/Header header\nstring child_frame_id\n" +
    "Transform transform" + SEP + HEADER + SEP +
    "geometry_msgs/Transform\nVector3 translation\nQuaternion rotation" + SEP + VECTOR3 + SEP +
    "geometry_msgs/Quaternion\nfloat64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1",
};
const writers = Object.fromEntries(Object.entries(DEFS).map(([type, def]) =>
  [type, new MessageWriter(parse(def, { ros2: true }))]));

// ---- the messages, in receive order ------------------------------------------------------------
// The laser on the robot (checked by the tests): base_footprint -> base_link -> laser.
const STATIC_TF = [
  { parent: "base_footprint", child: "base_link", t: { x: 0, y: 0, z: 0.05 }, yaw: 0 },
  { parent: "base_link", child: "laser", t: { x: 0.1, y: 0.02, z: 0.3 }, yaw: 0.05 },
];
const tf = (s, list) => ({
  transforms: list.map((e) => ({
    header: { stamp: s, frame_id: e.parent }, child_frame_id: e.child,
    transform: { translation: e.t, rotation: quat(e.yaw) },
  })),
});

function intelMessages({ scanTime = (k) => flaser[k].time + SCAN_DELAY } = {}) {
  const out = [];
  const first = stamp(flaser[0].time);
  out.push({ topic: "/tf_static", type: "tf2_msgs/msg/TFMessage", time: ns(first),
             msg: tf(first, STATIC_TF) });
  for (let j = 0; j < ODOMS; ++j) {
    const r = flaser[j];
    const s = stamp(r.time);
    const pose = { position: { x: r.pose[0], y: r.pose[1], z: 0 }, orientation: quat(r.pose[2]) };
    out.push({ topic: "/odom", type: "nav_msgs/msg/Odometry", time: ns(s) + 1000n, msg: {
      header: { stamp: s, frame_id: "odom" }, child_frame_id: "base_footprint",
      pose: { pose, covariance: new Array(36).fill(0) },
      twist: { twist: { linear: { x: 0.01 * j, y: 0, z: 0 }, angular: { x: 0, y: 0, z: -0.02 * j } },
               covariance: new Array(36).fill(0) },
    } });
    out.push({ topic: "/tf", type: "tf2_msgs/msg/TFMessage", time: ns(s) + 2000n, msg: tf(s, [
      { parent: "odom", child: "base_footprint", t: { x: r.pose[0], y: r.pose[1], z: 0 }, yaw: r.pose[2] },
    ]) });
  }
  for (let k = 0; k < SCANS; ++k) {
    const r = flaser[k];
    const s = stamp(scanTime(k)), received = stamp(r.time + SCAN_DELAY);
    const ranges = r.ranges.slice();
    if (k === 1) { ranges[0] = NaN; ranges[1] = Infinity; }  // REP 117: invalid, no return
    out.push({ topic: "/scan", type: "sensor_msgs/msg/LaserScan", time: ns(received) + 3000n, msg: {
      header: { stamp: s, frame_id: "laser" },
      angle_min: -Math.PI / 2, angle_max: -Math.PI / 2 + 179 * Math.PI / 180,
      angle_increment: Math.PI / 180, time_increment: 0, scan_time: 0.2,
      range_min: 0, range_max: 80,
      ranges: Float32Array.from(ranges),
      intensities: Float32Array.from(k === 0 ? new Array(180).fill(100) : []),
    } });
    out.push({ topic: "/ground_truth", type: "geometry_msgs/msg/PoseStamped", time: ns(received) + 4000n,
      msg: { header: { stamp: s, frame_id: "map" },
             pose: { position: { x: r.pose[0], y: r.pose[1], z: 0 }, orientation: quat(r.pose[2]) } } });
  }
  out.sort((a, b) => (a.time < b.time ? -1 : a.time > b.time ? 1 : 0));
  for (const m of out) m.data = writers[m.type].writeMessage(m.msg);
  return out;
}

// ---- ROS 1 bags (format 2.0) -----------------------------------------------------------------------
// No npm package writes them: the container is written here by its specification, and read back
// with @foxglove/rosbag, an independent reader, before it is kept. The messages are serialised by
// @foxglove/rosmsg-serialization.
const ROS1_HEADER = "Header\nuint32 seq\ntime stamp\nstring frame_id";
const ros1Def = (type) => DEFS[type].replaceAll(SEP + HEADER, SEP + ROS1_HEADER)
  .replace(/^std_msgs\/Header header$/m, "Header header")
  .replaceAll("MSG: geometry_msgs/TransformStamped\nstd_msgs/Header header",
              "MSG: geometry_msgs/TransformStamped\nHeader header")
  .replace(/^(float64 [xyzw]) [01]$/gm, "$1");  // ROS 1 has no default values
const ros1Type = (type) => type.replace("/msg/", "/");
const ros1Parsed = Object.fromEntries(Object.keys(DEFS).map((t) => [t, parse(fixHeader(ros1Def(t)))]));
function fixHeader(def) {  // "MSG: Header ..." is std_msgs/Header in ROS 1
  return def.replaceAll("MSG: Header\n", "MSG: std_msgs/Header\n");
}
const ros1Writers = Object.fromEntries(Object.entries(ros1Parsed).map(([t, d]) => [t, new Ros1Writer(d)]));

const u32 = (v) => { const b = Buffer.alloc(4); b.writeUInt32LE(v); return b; };
const u64 = (v) => { const b = Buffer.alloc(8); b.writeBigUInt64LE(BigInt(v)); return b; };
const rosTime = (t) => Buffer.concat([u32(Number(t / 1000000000n)), u32(Number(t % 1000000000n))]);
const fields = (f) => Buffer.concat(Object.entries(f).map(([k, v]) => {
  const b = Buffer.concat([Buffer.from(k + "="), Buffer.isBuffer(v) ? v : Buffer.from(v)]);
  return Buffer.concat([u32(b.length), b]);
}));
const record = (header, data) => {
  const h = fields(header);
  return Buffer.concat([u32(h.length), h, u32(data.length), data]);
};
const OP = (n) => Buffer.from([n]);

function writeRos1(file, messages, compression) {
  const conns = new Map();
  for (const m of messages)
    if (!conns.has(m.topic)) conns.set(m.topic, { id: conns.size, type: m.type });
  const connRecord = (topic) => {
    const c = conns.get(topic);
    return record({ op: OP(0x07), conn: u32(c.id), topic },
                  fields({ topic, type: ros1Type(c.type), md5sum: md5(ros1Parsed[c.type]),
                           message_definition: fixHeader(ros1Def(c.type)) }));
  };
  const HEADER_BYTES = 4096;
  const parts = [];
  let pos = 13 + HEADER_BYTES;
  const chunkInfos = [];
  for (let first = 0; first < messages.length; first += 40) {
    const batch = messages.slice(first, first + 40);
    const inner = [], index = new Map(), seen = new Set();
    let offset = 0;
    for (const m of batch) {
      if (!seen.has(m.topic)) {
        seen.add(m.topic);
        const r = connRecord(m.topic);
        inner.push(r);
        offset += r.length;
      }
      const c = conns.get(m.topic);
      if (!index.has(c.id)) index.set(c.id, []);
      index.get(c.id).push([m.time, offset]);
      const data = Buffer.from(ros1Writers[m.type].writeMessage(m.msg));
      const r = record({ op: OP(0x02), conn: u32(c.id), time: rosTime(m.time) }, data);
      inner.push(r);
      offset += r.length;
    }
    const raw = Buffer.concat(inner);
    const packed = compression === "lz4" ? Buffer.from(lz4.compress(raw))
      : compression === "bz2" ? Buffer.from(compressjs.Bzip2.compressFile(raw)) : raw;
    const chunk = record({ op: OP(0x05), compression, size: u32(raw.length) }, packed);
    const indexes = [...index.entries()].map(([id, list]) =>
      record({ op: OP(0x04), ver: u32(1), conn: u32(id), count: u32(list.length) },
             Buffer.concat(list.map(([t, o]) => Buffer.concat([rosTime(t), u32(o)])))));
    chunkInfos.push({ pos, start: batch[0].time, end: batch[batch.length - 1].time,
                      counts: [...index.entries()].map(([id, l]) => [id, l.length]) });
    parts.push(chunk, ...indexes);
    pos += chunk.length + indexes.reduce((n, b) => n + b.length, 0);
  }
  const indexPos = pos;
  for (const topic of conns.keys()) parts.push(connRecord(topic));
  for (const c of chunkInfos)
    parts.push(record({ op: OP(0x06), ver: u32(1), chunk_pos: u64(c.pos), start_time: rosTime(c.start),
                        end_time: rosTime(c.end), count: u32(c.counts.length) },
                      Buffer.concat(c.counts.map(([id, n]) => Buffer.concat([u32(id), u32(n)])))));
  const headerFields = fields({ op: OP(0x03), index_pos: u64(indexPos), conn_count: u32(conns.size),
                                chunk_count: u32(chunkInfos.length) });
  const padding = Buffer.alloc(HEADER_BYTES - 8 - headerFields.length, 0x20);
  const bagHeader = Buffer.concat([u32(headerFields.length), headerFields, u32(padding.length), padding]);
  const bytes = Buffer.concat([Buffer.from("#ROSBAG V2.0\n"), bagHeader, ...parts]);
  fs.writeFileSync(path.join(here, file), bytes);
  return bytes;
}

/// Reads a ROS 1 bag back with @foxglove/rosbag; throws unless every message is there as written.
async function checkRos1(file, messages) {
  const bzip2 = await Bzip2.init();
  await lz4Decompress.isLoaded;
  const bag = new Bag(new rosbagNode.FileReader(path.join(here, file)), {
    decompress: { lz4: (b, n) => lz4Decompress(b, n), bz2: (b, n) => bzip2.decompress(b, n, { small: false }) },
  });
  await bag.open();
  const read = [];
  for await (const r of bag.messageIterator()) read.push(r);
  if (read.length !== messages.length) throw new Error(`${file}: read ${read.length} of ${messages.length}`);
  const scan = read.find((r) => r.topic === "/scan").message;
  const first = messages.find((m) => m.topic === "/scan").msg;
  if (scan.ranges[5] !== first.ranges[5] || scan.header.stamp.nsec !== first.header.stamp.nsec)
    throw new Error(`${file}: the first scan does not read back`);
}

// ---- MCAP ----------------------------------------------------------------------------------------
class Buffered {
  chunks = []; size = 0n;
  position() { return this.size; }
  async write(b) { this.chunks.push(Buffer.from(b)); this.size += BigInt(b.byteLength); }
  bytes() { return Buffer.concat(this.chunks); }
}

async function writeMcap(file, messages, options) {
  const out = new Buffered();
  const w = new McapWriter({ writable: out, ...options });
  await w.start({ profile: "ros2", library: "@mcap/core" });
  const channels = new Map();
  for (const m of messages) {
    if (!channels.has(m.topic)) {
      const schemaId = await w.registerSchema({ name: m.type, encoding: "ros2msg",
                                                data: new TextEncoder().encode(DEFS[m.type]) });
      channels.set(m.topic, await w.registerChannel({ topic: m.topic, schemaId,
                                                      messageEncoding: "cdr", metadata: new Map() }));
    }
  }
  let seq = 0;
  for (const m of messages)
    await w.addMessage({ channelId: channels.get(m.topic), sequence: seq++, logTime: m.time,
                         publishTime: m.time, data: m.data });
  await w.end();
  fs.writeFileSync(path.join(here, file), out.bytes());
}

// ---- rosbag2 SQLite ------------------------------------------------------------------------------
async function writeDb3(folder, messages) {
  const SQL = await initSqlJs();
  const db = new SQL.Database();
  db.run("CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);");
  db.run("INSERT INTO schema VALUES (3, 'humble');");
  db.run("CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, " +
         "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);");
  db.run("CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, " +
         "timestamp INTEGER NOT NULL, data BLOB NOT NULL);");
  const ids = new Map();
  for (const m of messages)
    if (!ids.has(m.topic)) {
      ids.set(m.topic, ids.size + 1);
      db.run("INSERT INTO topics VALUES (?, ?, ?, 'cdr', '')", [ids.get(m.topic), m.topic, m.type]);
    }
  for (const m of messages)
    db.run("INSERT INTO messages(topic_id, timestamp, data) VALUES (?, ?, ?)",
           [ids.get(m.topic), Number(m.time), m.data]);
  const dir = path.join(here, folder);
  fs.mkdirSync(dir, { recursive: true });
  const name = `${folder}_0.db3`;
  fs.writeFileSync(path.join(dir, name), Buffer.from(db.export()));
  const counts = [...ids.keys()].map((t) => [t, messages.filter((m) => m.topic === t).length,
                                              messages.find((m) => m.topic === t).type]);
  const start = messages[0].time, end = messages[messages.length - 1].time;
  fs.writeFileSync(path.join(dir, "metadata.yaml"), [
    "rosbag2_bagfile_information:", "  version: 5", "  storage_identifier: sqlite3",
    "  duration:", `    nanoseconds: ${end - start}`, "  starting_time:",
    `    nanoseconds_since_epoch: ${start}`, `  message_count: ${messages.length}`,
    "  topics_with_message_count:",
    ...counts.flatMap(([t, n, type]) => ["    - topic_metadata:", `        name: ${t}`,
      `        type: ${type}`, "        serialization_format: cdr",
      "        offered_qos_profiles: \"\"", `      message_count: ${n}`]),
    "  compression_format: \"\"", "  compression_mode: \"\"", "  relative_file_paths:",
    `    - ${name}`, "",
  ].join("\n"));
}

// ---- the fixtures --------------------------------------------------------------------------------
await zstd.isLoaded;
const messages = intelMessages();
await writeMcap("intel-zstd.mcap", messages, { chunkSize: 16384,
  compressChunk: (d) => ({ compression: "zstd", compressedData: zstd.compress(d, 19) }) });
await writeMcap("intel-lz4.mcap", messages, { chunkSize: 16384,
  compressChunk: (d) => ({ compression: "lz4", compressedData: lz4.compress(d) }) });
// Uncompressed chunks, and no summary at all: the reader must scan the file.
await writeMcap("intel-plain.mcap", messages, { chunkSize: 16384, useSummaryOffsets: false,
  useStatistics: false, useChunkIndex: false, useMessageIndex: false, repeatSchemas: false,
  repeatChannels: false });
await writeDb3("intel-rosbag2", messages);
const ros1 = messages.filter((m) => m.topic !== "/tf");
for (const [file, compression] of [["intel.bag", "none"], ["intel-lz4.bag", "lz4"], ["intel-bz2.bag", "bz2"]]) {
  writeRos1(file, ros1, compression);
  await checkRos1(file, ros1);
}
// Scan 20 stamped before scan 19: a time that runs backwards.
const back = intelMessages({ scanTime: (k) => flaser[k === 20 ? 18 : k].time + SCAN_DELAY });
await writeMcap("backwards.mcap", back.filter((m) => m.topic === "/scan" || m.topic === "/odom"),
                { compressChunk: (d) => ({ compression: "zstd", compressedData: zstd.compress(d, 19) }) });
console.log("wrote", fs.readdirSync(here).filter((f) => !f.includes("node_modules")).join(" "));
