// ROS 1 bags, format 2.0: after "#ROSBAG V2.0\n", records of a header (fields "name=value", each
// with a 4-byte length; "op" tells the kind) and data, each with a 4-byte length. Chunks hold the
// connections and messages, uncompressed, bz2 or lz4; the index after them is not needed for a
// read from start to end.
#include <map>

#include "bag_formats.hpp"

namespace implicit::robot::bag_detail {
namespace {

constexpr std::size_t kRos1MagicBytes = 13;

enum Ros1Op : std::uint8_t {
  kRos1Message = 0x02,
  kRos1BagHeader = 0x03,
  kRos1Chunk = 0x05,
  kRos1Connection = 0x07,
};

/// The fields of a record header (or of a connection header).
std::map<std::string, std::string_view, std::less<>> ros1_fields(std::string_view header,
                                                                 std::string_view name,
                                                                 std::size_t base) {
  std::map<std::string, std::string_view, std::less<>> fields;
  ByteReader r(header, name, base);
  while (!r.done()) {
    const auto n = r.le<std::uint32_t>("a header field's length");
    const std::string_view f = r.take(n, "a header field");
    const std::size_t eq = f.find('=');
    if (eq == std::string_view::npos)
      r.fail(fmt::format("expected a header field 'name=value', got '{}'", printable(f, 40)));
    fields.emplace(std::string(f.substr(0, eq)), f.substr(eq + 1));
  }
  return fields;
}

std::string_view ros1_field(const std::map<std::string, std::string_view, std::less<>>& fields,
                            std::string_view field, std::size_t bytes, const ByteReader& r) {
  const auto f = fields.find(field);
  if (f == fields.end() || (bytes > 0 && f->second.size() != bytes))
    r.fail(fmt::format(
        "expected a record header field '{}'{}, got {}", field,
        bytes > 0 ? fmt::format(" of {} bytes", bytes) : std::string(),
        f == fields.end() ? std::string("none") : fmt::format("{} bytes", f->second.size())));
  return f->second;
}

std::uint64_t ros1_number(std::string_view bytes) {
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < bytes.size(); ++i)
    v |= static_cast<std::uint64_t>(static_cast<unsigned char>(bytes[i])) << (8 * i);
  return v;
}

class Ros1Reader {
 public:
  Ros1Reader(std::string_view name, const std::vector<std::string>& topics)
      : name_(name), topics_(topics) {}

  void records(std::string_view data, std::size_t base, bool top_level) {
    ByteReader r(data, name_, base);
    while (!r.done()) {
      const std::size_t at = r.pos();
      const auto header_length = r.le<std::uint32_t>("a record's header length");
      const std::string_view header = r.take(header_length, "a record's header");
      const auto data_length = r.le<std::uint32_t>("a record's data length");
      const std::string_view content = r.take(data_length, "a record's data");
      const auto fields = ros1_fields(header, name_, base + at + 4);
      ByteReader here(data, name_, base);
      here.seek(at);
      const auto op = static_cast<std::uint8_t>(ros1_field(fields, "op", 1, here)[0]);
      if (op == kRos1Chunk && top_level) {
        const std::string_view compression = ros1_field(fields, "compression", 0, here);
        const std::uint64_t size = ros1_number(ros1_field(fields, "size", 4, here));
        const std::string where = fmt::format("{}: chunk at byte {}", name_, base + at);
        const std::string inner = bag_decompress(
            compression == "none" ? std::string_view() : compression, content, size, where);
        records(
            inner,
            compression == "none" ? base + (data.size() - r.remaining()) - data_length : base + at,
            false);
      } else if (op == kRos1Connection) {
        connection(fields, content, here, base + (data.size() - r.remaining()) - data_length);
      } else if (op == kRos1Message) {
        message(fields, content, here);
      }
    }
  }

  BagContents finish() {
    BagContents b;
    b.source = std::string(name_);
    b.format = "ROS 1 bag";
    b.topics = std::move(found_);
    b.messages = std::move(messages_);
    bag_sort_messages(b);
    return b;
  }

 private:
  void connection(const std::map<std::string, std::string_view, std::less<>>& fields,
                  std::string_view content, const ByteReader& here, std::size_t content_base) {
    const auto id = static_cast<std::uint32_t>(ros1_number(ros1_field(fields, "conn", 4, here)));
    const std::string topic(ros1_field(fields, "topic", 0, here));
    const auto details = ros1_fields(content, name_, content_base);
    const std::string type(ros1_field(details, "type", 0, here));
    std::size_t k = 0;
    while (k < found_.size() && found_[k].name != topic) ++k;
    if (k == found_.size()) found_.push_back({topic, type, BagEncoding::kRos1});
    connections_[id] = k;
  }

  void message(const std::map<std::string, std::string_view, std::less<>>& fields,
               std::string_view content, const ByteReader& here) {
    const auto id = static_cast<std::uint32_t>(ros1_number(ros1_field(fields, "conn", 4, here)));
    const std::uint64_t time = ros1_number(ros1_field(fields, "time", 8, here));
    const auto c = connections_.find(id);
    if (c == connections_.end())
      here.fail(
          fmt::format("a message on connection {}, which no connection record before it "
                      "defines",
                      id));
    if (!bag_wants(topics_, found_[c->second].name)) return;
    BagMessage m;
    m.topic = c->second;
    m.time_ns = static_cast<std::int64_t>((time & 0xffffffffu) * 1000000000ull) +
                static_cast<std::int64_t>(time >> 32);
    m.data = std::string(content);
    messages_.push_back(std::move(m));
  }

  std::string_view name_;
  const std::vector<std::string>& topics_;
  std::map<std::uint32_t, std::size_t> connections_;
  std::vector<BagTopic> found_;
  std::vector<BagMessage> messages_;
};

}  // namespace

BagContents parse_ros1_bag(std::string_view bytes, std::string_view name,
                           const std::vector<std::string>& topics) {
  Ros1Reader reader(name, topics);
  reader.records(bytes.substr(kRos1MagicBytes), kRos1MagicBytes, true);
  return reader.finish();
}

}  // namespace implicit::robot::bag_detail
