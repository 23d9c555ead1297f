// ROS map_server map files (map_io.hpp): the YAML with yaml-cpp, the PGM image by hand.
#include "implicit/robot/map_io.hpp"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "implicit/core/error.hpp"
#include "implicit/core/output_file.hpp"
#include "implicit/robot/csv_table.hpp"

namespace implicit::robot {
namespace {

enum class MapMode { kTrinary, kScale, kRaw };

struct MapYaml {
  std::string image;
  double resolution = 0.0;
  Vec<2> origin = Vec<2>::Zero();
  bool negate = false;
  double occupied_thresh = 0.0, free_thresh = 0.0;
  MapMode mode = MapMode::kTrinary;
};

// ---- The YAML file -----------------------------------------------------------------------

class MapYamlReader {
 public:
  MapYamlReader(std::string_view text, std::string name) : name_(std::move(name)) {
    try {
      root_ = YAML::Load(std::string(text));
    } catch (const YAML::Exception& e) {
      fail_at(e.mark,
              fmt::format("expected a YAML file, got a syntax error: {}", printable(e.msg)));
    }
    if (!root_.IsMap())
      throw ParseError(fmt::format(
          "{}: expected a YAML mapping with the keys image, resolution, origin, negate, "
          "occupied_thresh and free_thresh, got {}",
          name_, root_.IsNull() ? "an empty file" : "something else"));
  }

  MapYaml read() const {
    MapYaml m;
    m.image = scalar("image", "an image file name");
    require_at(!m.image.empty(), "image", "an image file name, got an empty one");
    m.resolution = number("resolution", "a positive number (metres per pixel)");
    require_at(m.resolution > 0, "resolution",
               fmt::format("a positive number (metres per pixel), got {}", m.resolution));
    read_origin(m);
    m.negate = flag("negate");
    m.occupied_thresh = threshold("occupied_thresh");
    m.free_thresh = threshold("free_thresh");
    require_at(
        m.free_thresh < m.occupied_thresh, "free_thresh",
        fmt::format("a value below occupied_thresh {}, got {}", m.occupied_thresh, m.free_thresh));
    if (root_["mode"]) {
      const std::string mode = scalar("mode", "trinary, scale or raw");
      if (mode == "trinary")
        m.mode = MapMode::kTrinary;
      else if (mode == "scale")
        m.mode = MapMode::kScale;
      else if (mode == "raw")
        m.mode = MapMode::kRaw;
      else
        fail_key("mode", fmt::format("expected trinary, scale or raw, got '{}'", printable(mode)));
    }
    return m;
  }

 private:
  [[noreturn]] void fail_at(const YAML::Mark& mark, const std::string& what) const {
    if (mark.is_null() || mark.line < 0) throw ParseError(fmt::format("{}: {}", name_, what));
    throw ParseError(fmt::format("{}:{}: {}", name_, mark.line + 1, what));
  }
  [[noreturn]] void fail_key(const char* key, const std::string& what) const {
    fail_at(root_[key].Mark(), fmt::format("key '{}': {}", key, what));
  }
  void require_at(bool ok, const char* key, const std::string& expected) const {
    if (!ok) fail_key(key, "expected " + expected);
  }

