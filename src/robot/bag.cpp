// Bag files: the format from the first bytes, rosbag2 folders (metadata.yaml), decompression.
#include <algorithm>
#include <array>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <system_error>

#include <bzlib.h>
#include <lz4frame.h>
#include <yaml-cpp/yaml.h>
#include <zlib.h>
#include <zstd.h>

#include "bag_formats.hpp"

namespace implicit::robot {
namespace bag_detail {
namespace {

constexpr std::string_view kMcapMagic("\x89MCAP0\r\n", 8);
constexpr std::string_view kRos1Magic("#ROSBAG V2.0\n", 13);
constexpr std::string_view kSqliteMagic("SQLite format 3\0", 16);
// A bag is read whole into memory; beyond this a message, not the OOM killer.
constexpr std::uintmax_t kMaxBagFileBytes = std::uintmax_t{8} << 30;

enum class Format { kNone, kMcap, kRos1, kSqlite };

Format format_of(std::string_view head) {
  if (head.starts_with(kMcapMagic)) return Format::kMcap;
  if (head.starts_with(kRos1Magic)) return Format::kRos1;
  if (head.starts_with(kSqliteMagic)) return Format::kSqlite;
  return Format::kNone;
}

std::string read_head(const std::filesystem::path& file, std::size_t n) {
  std::ifstream in(file, std::ios::binary);
  std::string head(n, '\0');
  in.read(head.data(), static_cast<std::streamsize>(n));
  head.resize(static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  return head;
}

std::string read_whole_file(const std::filesystem::path& file) {
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(file, ec);
  if (ec) throw ParseError(fmt::format("{}: cannot read the bag: {}", file.string(), ec.message()));
  if (size > kMaxBagFileBytes)
    throw ParseError(fmt::format("{}: expected a bag of at most {} GiB (read whole), got {} bytes",
                                 file.string(), kMaxBagFileBytes >> 30, size));
  std::ifstream in(file, std::ios::binary);
  std::string bytes(static_cast<std::size_t>(size), '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(size));
  if (!in || static_cast<std::uintmax_t>(in.gcount()) != size)
    throw ParseError(fmt::format("{}: cannot read the bag's {} bytes", file.string(), size));
  return bytes;
}

/// Adds `part` (one file of a split rosbag2) to `all`, topics merged by name.
void merge_into(BagContents& all, BagContents&& part) {
  std::vector<std::size_t> index(part.topics.size());
  for (std::size_t i = 0; i < part.topics.size(); ++i) {
    std::size_t k = all.find_topic(part.topics[i].name);
    if (k == all.topics.size()) all.topics.push_back(part.topics[i]);
    index[i] = k;
  }
  for (BagMessage& m : part.messages) {
    m.topic = index[m.topic];
    all.messages.push_back(std::move(m));
  }
  if (all.format.empty()) all.format = part.format;
}

/// A rosbag2 folder: its metadata.yaml names the storage and the files, in order.
BagContents read_rosbag2_folder(const std::filesystem::path& dir,
                                const std::vector<std::string>& topics);

BagContents read_bag_file(const std::filesystem::path& file,
                          const std::vector<std::string>& topics) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec))
    throw ParseError(fmt::format(
        "{}: expected a bag file (.db3, .mcap, .bag) or a rosbag2 folder "
        "with metadata.yaml, got {}",
        file.string(), std::filesystem::exists(file, ec) ? "something else" : "no such file"));
  if (format_of(read_head(file, 16)) == Format::kSqlite)
    return read_rosbag2_sqlite(file, {}, file.string(), topics);
  const std::string bytes = read_whole_file(file);
  return parse_bag(bytes, file.string(), topics);
}

BagContents read_rosbag2_folder(const std::filesystem::path& dir,
                                const std::vector<std::string>& topics) {
  const std::filesystem::path meta = dir / "metadata.yaml";
  std::vector<std::string> files;
  try {
    const YAML::Node info = YAML::LoadFile(meta.string())["rosbag2_bagfile_information"];
    if (!info)
      throw ParseError(
          fmt::format("{}: expected a 'rosbag2_bagfile_information' map", meta.string()));
    const std::string compression =
        info["compression_format"] ? info["compression_format"].as<std::string>() : "";
    if (!compression.empty())
      throw ParseError(
          fmt::format("{}: compression_format '{}': expected an uncompressed rosbag2 "
                      "(decompress it with 'ros2 bag convert' first)",
                      meta.string(), printable(compression)));
    for (const YAML::Node& f : info["relative_file_paths"]) files.push_back(f.as<std::string>());
  } catch (const YAML::Exception& e) {
    throw ParseError(fmt::format("{}: expected rosbag2 metadata: {}", meta.string(), e.what()));
  }
  if (files.empty())
    throw ParseError(fmt::format(
        "{}: expected relative_file_paths naming the bag's files, got none", meta.string()));
  BagContents all;
  all.source = dir.string();
  for (const std::string& f : files) merge_into(all, read_bag_file(dir / f, topics));
  bag_sort_messages(all);
  return all;
}

}  // namespace

std::string bag_decompress(std::string_view method, std::string_view in, std::uint64_t size,
                           std::string_view where) {
  if (method.empty() || method == "none") {
    if (in.size() != size)
      throw ParseError(fmt::format("{}: expected {} bytes, got {}", where, size, in.size()));
    return std::string(in);
  }
  std::string out;
  std::array<char, 65536> buf{};
  auto append = [&](std::size_t n) {
    if (out.size() + n > size)
      throw ParseError(
          fmt::format("{}: {} data decompresses to more than the {} bytes stated "
                      "(corrupt?)",
                      where, method, size));
    out.append(buf.data(), n);
  };
  bool ok = false;
  if (method == "zstd") {
    // Freed however the loop ends (append throws on output beyond `size`).
    const std::unique_ptr<ZSTD_DCtx, decltype(&ZSTD_freeDCtx)> ctx(ZSTD_createDCtx(),
                                                                   &ZSTD_freeDCtx);
    if (!ctx) throw std::bad_alloc();
    ZSTD_DCtx* z = ctx.get();
    ZSTD_inBuffer src{in.data(), in.size(), 0};
    std::size_t r = 1;
    for (;;) {  // frame after frame, until the input ends
      ZSTD_outBuffer dst{buf.data(), buf.size(), 0};
      r = ZSTD_decompressStream(z, &dst, &src);
      if (ZSTD_isError(r)) break;
      append(dst.pos);
      if (src.pos == src.size && (r == 0 || dst.pos < dst.size)) break;
    }
    ok = r == 0;
  } else if (method == "lz4") {
    LZ4F_dctx* z = nullptr;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&z, LZ4F_VERSION))) throw std::bad_alloc();
    const std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> ctx(
        z, &LZ4F_freeDecompressionContext);
    std::size_t pos = 0, r = 1;
    while (r != 0 && pos < in.size()) {
      std::size_t n_out = buf.size(), n_in = in.size() - pos;
      r = LZ4F_decompress(z, buf.data(), &n_out, in.data() + pos, &n_in, nullptr);
      if (LZ4F_isError(r)) break;
      pos += n_in;
      append(n_out);
      if (n_in == 0 && n_out == 0) break;
    }
    ok = r == 0 && pos == in.size();
  } else if (method == "bz2") {
    bz_stream s{};
    if (BZ2_bzDecompressInit(&s, 0, 0) != BZ_OK) throw std::bad_alloc();
    const std::unique_ptr<bz_stream, decltype(&BZ2_bzDecompressEnd)> ctx(&s, &BZ2_bzDecompressEnd);
    s.next_in = const_cast<char*>(in.data());  // bzlib's interface is not const; it only reads
    s.avail_in = static_cast<unsigned>(std::min<std::size_t>(in.size(), UINT32_MAX));
    int r = BZ_OK;
    while (r == BZ_OK) {
      s.next_out = buf.data();
      s.avail_out = static_cast<unsigned>(buf.size());
      r = BZ2_bzDecompress(&s);
      if (r != BZ_OK && r != BZ_STREAM_END) break;
      const std::size_t n = buf.size() - s.avail_out;
      append(n);
      if (r == BZ_OK && n == 0 && s.avail_in == 0) break;  // input ends early
    }
    ok = r == BZ_STREAM_END && s.avail_in == 0 && in.size() <= UINT32_MAX;
  } else {
    throw ParseError(fmt::format("{}: compression '{}': expected none, zstd, lz4 or bz2", where,
                                 printable(method, 40)));
  }
  if (!ok || out.size() != size)
    throw ParseError(fmt::format(
        "{}: expected {} data that decompresses to {} bytes, got {} "
        "(corrupt or truncated)",
        where, method, size, ok ? fmt::format("{} bytes", out.size()) : std::string("an error")));
  return out;
}

