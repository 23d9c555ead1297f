// Writes the ROS bag fixtures of this folder with writers that are not the project's: MCAP files
// with @mcap/core's McapWriter, rosbag2 SQLite files with sql.js, messages serialised by
// @foxglove/rosmsg2-serialization (CDR). The data: 30 scans and 31 odometry poses from the first
// 31 laser messages of data/carmen/intel-corrected.log.gz (README.md in this folder says which
// and how; tests/robot/bag_test.cpp checks the readers against the same values).
//
//   cd tests/data/bags && npm ci && node generate.mjs
import fs from "node:fs";
import path from "node:path";
import zlib from "node:zlib";
import { fileURLToPath } from "node:url";

import { McapWriter } from "@mcap/core";
import { parse } from "@foxglove/rosmsg";
import { MessageWriter } from "@foxglove/rosmsg2-serialization";
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
  return { sec, nanosec: Math.round((t - sec) * 1e9) };
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
// Scan 20 stamped before scan 19: a time that runs backwards.
const back = intelMessages({ scanTime: (k) => flaser[k === 20 ? 18 : k].time + SCAN_DELAY });
await writeMcap("backwards.mcap", back.filter((m) => m.topic === "/scan" || m.topic === "/odom"),
                { compressChunk: (d) => ({ compression: "zstd", compressedData: zstd.compress(d, 19) }) });
console.log("wrote", fs.readdirSync(here).filter((f) => !f.includes("node_modules")).join(" "));
