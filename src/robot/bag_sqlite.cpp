// rosbag2's SQLite storage (.db3): tables topics(id, name, type, serialization_format, ...) and
// messages(id, topic_id, timestamp, data), read through SQLite itself.
#include <sqlite3.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <memory>
#include <system_error>

#include "bag_formats.hpp"

namespace implicit::robot::bag_detail {
namespace {

struct SqliteCloser {
  void operator()(sqlite3* db) const { sqlite3_close(db); }
};
struct StatementCloser {
  void operator()(sqlite3_stmt* s) const { sqlite3_finalize(s); }
};
using SqliteDb = std::unique_ptr<sqlite3, SqliteCloser>;
using SqliteStatement = std::unique_ptr<sqlite3_stmt, StatementCloser>;

[[noreturn]] void sqlite_fail(std::string_view name, sqlite3* db, std::string_view doing) {
  throw ParseError(fmt::format("{}: expected a rosbag2 SQLite database: {}: {}", name, doing,
                               db != nullptr ? sqlite3_errmsg(db) : "out of memory"));
}

SqliteDb open_file(const std::filesystem::path& file, std::string_view name) {
  sqlite3* raw = nullptr;
  const int rc = sqlite3_open_v2(file.c_str(), &raw, SQLITE_OPEN_READONLY, nullptr);
  SqliteDb db(raw);
  if (rc != SQLITE_OK) sqlite_fail(name, raw, "cannot open it");
  return db;
}

/// An in-memory database holding a copy of `bytes` (the fuzz target and parse_bag).
SqliteDb open_bytes(std::string_view bytes, std::string_view name) {
  sqlite3* raw = nullptr;
  if (sqlite3_open_v2(":memory:", &raw, SQLITE_OPEN_READWRITE, nullptr) != SQLITE_OK)
    sqlite_fail(name, raw, "cannot open an in-memory database");
  SqliteDb db(raw);
  const auto n = static_cast<sqlite3_int64>(bytes.size());
  auto* copy = static_cast<unsigned char*>(sqlite3_malloc64(static_cast<sqlite3_uint64>(n) + 1));
  if (copy == nullptr) throw std::bad_alloc();
  if (n > 0) std::memcpy(copy, bytes.data(), bytes.size());
  const int rc = sqlite3_deserialize(db.get(), "main", copy, n, n,
                                     SQLITE_DESERIALIZE_FREEONCLOSE | SQLITE_DESERIALIZE_READONLY);
  if (rc != SQLITE_OK) sqlite_fail(name, db.get(), "cannot load it");
  return db;
}

SqliteStatement prepare_statement(sqlite3* db, const char* sql, std::string_view name) {
  sqlite3_stmt* raw = nullptr;
  if (sqlite3_prepare_v2(db, sql, -1, &raw, nullptr) != SQLITE_OK)
    sqlite_fail(name, db, fmt::format("query '{}'", sql));
  return SqliteStatement(raw);
}

std::string column_text(sqlite3_stmt* s, int col) {
  const unsigned char* t = sqlite3_column_text(s, col);
  return t != nullptr ? std::string(reinterpret_cast<const char*>(t),
                                    static_cast<std::size_t>(sqlite3_column_bytes(s, col)))
                      : std::string();
}

/// SQLite reads the pages a file lacks as empty: a truncated file would read as a shorter bag.
/// The header (the first 100 bytes) states the page size and count.
void require_complete(std::string_view head, std::uintmax_t size, std::string_view name) {
  if (head.size() < 100)
    throw ParseError(
        fmt::format("{}: expected a SQLite header of 100 bytes, got {} bytes (a "
                    "truncated file?)",
                    name, head.size()));
  auto byte = [&](std::size_t i) {
    return static_cast<std::uint32_t>(static_cast<unsigned char>(head[i]));
  };
  std::uint64_t page = (byte(16) << 8) | byte(17);
  if (page == 1) page = 65536;
  const std::uint64_t pages = (byte(28) << 24) | (byte(29) << 16) | (byte(30) << 8) | byte(31);
  if (page * pages > size)
    throw ParseError(
        fmt::format("{}: expected {} pages of {} bytes ({} bytes), got {} bytes (a "
                    "truncated file?)",
                    name, pages, page, page * pages, size));
}

}  // namespace

BagContents read_rosbag2_sqlite(const std::filesystem::path& file, std::string_view bytes,
                                std::string_view name, const std::vector<std::string>& topics) {
  if (file.empty()) {
    require_complete(bytes.substr(0, 100), bytes.size(), name);
  } else {
    std::ifstream in(file, std::ios::binary);
    std::string head(100, '\0');
    in.read(head.data(), 100);
    head.resize(static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
    std::error_code ec;
    require_complete(head, std::filesystem::file_size(file, ec), name);
  }
  SqliteDb db = file.empty() ? open_bytes(bytes, name) : open_file(file, name);
  BagContents b;
  b.source = std::string(name);
  b.format = "rosbag2 SQLite";
  std::vector<std::int64_t> ids;
  std::vector<bool> wanted;
  {
    SqliteStatement s = prepare_statement(db.get(),
                                          "SELECT id, name, type, serialization_format FROM topics "
                                          "ORDER BY id",
                                          name);
    int rc = 0;
    while ((rc = sqlite3_step(s.get())) == SQLITE_ROW) {
      BagTopic t;
      t.name = column_text(s.get(), 1);
      t.type = column_text(s.get(), 2);
      const std::string format = column_text(s.get(), 3);
      if (format == "ros1")
        t.encoding = BagEncoding::kRos1;
      else if (format != "cdr")
        t.type = fmt::format("{} (serialization_format '{}')", t.type, printable(format, 40));
      ids.push_back(sqlite3_column_int64(s.get(), 0));
      wanted.push_back(bag_wants(topics, t.name));
      b.topics.push_back(std::move(t));
    }
    if (rc != SQLITE_DONE) sqlite_fail(name, db.get(), "reading the topics table");
  }
  SqliteStatement s = prepare_statement(db.get(),
                                        "SELECT topic_id, timestamp, data FROM messages "
                                        "ORDER BY timestamp, id",
                                        name);
  int rc = 0;
  std::size_t row = 0;
  while ((rc = sqlite3_step(s.get())) == SQLITE_ROW) {
    const std::int64_t id = sqlite3_column_int64(s.get(), 0);
    std::size_t k = 0;
    while (k < ids.size() && ids[k] != id) ++k;
    if (k == ids.size())
      throw ParseError(
          fmt::format("{}: message {} (by time): expected a topic_id of the topics "
                      "table, got {}",
                      name, row, id));
    ++row;
    if (!wanted[k]) continue;
    BagMessage m;
    m.topic = k;
    m.time_ns = sqlite3_column_int64(s.get(), 1);
    const void* blob = sqlite3_column_blob(s.get(), 2);
    const auto n = static_cast<std::size_t>(sqlite3_column_bytes(s.get(), 2));
    if (blob != nullptr) m.data.assign(static_cast<const char*>(blob), n);
    b.messages.push_back(std::move(m));
  }
  if (rc != SQLITE_DONE) sqlite_fail(name, db.get(), "reading the messages table");
  return b;
}

}  // namespace implicit::robot::bag_detail
