// MCAP files (the ROS 2 default since Iron): the summary's chunk indexes when the file has them,
// else a linear scan of the data section. Records: opcode (1 byte), length (8), content.
#include <map>

#include "bag_formats.hpp"

namespace implicit::robot::bag_detail {
namespace {

constexpr std::size_t kMagicBytes = 8;
constexpr std::size_t kFooterBytes = 1 + 8 + 20;  // opcode, length, three fields

enum McapOp : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kChunkIndex = 0x08,
  kDataEnd = 0x0F,
};

std::string_view mcap_string(ByteReader& r, std::string_view what) {
  const auto n = r.le<std::uint32_t>(what);
  return r.take(n, what);
}

struct McapChannel {
  std::string topic, encoding;
  std::uint16_t schema = 0;
};

/// What the records read so far define, and the messages kept.
class McapState {
 public:
  McapState(std::string_view name, const std::vector<std::string>& topics)
      : name_(name), topics_(topics) {}

  /// One record's content; `base` is its offset in the file (for messages).
  void record(std::uint8_t op, std::string_view content, std::size_t base) {
    ByteReader r(content, name_, base);
    if (op == kSchema) {
      const auto id = r.le<std::uint16_t>("Schema id");
      schemas_[id] = std::string(mcap_string(r, "Schema name"));
    } else if (op == kChannel) {
      const auto id = r.le<std::uint16_t>("Channel id");
      McapChannel c;
      c.schema = r.le<std::uint16_t>("Channel schema_id");
      c.topic = std::string(mcap_string(r, "Channel topic"));
      c.encoding = std::string(mcap_string(r, "Channel message_encoding"));
      channels_[id] = std::move(c);
    } else if (op == kMessage) {
      const auto id = r.le<std::uint16_t>("Message channel_id");
      r.le<std::uint32_t>("Message sequence");
      const auto log_time = r.le<std::uint64_t>("Message log_time");
      r.le<std::uint64_t>("Message publish_time");
      const auto c = channels_.find(id);
      if (c == channels_.end())
        r.fail(fmt::format("Message on channel {}, which no Channel record before it defines", id));
      if (!bag_wants(topics_, c->second.topic)) return;
      BagMessage m;
      m.topic = topic_index(c->second, r);
      m.time_ns = static_cast<std::int64_t>(log_time & 0x7fffffffffffffffULL);
      m.data = std::string(r.take(r.remaining(), "Message data"));
      messages_.push_back(std::move(m));
    } else if (op == kChunk) {
      chunk(content, base);
    }
  }

  /// Every record of `data` (a chunk's records, or the file from `from` to `to`).
  void records(std::string_view data, std::size_t base, bool top_level) {
    ByteReader r(data, name_, base);
    while (!r.done()) {
      const std::size_t at = r.pos();
      const auto op = r.le<std::uint8_t>("a record's opcode");
      const auto length = r.le<std::uint64_t>("a record's length");
      const std::string_view content = r.take(length, fmt::format("record 0x{:02x}'s content", op));
      if (top_level && (op == kDataEnd || op == kFooter)) {
        data_end_ = true;
        return;
      }
      if (top_level && op == kHeader && at != 0)
        r.fail("expected one Header record, at the start, got another");
      record(op, content, base + at + 9);
    }
  }

  BagContents finish() {
    BagContents b;
    b.source = std::string(name_);
    b.format = "MCAP";
    for (const auto& [id, c] : channels_) topic_index(c, ByteReader({}, name_));
    b.topics = std::move(topics_found_);
    b.messages = std::move(messages_);
    bag_sort_messages(b);
    return b;
  }

  bool data_end() const { return data_end_; }

 private:
  void chunk(std::string_view content, std::size_t base) {
    ByteReader r(content, name_, base);
    r.le<std::uint64_t>("Chunk message_start_time");
    r.le<std::uint64_t>("Chunk message_end_time");
    const auto size = r.le<std::uint64_t>("Chunk uncompressed_size");
    const auto crc = r.le<std::uint32_t>("Chunk uncompressed_crc");
    const std::string_view compression = mcap_string(r, "Chunk compression");
    const auto length = r.le<std::uint64_t>("Chunk records length");
    const std::size_t at = base + r.pos();
    const std::string_view packed = r.take(length, "Chunk records");
    const std::string where = fmt::format("{}: chunk at byte {}", name_, base - 9);
    const std::string records_data = bag_decompress(compression, packed, size, where);
    if (crc != 0 && bag_crc32(records_data) != crc)
      throw ParseError(fmt::format("{}: expected the records' CRC-32 {:08x}, got {:08x} (corrupt)",
                                   where, crc, bag_crc32(records_data)));
    // Offsets inside a compressed chunk are not file offsets: name the chunk's start.
    records(records_data, compression.empty() ? at : base - 9, false);
  }