std::uint32_t bag_crc32(std::string_view data) {
  uLong crc = crc32(0L, Z_NULL, 0);
  std::size_t pos = 0;
  while (pos < data.size()) {  // zlib takes at most 4 GiB per call
    const auto n = static_cast<uInt>(std::min<std::size_t>(data.size() - pos, 1u << 30));
    crc = crc32(crc, reinterpret_cast<const Bytef*>(data.data() + pos), n);
    pos += n;
  }
  return static_cast<std::uint32_t>(crc);
}

void bag_sort_messages(BagContents& bag) {
  std::stable_sort(bag.messages.begin(), bag.messages.end(),
                   [](const BagMessage& a, const BagMessage& b) { return a.time_ns < b.time_ns; });
}

}  // namespace bag_detail

std::size_t BagContents::find_topic(std::string_view name) const {
  for (std::size_t i = 0; i < topics.size(); ++i)
    if (topics[i].name == name) return i;
  return topics.size();
}

bool is_bag(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    return std::filesystem::exists(path / "metadata.yaml", ec);
  if (!std::filesystem::is_regular_file(path, ec)) return false;
  return bag_detail::format_of(bag_detail::read_head(path, 16)) != bag_detail::Format::kNone;
}

BagContents read_bag(const std::filesystem::path& path, const std::vector<std::string>& topics) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return bag_detail::read_rosbag2_folder(path, topics);
  return bag_detail::read_bag_file(path, topics);
}

BagContents parse_bag(std::string_view bytes, std::string_view name,
                      const std::vector<std::string>& topics) {
  switch (bag_detail::format_of(bytes)) {
    case bag_detail::Format::kMcap:
      return bag_detail::parse_mcap(bytes, name, topics);
    case bag_detail::Format::kRos1:
      return bag_detail::parse_ros1_bag(bytes, name, topics);
    case bag_detail::Format::kSqlite:
      return bag_detail::read_rosbag2_sqlite({}, bytes, name, topics);
    case bag_detail::Format::kNone:
      break;
  }
  throw ParseError(fmt::format(
      "{}: expected a ROS bag (an MCAP file, a rosbag2 SQLite file or a ROS 1 bag of format "
      "2.0), got a file that starts with '{}'",
      name, printable(bytes.substr(0, 16))));
}

}  // namespace implicit::robot