  YAML::Node node(const char* key, const char* expected) const {
    const YAML::Node n = root_[key];
    if (!n)
      throw ParseError(fmt::format("{}: key '{}': expected {}, got nothing (the key is missing)",
                                   name_, key, expected));
    return n;
  }
  std::string scalar(const char* key, const char* expected) const {
    const YAML::Node n = node(key, expected);
    if (!n.IsScalar()) fail_key(key, fmt::format("expected {}, got a list or mapping", expected));
    return n.Scalar();
  }
  static bool parse_number(std::string_view s, double* v) {
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    const auto r = std::from_chars(s.data(), s.data() + s.size(), *v);
    return r.ec == std::errc() && r.ptr == s.data() + s.size() && std::isfinite(*v);
  }
  double number(const char* key, const char* expected) const {
    const std::string s = scalar(key, expected);
    double v = 0.0;
    if (!parse_number(s, &v))
      fail_key(key, fmt::format("expected {}, got '{}'", expected, printable(s)));
    return v;
  }
  double threshold(const char* key) const {
    const double v = number(key, "a number in [0, 1]");
    require_at(v >= 0 && v <= 1, key, fmt::format("a number in [0, 1], got {}", v));
    return v;
  }
  bool flag(const char* key) const {
    const std::string s = scalar(key, "0 or 1");
    if (s == "0" || s == "false" || s == "False" || s == "FALSE") return false;
    if (s == "1" || s == "true" || s == "True" || s == "TRUE") return true;
    fail_key(key, fmt::format("expected 0 or 1, got '{}'", printable(s)));
  }
  void read_origin(MapYaml& m) const {
    const char* expected = "a list [x, y, yaw] of three numbers";
    const YAML::Node n = node("origin", expected);
    if (!n.IsSequence() || n.size() != 3)
      fail_key("origin", fmt::format("expected {}, got {}", expected,
                                     n.IsSequence() ? fmt::format("{} values", n.size())
                                                    : std::string("a single value")));
    double v[3];
    for (std::size_t k = 0; k < 3; ++k)
      if (!n[k].IsScalar() || !parse_number(n[k].Scalar(), &v[k]))
        fail_key("origin",
                 fmt::format("expected {}, got '{}' at position {}", expected,
                             n[k].IsScalar() ? printable(n[k].Scalar()) : "a list", k + 1));
    // map_server rotates the image about the origin; the grid here is axis-aligned.
    require_at(v[2] == 0, "origin",
               fmt::format("a yaw of 0, got {} (rotated maps are not supported: rotate the "
                           "image instead)",
                           v[2]));
    m.origin = Vec<2>(v[0], v[1]);
  }

  std::string name_;
  YAML::Node root_;
};

MapYaml read_map_yaml(std::string_view text, const std::string& name) {
  // yaml-cpp reports everything it refuses as a YAML::Exception; so does a lookup on a node of
  // an unexpected kind. Both become ParseErrors naming the file.
  try {
    return MapYamlReader(text, name).read();
  } catch (const YAML::Exception& e) {
    throw ParseError(
        fmt::format("{}: expected a map_server YAML file, got one yaml-cpp refuses: {}", name,
                    printable(e.msg)));
  }
}

// ---- The PGM image -----------------------------------------------------------------------

struct PgmImage {
  int width = 0, height = 0, maxval = 0;
  std::vector<std::uint16_t> pixels;  ///< row-major, the first row the top of the image
};

class PgmDecoder {
 public:
  PgmDecoder(std::string_view bytes, std::string name) : bytes_(bytes), name_(std::move(name)) {}

  PgmImage decode() {
    const bool binary = read_magic();
    PgmImage im;
    im.width = header_integer("width", 1);
    im.height = header_integer("height", 1);
    im.maxval = header_integer("maxval", 0);
    if (im.maxval < 1 || im.maxval > 65535)
      fail(fmt::format("field 'maxval': expected a maxval in 1..65535, got {}", im.maxval));
    if (binary)
      read_binary(im);
    else
      read_plain(im);
    return im;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw ParseError(fmt::format("{}:{}: {}", name_, line_, what));
  }

  bool read_magic() {
    if (bytes_.empty()) fail("expected a PGM image (P5 or P2), got an empty file");
    const std::string_view magic = bytes_.substr(0, 2);
    if (magic == "P5" || magic == "P2") {
      pos_ = 2;
      return magic == "P5";
    }
    if (magic == "P1" || magic == "P3" || magic == "P4" || magic == "P6")
      fail(
          fmt::format("expected a greyscale PGM image (P5 or P2), got a {} image ({}): save the "
                      "map as PGM",
                      magic, magic == "P1" || magic == "P4" ? "PBM" : "PPM, colour"));
    fail(fmt::format("expected a PGM image (P5 or P2), got a file starting '{}'",
                     printable(bytes_.substr(0, 8))));
  }