  std::size_t topic_index(const McapChannel& c, const ByteReader& r) {
    for (std::size_t i = 0; i < topics_found_.size(); ++i)
      if (topics_found_[i].name == c.topic) return i;
    BagTopic t;
    t.name = c.topic;
    if (c.schema != 0) {
      const auto s = schemas_.find(c.schema);
      if (s == schemas_.end())
        r.fail(fmt::format("channel '{}' names schema {}, which no Schema record defines",
                           printable(c.topic), c.schema));
      t.type = s->second;
    }
    if (c.encoding == "cdr")
      t.encoding = BagEncoding::kCdr;
    else if (c.encoding == "ros1")
      t.encoding = BagEncoding::kRos1;
    else
      t.type = fmt::format("{} (message encoding '{}')", t.type, printable(c.encoding, 40));
    topics_found_.push_back(std::move(t));
    return topics_found_.size() - 1;
  }

  std::string_view name_;
  const std::vector<std::string>& topics_;
  std::map<std::uint16_t, std::string> schemas_;
  std::map<std::uint16_t, McapChannel> channels_;
  std::vector<BagTopic> topics_found_;
  std::vector<BagMessage> messages_;
  bool data_end_ = false;
};

/// The chunk records' offsets listed in the summary section, or none when the file has no
/// summary (or one without chunk indexes). Schemas and channels of the summary go to `state`.
std::vector<std::pair<std::uint64_t, std::uint64_t>> summary_chunks(std::string_view bytes,
                                                                    std::string_view name,
                                                                    McapState& state) {
  std::vector<std::pair<std::uint64_t, std::uint64_t>> chunks;
  const std::size_t footer = bytes.size() - kMagicBytes - kFooterBytes;
  ByteReader f(bytes.substr(footer, kFooterBytes), name, footer);
  if (f.le<std::uint8_t>("the Footer opcode") != kFooter)
    f.fail("expected the Footer record before the closing magic (a truncated or corrupt file?)");
  f.le<std::uint64_t>("the Footer length");
  const auto start = f.le<std::uint64_t>("Footer summary_start");
  if (start == 0) return chunks;
  if (start < kMagicBytes || start > footer)
    f.fail(fmt::format("expected summary_start within the file, got {}", start));
  ByteReader r(bytes.substr(0, footer), name);
  r.seek(static_cast<std::size_t>(start));
  while (!r.done()) {
    const std::size_t at = r.pos();
    const auto op = r.le<std::uint8_t>("a summary record's opcode");
    const auto length = r.le<std::uint64_t>("a summary record's length");
    const std::string_view content = r.take(length, "a summary record's content");
    if (op == kSchema || op == kChannel) state.record(op, content, at + 9);
    if (op != kChunkIndex) continue;
    ByteReader c(content, name, at + 9);
    c.le<std::uint64_t>("ChunkIndex message_start_time");
    c.le<std::uint64_t>("ChunkIndex message_end_time");
    const auto offset = c.le<std::uint64_t>("ChunkIndex chunk_start_offset");
    const auto chunk_length = c.le<std::uint64_t>("ChunkIndex chunk_length");
    if (offset < kMagicBytes || offset > start || chunk_length > start - offset)
      c.fail(
          fmt::format("expected a chunk within the data section (bytes 8 to {}), got {} bytes "
                      "at {}",
                      start, chunk_length, offset));
    chunks.emplace_back(offset, chunk_length);
  }
  return chunks;
}

}  // namespace

BagContents parse_mcap(std::string_view bytes, std::string_view name,
                       const std::vector<std::string>& topics) {
  McapState state(name, topics);
  const bool closed = bytes.size() >= 2 * kMagicBytes + kFooterBytes &&
                      bytes.substr(bytes.size() - kMagicBytes) == bytes.substr(0, kMagicBytes);
  if (!closed)
    throw ParseError(
        fmt::format("{}: byte {}: expected the MCAP magic closing the file, got none "
                    "(a truncated file, or one still being recorded?)",
                    name, bytes.size()));
  const auto chunks = summary_chunks(bytes, name, state);
  if (!chunks.empty()) {
    for (const auto& [offset, length] : chunks)
      state.records(
          bytes.substr(static_cast<std::size_t>(offset), static_cast<std::size_t>(length)),
          static_cast<std::size_t>(offset), false);
    return state.finish();
  }
  // No summary: every record from the header to the data end.
  state.records(bytes.substr(kMagicBytes, bytes.size() - 2 * kMagicBytes - kFooterBytes),
                kMagicBytes, true);
  if (!state.data_end())
    throw ParseError(
        fmt::format("{}: expected a DataEnd record after the data, got none (a "
                    "truncated or corrupt file?)",
                    name));
  return state.finish();
}

}  // namespace implicit::robot::bag_detail
