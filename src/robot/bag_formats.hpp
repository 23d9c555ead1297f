#pragma once
// The parts the bag readers share (robot/bag.hpp): a bounds-checked little-endian byte reader,
// chunk decompression, and one parser per file format.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include "implicit/core/error.hpp"
#include "implicit/robot/bag.hpp"

namespace implicit::robot::bag_detail {

/// Reads little-endian values from `data`; running past its end, or any `fail`, throws a
/// ParseError "where: byte N: ...", N counted from the file's start (`base` is data's offset).
class ByteReader {
 public:
  ByteReader(std::string_view data, std::string_view where, std::size_t base = 0)
      : data_(data), where_(where), base_(base) {}

  std::size_t pos() const { return pos_; }
  std::size_t remaining() const { return data_.size() - pos_; }
  bool done() const { return pos_ == data_.size(); }
  void seek(std::size_t p) {
    if (p > data_.size()) fail(fmt::format("expected an offset within the data, got {}", p));
    pos_ = p;
  }

  template <typename T>
  T le(std::string_view what) {
    const std::string_view b = take(sizeof(T), what);
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i)
      v |= static_cast<std::uint64_t>(static_cast<unsigned char>(b[i])) << (8 * i);
    return static_cast<T>(v);
  }

  std::string_view take(std::uint64_t n, std::string_view what) {
    if (n > remaining())
      fail(fmt::format("expected {} ({} bytes), got only {} bytes (a truncated or corrupt file?)",
                       what, n, remaining()));
    const std::string_view s = data_.substr(pos_, static_cast<std::size_t>(n));
    pos_ += static_cast<std::size_t>(n);
    return s;
  }

  [[noreturn]] void fail(std::string_view what) const {
    throw ParseError(fmt::format("{}: byte {}: {}", where_, base_ + pos_, what));
  }

 private:
  std::string_view data_;
  std::string_view where_;
  std::size_t base_ = 0;
  std::size_t pos_ = 0;
};

/// True when `topic` is kept (an empty list keeps every topic).
inline bool bag_wants(const std::vector<std::string>& topics, std::string_view topic) {
  if (topics.empty()) return true;
  for (const std::string& t : topics)
    if (t == topic) return true;
  return false;
}

/// Decompresses `in` by `method` ("zstd", "lz4" (frame format), "bz2"; "" or "none": a copy) to
/// exactly `size` bytes; otherwise a ParseError naming `where`. Memory grows with the output
/// produced, never to a stated size that the data does not reach.
std::string bag_decompress(std::string_view method, std::string_view in, std::uint64_t size,
                           std::string_view where);

/// CRC-32 (zlib's, as MCAP and others use).
std::uint32_t bag_crc32(std::string_view data);

/// Sorts the messages by receive time, keeping the file's order among equal times.
void bag_sort_messages(BagContents& bag);

BagContents parse_mcap(std::string_view bytes, std::string_view name,
                       const std::vector<std::string>& topics);
BagContents parse_ros1_bag(std::string_view bytes, std::string_view name,
                           const std::vector<std::string>& topics);
/// A rosbag2 SQLite file, read in place (`file`), or from memory (`bytes`, when file is empty).
BagContents read_rosbag2_sqlite(const std::filesystem::path& file, std::string_view bytes,
                                std::string_view name, const std::vector<std::string>& topics);

}  // namespace implicit::robot::bag_detail