  static bool space(char c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
  }
  // Whitespace and '#' comments (to the end of the line), counting lines.
  void skip_blank() {
    while (pos_ < bytes_.size()) {
      const char c = bytes_[pos_];
      if (c == '#') {
        while (pos_ < bytes_.size() && bytes_[pos_] != '\n') ++pos_;
      } else if (space(c)) {
        if (c == '\n') ++line_;
        ++pos_;
      } else {
        return;
      }
    }
  }
  // A decimal number at pos_ (after blanks); false at the end of the data. Fails on anything
  // that is not digits up to the next blank, or on a value above `limit`.
  bool integer(const char* field, long limit, long* value) {
    skip_blank();
    if (pos_ >= bytes_.size()) return false;
    std::size_t end = pos_;
    while (end < bytes_.size() && !space(bytes_[end]) && bytes_[end] != '#') ++end;
    const std::string_view token = bytes_.substr(pos_, end - pos_);
    long v = 0;
    const auto r = std::from_chars(token.data(), token.data() + token.size(), v);
    if (r.ec == std::errc::result_out_of_range || (r.ec == std::errc() && v > limit) ||
        (r.ec == std::errc() && r.ptr == token.data() + token.size() && v < 0))
      fail(fmt::format("field '{}': expected an integer in 0..{}, got '{}'", field, limit,
                       printable(token)));
    if (r.ec != std::errc() || r.ptr != token.data() + token.size())
      fail(fmt::format("field '{}': expected a non-negative integer, got '{}'", field,
                       printable(token)));
    pos_ = end;
    *value = v;
    return true;
  }
  int header_integer(const char* field, long min) {
    long v = 0;
    if (!integer(field, 2147483647L, &v))
      fail(
          fmt::format("field '{}': expected a number, got the end of the file (a truncated "
                      "header)",
                      field));
    if (v < min) fail(fmt::format("field '{}': expected an integer >= {}, got {}", field, min, v));
    return static_cast<int>(v);
  }

  void read_binary(PgmImage& im) {
    // Exactly one whitespace byte separates the header from the samples.
    if (pos_ >= bytes_.size() || !space(bytes_[pos_]))
      fail("expected a whitespace byte after maxval, then the pixels, got the end of the file");
    ++pos_;
    const std::size_t sample = im.maxval < 256 ? 1 : 2;
    const std::size_t count =
        static_cast<std::size_t>(im.width) * static_cast<std::size_t>(im.height);
    const std::size_t have = bytes_.size() - pos_;
    if (have / sample != count || have % sample != 0)
      fail(
          fmt::format("expected {} x {} pixels of {} byte(s) = {} bytes of pixel data, got {} "
                      "({})",
                      im.width, im.height, sample, count * sample, have,
                      have < count * sample ? "a truncated file" : "more than the header says"));
    im.pixels.resize(count);
    const auto* p = reinterpret_cast<const unsigned char*>(bytes_.data() + pos_);
    for (std::size_t k = 0; k < count; ++k) {
      // Two-byte samples are big-endian (most significant byte first).
      const unsigned v = sample == 1 ? p[k] : (unsigned{p[2 * k]} << 8) | p[2 * k + 1];
      if (v > static_cast<unsigned>(im.maxval))
        fail(fmt::format("pixel (row {}, column {}): expected a value <= maxval {}, got {}",
                         k / static_cast<std::size_t>(im.width),
                         k % static_cast<std::size_t>(im.width), im.maxval, v));
      im.pixels[k] = static_cast<std::uint16_t>(v);
    }
  }

  void read_plain(PgmImage& im) {
    const std::size_t count =
        static_cast<std::size_t>(im.width) * static_cast<std::size_t>(im.height);
    // Each value takes a digit and a separator: a bound on the count before allocating it.
    if (count > (bytes_.size() - pos_ + 1) / 2)
      fail(
          fmt::format("expected {} x {} pixel values, got a file too short for them (a "
                      "truncated file, or a header with the wrong size)",
                      im.width, im.height));
    im.pixels.resize(count);
    for (std::size_t k = 0; k < count; ++k) {
      long v = 0;
      if (!integer("pixel", im.maxval, &v))
        fail(fmt::format("expected {} x {} = {} pixel values, got {} (a truncated file?)", im.width,
                         im.height, count, k));
      im.pixels[k] = static_cast<std::uint16_t>(v);
    }
    skip_blank();
    if (pos_ < bytes_.size())
      fail(fmt::format("expected {} x {} = {} pixel values, got more: '{}'", im.width, im.height,
                       count, printable(bytes_.substr(pos_, 16))));
  }

  std::string_view bytes_;
  std::string name_;
  std::size_t pos_ = 0;
  std::size_t line_ = 1;
};

// map_server's conversion of one pixel (map_io.hpp).
std::int8_t map_value(const MapYaml& m, unsigned v, unsigned maxval) {
  if (m.mode == MapMode::kRaw) {
    const unsigned raw = m.negate ? maxval - v : v;
    if (raw <= 100) return static_cast<std::int8_t>(raw);
    return OccupancyGrid::kUnknown;  // 255; anything else is refused before
  }
  const double p = m.negate ? double(v) / maxval : double(maxval - v) / maxval;
  if (p > m.occupied_thresh) return OccupancyGrid::kOccupied;
  if (p < m.free_thresh) return OccupancyGrid::kFree;
  if (m.mode == MapMode::kTrinary) return OccupancyGrid::kUnknown;
  return static_cast<std::int8_t>(
      std::lround(99.0 * (p - m.free_thresh) / (m.occupied_thresh - m.free_thresh)));
}

OccupancyGrid to_grid(const MapYaml& m, const PgmImage& im, const std::string& image_name) {
  OccupancyGrid grid(im.width, im.height, m.resolution, m.origin);
  const auto maxval = static_cast<unsigned>(im.maxval);
  for (int row = 0; row < im.height; ++row) {
    const int iy = im.height - 1 - row;  // the image's first row is the highest y
    for (int ix = 0; ix < im.width; ++ix) {
      const unsigned v =
          im.pixels[static_cast<std::size_t>(row) * static_cast<std::size_t>(im.width) +
                    static_cast<std::size_t>(ix)];
      if (m.mode == MapMode::kRaw) {
        const unsigned raw = m.negate ? maxval - v : v;
        if (raw > 100 && raw != 255)
          throw ParseError(fmt::format(
              "{}: pixel (row {}, column {}): expected a value 0..100, or 255 for unknown, in "
              "raw mode, got {}{}",
              image_name, row, ix, raw, m.negate ? " (after negate)" : ""));
      }
      grid.at(ix, iy) = map_value(m, v, maxval);
    }
  }
  return grid;
}

std::string image_name_of(const std::filesystem::path& yaml_name, const MapYaml& m) {
  return (yaml_name.parent_path() / m.image).string();
}

OccupancyGrid decode_map(const MapYaml& m, std::string_view pgm_bytes,
                         const std::string& image_name) {
  const PgmImage im = PgmDecoder(pgm_bytes, image_name).decode();
  // A pixel 2^31 pixels out would overflow the world coordinates of nothing useful; refuse
  // maps whose far corner is not a finite number.
  require(std::isfinite(m.origin.x() + im.width * m.resolution) &&
              std::isfinite(m.origin.y() + im.height * m.resolution),
          "{}: expected a map with a finite extent, got {} x {} pixels of {} m", image_name,
          im.width, im.height, m.resolution);
  return to_grid(m, im, image_name);
}

std::string read_binary_file(const std::filesystem::path& path, const std::string& referrer) {
  constexpr std::uintmax_t kMaxImageBytes = std::uintmax_t{1} << 30;
  std::error_code ec;
  const bool regular = std::filesystem::is_regular_file(path, ec);
  const std::uintmax_t size = regular ? std::filesystem::file_size(path, ec) : 0;
  std::ifstream in(path, std::ios::binary);
  if (!regular || ec || !in)
    throw ParseError(
        fmt::format("{}: key 'image': expected a readable image file, cannot read "
                    "'{}'",
                    referrer, path.string()));
  if (size > kMaxImageBytes)
    throw ParseError(fmt::format("{}: expected an image of at most 1024 MiB, got {} bytes",
                                 path.string(), size));
  std::string bytes(static_cast<std::size_t>(size), '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(size));
  if (static_cast<std::uintmax_t>(in.gcount()) != size)
    throw ParseError(
        fmt::format("{}: expected {} bytes, read {} (the file changed or a read "
                    "failed)",
                    path.string(), size, in.gcount()));
  return bytes;
}

// ---- Writing -----------------------------------------------------------------------------

std::uint8_t pixel_of(std::int8_t value) {
  if (value == OccupancyGrid::kUnknown) return 205;
  if (value == OccupancyGrid::kFree) return 254;
  // 100 -> 0; in between a grey whose p = (255 - v) / 255 is close to value / 100 and falls on
  // the same side of both thresholds as OccupancyGrid::kOccupiedAt and kFreeAt (map_io.hpp).
  return static_cast<std::uint8_t>((255 * (100 - value) + 50) / 100);
}

// A YAML double-quoted scalar: any file name reads back as itself.
std::string yaml_quoted(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\')
      out += fmt::format("\\{}", c);
    else if (static_cast<unsigned char>(c) < 0x20)
      out += fmt::format("\\x{:02x}", static_cast<unsigned char>(c));
    else
      out += c;
  }
  return out + "\"";
}

// The library's one writer (OutputFile: a temporary name, renamed when complete), with the
// message saying which function wrote.
[[noreturn]] void refuse_unwritable_map(const InvalidArgument& e) {
  throw InvalidArgument(fmt::format("save_map: expected a writable file: {}", e.what()));
}

}  // namespace

OccupancyGrid parse_map(std::string_view yaml_text, std::string_view pgm_bytes,
                        std::string_view name) {
  const std::string yaml_name(name);
  const MapYaml m = read_map_yaml(yaml_text, yaml_name);
  return decode_map(m, pgm_bytes, image_name_of(yaml_name, m));
}

OccupancyGrid load_map(const std::filesystem::path& yaml_file) {
  const std::string yaml_name = yaml_file.string();
  const MapYaml m = read_map_yaml(read_text_file(yaml_file), yaml_name);
  const std::filesystem::path image = yaml_file.parent_path() / m.image;
  return decode_map(m, read_binary_file(image, yaml_name), image.string());
}

void save_map(const OccupancyGrid& grid, const std::filesystem::path& yaml_file) {
  require(!grid.empty(), "save_map: expected a grid with cells, got an empty one ('{}')",
          yaml_file.string());
  require(yaml_file.has_filename() && yaml_file.extension() != ".pgm",
          "save_map: expected a YAML file name (the image goes beside it as .pgm), got '{}'",
          yaml_file.string());
  std::filesystem::path image = yaml_file;
  image.replace_extension(".pgm");

  std::string pgm = fmt::format("P5\n{} {}\n255\n", grid.width(), grid.height());
  const std::size_t header = pgm.size();
  pgm.resize(header + grid.data().size());
  for (int iy = grid.height() - 1, row = 0; iy >= 0; --iy, ++row)  // top row first
    for (int ix = 0; ix < grid.width(); ++ix)
      pgm[header + static_cast<std::size_t>(row) * static_cast<std::size_t>(grid.width()) +
          static_cast<std::size_t>(ix)] = static_cast<char>(pixel_of(grid.at(ix, iy)));

  // fmt's shortest round-trip form: the numbers read back bit for bit.
  const std::string yaml = fmt::format(
      "image: {}\nmode: trinary\nresolution: {}\norigin: [{}, {}, 0.0]\nnegate: 0\n"
      "occupied_thresh: 0.65\nfree_thresh: 0.196\n",
      yaml_quoted(image.filename().string()), grid.resolution(), grid.origin().x(),
      grid.origin().y());

  try {
    OutputFile pgm_file(image, OutputFile::Mode::kReplace, "");
    OutputFile yaml_out(yaml_file, OutputFile::Mode::kReplace, "");
    pgm_file.stream() << pgm;
    yaml_out.stream() << yaml;
    // The image first: a YAML file under its final name always names a complete image.
    pgm_file.commit();
    yaml_out.commit();
  } catch (const InvalidArgument& e) {
    refuse_unwritable_map(e);
  }
}

}  // namespace implicit::robot
