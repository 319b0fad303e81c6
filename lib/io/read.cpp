// SPDX-License-Identifier: BSD-3-Clause
// Strict readers into a raw TriangleSoup. Each file is read into memory in one go and
// parsed with std::from_chars (ASCII) or memcpy + byte swap (binary). Every count
// taken from a header is checked against the bytes the file actually holds before
// anything is allocated on its word, and every error names the file and the problem.
#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "nurbsfront/core/error.h"
#include "nurbsfront/core/parallel.h"
#include "nurbsfront/io/mesh_io.h"

namespace nurbsfront {
namespace {

namespace fs = std::filesystem;

using Triangle = std::array<std::uint32_t, 3>;

//! Largest point count a soup can index (indices are 32-bit).
constexpr std::uint64_t kMaxPoints = std::numeric_limits<std::uint32_t>::max();

[[noreturn]] void fail(const fs::path& path, const std::string& what) {
  throw IoError("cannot read '" + path.string() + "': " + what);
}

std::string load_file(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) fail(path, "no such file");
  if (fs::is_directory(path, ec)) fail(path, "it is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open the file");
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) fail(path, "cannot determine the file size");
  in.seekg(0, std::ios::beg);
  std::string data(static_cast<std::size_t>(size), '\0');
  if (size > 0 && !in.read(data.data(), size)) fail(path, "read error");
  if (data.empty()) fail(path, "the file is empty");
  return data;
}

// ---------------------------------------------------------------------------------
// Scalar types shared by PLY and binary VTK.

enum class Scalar { I8, U8, I16, U16, I32, U32, I64, U64, F32, F64, Invalid };

std::size_t scalar_size(Scalar t) {
  switch (t) {
    case Scalar::I8:
    case Scalar::U8: return 1;
    case Scalar::I16:
    case Scalar::U16: return 2;
    case Scalar::I32:
    case Scalar::U32:
    case Scalar::F32: return 4;
    case Scalar::I64:
    case Scalar::U64:
    case Scalar::F64: return 8;
    case Scalar::Invalid: break;
  }
  return 0;
}

bool is_integer(Scalar t) { return t != Scalar::F32 && t != Scalar::F64 && t != Scalar::Invalid; }

Scalar ply_scalar(std::string_view name) {
  if (name == "char" || name == "int8") return Scalar::I8;
  if (name == "uchar" || name == "uint8") return Scalar::U8;
  if (name == "short" || name == "int16") return Scalar::I16;
  if (name == "ushort" || name == "uint16") return Scalar::U16;
  if (name == "int" || name == "int32") return Scalar::I32;
  if (name == "uint" || name == "uint32") return Scalar::U32;
  if (name == "float" || name == "float32") return Scalar::F32;
  if (name == "double" || name == "float64") return Scalar::F64;
  return Scalar::Invalid;
}

Scalar vtk_scalar(std::string_view name) {
  if (name == "char") return Scalar::I8;
  if (name == "unsigned_char" || name == "bit") return name == "bit" ? Scalar::Invalid : Scalar::U8;
  if (name == "short") return Scalar::I16;
  if (name == "unsigned_short") return Scalar::U16;
  if (name == "int" || name == "vtktypeint32") return Scalar::I32;
  if (name == "unsigned_int" || name == "vtktypeuint32") return Scalar::U32;
  if (name == "long" || name == "vtktypeint64" || name == "vtkIdType") return Scalar::I64;
  if (name == "unsigned_long" || name == "vtktypeuint64") return Scalar::U64;
  if (name == "float") return Scalar::F32;
  if (name == "double") return Scalar::F64;
  return Scalar::Invalid;
}

template <typename T>
T load(const char* p, bool big_endian) {
  std::array<char, sizeof(T)> bytes;
  std::memcpy(bytes.data(), p, sizeof(T));
  if (big_endian != (std::endian::native == std::endian::big)) std::reverse(bytes.begin(), bytes.end());
  T value;
  std::memcpy(&value, bytes.data(), sizeof(T));
  return value;
}

double load_as_double(Scalar t, const char* p, bool big_endian) {
  switch (t) {
    case Scalar::I8: return load<std::int8_t>(p, big_endian);
    case Scalar::U8: return load<std::uint8_t>(p, big_endian);
    case Scalar::I16: return load<std::int16_t>(p, big_endian);
    case Scalar::U16: return load<std::uint16_t>(p, big_endian);
    case Scalar::I32: return load<std::int32_t>(p, big_endian);
    case Scalar::U32: return load<std::uint32_t>(p, big_endian);
    case Scalar::I64: return static_cast<double>(load<std::int64_t>(p, big_endian));
    case Scalar::U64: return static_cast<double>(load<std::uint64_t>(p, big_endian));
    case Scalar::F32: return load<float>(p, big_endian);
    case Scalar::F64: return load<double>(p, big_endian);
    case Scalar::Invalid: break;
  }
  return 0.0;
}

//! Integer value; the caller has checked is_integer(t). Values above INT64_MAX map to -1
//! (invalid as an index or count either way).
std::int64_t load_as_int(Scalar t, const char* p, bool big_endian) {
  switch (t) {
    case Scalar::I8: return load<std::int8_t>(p, big_endian);
    case Scalar::U8: return load<std::uint8_t>(p, big_endian);
    case Scalar::I16: return load<std::int16_t>(p, big_endian);
    case Scalar::U16: return load<std::uint16_t>(p, big_endian);
    case Scalar::I32: return load<std::int32_t>(p, big_endian);
    case Scalar::U32: return load<std::uint32_t>(p, big_endian);
    case Scalar::I64: return load<std::int64_t>(p, big_endian);
    case Scalar::U64: {
      const std::uint64_t v = load<std::uint64_t>(p, big_endian);
      return v > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()) ? -1
                                                                                        : static_cast<std::int64_t>(v);
    }
    default: break;
  }
  return -1;
}

// ---------------------------------------------------------------------------------
// A cursor over the file's bytes: tokens for ASCII parts, raw reads for binary parts.

class Cursor {
 public:
  Cursor(std::string_view data, const fs::path& path) : data_(data), path_(path) {}

  [[noreturn]] void fail(const std::string& what) const {
    const auto line = 1 + std::count(data_.begin(), data_.begin() + static_cast<std::ptrdiff_t>(std::min(pos_, data_.size())), '\n');
    ::nurbsfront::fail(path_, what + " (line " + std::to_string(line) + ")");
  }
  [[noreturn]] void fail_binary(const std::string& what) const {
    ::nurbsfront::fail(path_, what + " (byte offset " + std::to_string(pos_) + ")");
  }

  //! '#' starts a comment up to the end of the line when enabled (OBJ, OFF).
  void set_comments(bool enabled) { comments_ = enabled; }

  std::size_t pos() const { return pos_; }
  void set_pos(std::size_t pos) { pos_ = pos; }
  std::size_t remaining() const { return data_.size() - pos_; }

  //! Skips whitespace including newlines (and comments if enabled).
  void skip_space() {
    while (pos_ < data_.size()) {
      const char c = data_[pos_];
      if (c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v') {
        ++pos_;
      } else if (comments_ && c == '#') {
        skip_line();
      } else {
        break;
      }
    }
  }
  //! Skips blanks within the line (and a trailing comment if enabled).
  void skip_blank() {
    while (pos_ < data_.size()) {
      const char c = data_[pos_];
      if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') {
        ++pos_;
      } else if (comments_ && c == '#') {
        while (pos_ < data_.size() && data_[pos_] != '\n') ++pos_;
      } else if (c == '\\' && pos_ + 1 < data_.size() && (data_[pos_ + 1] == '\n' || data_[pos_ + 1] == '\r')) {
        // OBJ line continuation
        ++pos_;
        while (pos_ < data_.size() && data_[pos_] != '\n') ++pos_;
        if (pos_ < data_.size()) ++pos_;
      } else {
        break;
      }
    }
  }
  bool at_end() {
    skip_space();
    return pos_ >= data_.size();
  }
  bool at_eol() {
    skip_blank();
    return pos_ >= data_.size() || data_[pos_] == '\n';
  }
  //! Moves past the next '\n' (or to the end).
  void skip_line() {
    while (pos_ < data_.size() && data_[pos_] != '\n') ++pos_;
    if (pos_ < data_.size()) ++pos_;
  }
  //! The rest of the current line (without '\r\n'), moving past it.
  std::string_view line() {
    const std::size_t begin = pos_;
    while (pos_ < data_.size() && data_[pos_] != '\n') ++pos_;
    std::size_t end = pos_;
    if (pos_ < data_.size()) ++pos_;
    if (end > begin && data_[end - 1] == '\r') --end;
    return data_.substr(begin, end - begin);
  }
  //! Next whitespace-separated token (across lines); empty at the end.
  std::string_view token() {
    skip_space();
    return word();
  }
  //! Next token on this line; empty at the end of the line.
  std::string_view token_in_line() {
    skip_blank();
    return word();
  }
  void expect(std::string_view keyword) {
    const std::string_view t = token();
    if (t != keyword) {
      fail("expected '" + std::string(keyword) + "', found " + describe(t));
    }
  }
  //! A real number (across lines). May be non-finite: callers check coordinates.
  double real() {
    skip_space();
    return real_here();
  }
  double real_in_line() {
    skip_blank();
    return real_here();
  }
  //! A signed integer (across lines).
  std::int64_t integer() {
    skip_space();
    return integer_here();
  }
  std::int64_t integer_in_line() {
    skip_blank();
    return integer_here();
  }
  //! An OBJ face corner "i", "i/t", "i//n" or "i/t/n": the vertex index i.
  std::int64_t obj_index() {
    skip_blank();
    if (pos_ >= data_.size()) fail("truncated: expected a face index");
    const char* first = data_.data() + pos_;
    const char* last = data_.data() + data_.size();
    std::int64_t value = 0;
    const auto [ptr, ec] = std::from_chars(first, last, value);
    if (ec != std::errc()) fail("expected a face index, found " + describe(word_at(pos_)));
    pos_ = static_cast<std::size_t>(ptr - data_.data());
    if (pos_ < data_.size() && data_[pos_] == '/') {
      while (pos_ < data_.size() && (data_[pos_] == '/' || data_[pos_] == '-' || (data_[pos_] >= '0' && data_[pos_] <= '9'))) ++pos_;
    }
    if (!at_separator()) fail("malformed face index " + describe(word_at(static_cast<std::size_t>(first - data_.data()))));
    return value;
  }
  //! A non-negative count (across lines).
  std::uint64_t count(const char* what) {
    const std::int64_t v = integer();
    if (v < 0) fail(std::string("negative ") + what);
    return static_cast<std::uint64_t>(v);
  }
  //! Checks that n raw bytes are available at the cursor.
  void need(std::uint64_t n, std::string_view what) const {
    if (n > remaining()) {
      fail_binary("truncated: " + std::string(what) + " needs " + std::to_string(n) + " bytes but only " +
                  std::to_string(remaining()) + " remain");
    }
  }
  //! Checks that n items of s bytes each are available at the cursor (overflow-safe).
  void need_items(std::uint64_t n, std::size_t s, std::string_view what) const {
    if (s > 0 && n > remaining() / s) {
      fail_binary("truncated: " + std::string(what) + " (" + std::to_string(n) + " x " + std::to_string(s) +
                  " bytes) but only " + std::to_string(remaining()) + " bytes remain");
    }
  }
  const char* here() const { return data_.data() + pos_; }
  void advance(std::size_t n) { pos_ += n; }

  static std::string describe(std::string_view t) {
    if (t.empty()) return "the end of the file";
    std::string s(t.substr(0, 32));
    for (char& c : s) {
      if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
    }
    return "'" + s + (t.size() > 32 ? "...'" : "'");
  }

 private:
  std::string_view word() {
    const std::size_t begin = pos_;
    while (pos_ < data_.size()) {
      const char c = data_[pos_];
      if (c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v') break;
      ++pos_;
    }
    return data_.substr(begin, pos_ - begin);
  }
  bool at_separator() const {
    if (pos_ >= data_.size()) return true;
    const char c = data_[pos_];
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v' ||
           (comments_ && c == '#');
  }
  double real_here() {
    if (pos_ >= data_.size()) fail("truncated: expected a number, found the end of the file");
    const char* first = data_.data() + pos_;
    const char* last = data_.data() + data_.size();
    if (*first == '+' && first + 1 < last) ++first;  // from_chars does not take '+'
    double value = 0.0;
    const auto [ptr, ec] = std::from_chars(first, last, value, std::chars_format::general);
    if (ec == std::errc::result_out_of_range) {
      fail("number out of the range of double");
    }
    if (ec != std::errc() || (pos_ = static_cast<std::size_t>(ptr - data_.data()), !at_separator())) {
      skip_blank();
      fail("expected a number, found " + describe(word_at(static_cast<std::size_t>(first - data_.data()))));
    }
    return value;
  }
  std::int64_t integer_here() {
    if (pos_ >= data_.size()) fail("truncated: expected an integer, found the end of the file");
    const char* first = data_.data() + pos_;
    const char* last = data_.data() + data_.size();
    if (*first == '+' && first + 1 < last) ++first;
    std::int64_t value = 0;
    const auto [ptr, ec] = std::from_chars(first, last, value);
    if (ec == std::errc::result_out_of_range) fail("integer out of range");
    if (ec != std::errc() || (pos_ = static_cast<std::size_t>(ptr - data_.data()), !at_separator())) {
      fail("expected an integer, found " + describe(word_at(static_cast<std::size_t>(first - data_.data()))));
    }
    return value;
  }
  std::string_view word_at(std::size_t begin) const {
    std::size_t end = begin;
    while (end < data_.size() && !std::isspace(static_cast<unsigned char>(data_[end]))) ++end;
    return data_.substr(begin, end - begin);
  }

  std::string_view data_;
  const fs::path& path_;
  std::size_t pos_ = 0;
  bool comments_ = false;
};

//! Reserves at most what the remaining bytes can hold, so a lying header cannot make us
//! allocate 10^12 elements.
template <typename V>
void reserve_bounded(V& v, std::uint64_t declared, std::size_t remaining_bytes, std::size_t min_bytes_each) {
  const std::uint64_t cap = remaining_bytes / std::max<std::size_t>(min_bytes_each, 1) + 1;
  v.reserve(v.size() + static_cast<std::size_t>(std::min(declared, cap)));
}

void check_point_count(const Cursor& c, std::uint64_t n) {
  if (n > kMaxPoints) c.fail("more than 2^32-1 points (" + std::to_string(n) + ") are not supported");
}

//! Adds a polygon, fan-triangulated. Indices are checked later against the point count.
void add_polygon(TriangleSoup& soup, const std::vector<std::int64_t>& poly, const Cursor& c) {
  if (poly.size() < 3) c.fail("polygon with " + std::to_string(poly.size()) + " vertices (at least 3 needed)");
  for (const std::int64_t i : poly) {
    if (i < 0 || static_cast<std::uint64_t>(i) >= kMaxPoints) {
      c.fail("vertex index " + std::to_string(i) + " out of range");
    }
  }
  for (std::size_t k = 1; k + 1 < poly.size(); ++k) {
    soup.triangles.push_back({static_cast<std::uint32_t>(poly[0]), static_cast<std::uint32_t>(poly[k]),
                              static_cast<std::uint32_t>(poly[k + 1])});
  }
}

//! Final checks common to all formats: indices in range, coordinates finite.
void validate_soup(const fs::path& path, const TriangleSoup& soup) {
  for (std::size_t i = 0; i < soup.points.size(); ++i) {
    if (!soup.points[i].allFinite()) {
      fail(path, "point " + std::to_string(i) + " has a non-finite coordinate (NaN or infinity)");
    }
  }
  const std::size_t n = soup.points.size();
  for (std::size_t f = 0; f < soup.triangles.size(); ++f) {
    for (const std::uint32_t v : soup.triangles[f]) {
      if (v >= n) {
        fail(path, "triangle " + std::to_string(f) + " references vertex " + std::to_string(v) +
                       " but the file has only " + std::to_string(n) + " vertices");
      }
    }
  }
}

// ---------------------------------------------------------------------------------
// OBJ

TriangleSoup read_obj(std::string_view data, const fs::path& path) {
  TriangleSoup soup;
  Cursor c(data, path);
  c.set_comments(true);
  std::vector<std::int64_t> poly;
  bool any = false;
  while (!c.at_end()) {
    const std::string_view key = c.token_in_line();
    if (key == "v") {
      const double x = c.real_in_line();
      const double y = c.real_in_line();
      const double z = c.real_in_line();
      while (!c.at_eol()) (void)c.real_in_line();  // optional w or vertex colour
      soup.points.emplace_back(x, y, z);
      any = true;
    } else if (key == "f") {
      poly.clear();
      while (!c.at_eol()) {
        const std::int64_t i = c.obj_index();
        if (i == 0) c.fail("face index 0 (OBJ indices start at 1)");
        // negative indices count back from the last vertex defined so far
        poly.push_back(i > 0 ? i - 1 : static_cast<std::int64_t>(soup.points.size()) + i);
      }
      add_polygon(soup, poly, c);
      any = true;
    } else if (key == "vt" || key == "vn" || key == "vp" || key == "g" || key == "o" || key == "s" ||
               key == "usemtl" || key == "mtllib" || key == "l" || key == "p" || key == "mg" ||
               key == "cstype" || key == "deg" || key == "curv" || key == "curv2" || key == "surf" ||
               key == "parm" || key == "end" || key == "lod" || key == "usemap" || key == "maplib") {
      // Texture, normal, grouping and material records do not change the geometry.
      while (!c.at_eol()) (void)c.token_in_line();
    } else {
      c.fail("unknown OBJ record " + Cursor::describe(key));
    }
    if (!c.at_eol()) c.fail("unexpected " + Cursor::describe(c.token_in_line()) + " at the end of the record");
  }
  if (!any) fail(path, "no vertices or faces found");
  return soup;
}

// ---------------------------------------------------------------------------------
// PLY

struct PlyProperty {
  std::string name;
  Scalar type = Scalar::Invalid;       //!< value type (item type for lists)
  Scalar count_type = Scalar::Invalid; //!< list length type; Invalid for scalars
  bool is_list() const { return count_type != Scalar::Invalid; }
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
  //! Bytes of one item in binary, lists counted as empty.
  std::uint64_t min_binary_size() const {
    std::uint64_t s = 0;
    for (const auto& p : properties) s += p.is_list() ? scalar_size(p.count_type) : scalar_size(p.type);
    return s;
  }
};

enum class PlyFormat { Ascii, BinaryLittle, BinaryBig };

TriangleSoup read_ply(std::string_view data, const fs::path& path) {
  Cursor c(data, path);
  if (c.line() != "ply") fail(path, "not a PLY file (first line is not 'ply')");
  PlyFormat format = PlyFormat::Ascii;
  bool has_format = false;
  std::vector<PlyElement> elements;
  for (;;) {
    if (c.remaining() == 0) fail(path, "truncated header: no 'end_header'");
    Cursor line_cursor(c.line(), path);
    const std::string_view key = line_cursor.token();
    if (key == "end_header") break;
    if (key.empty() || key == "comment" || key == "obj_info") continue;
    if (key == "format") {
      const std::string_view f = line_cursor.token();
      if (f == "ascii") {
        format = PlyFormat::Ascii;
      } else if (f == "binary_little_endian") {
        format = PlyFormat::BinaryLittle;
      } else if (f == "binary_big_endian") {
        format = PlyFormat::BinaryBig;
      } else {
        c.fail("unknown PLY format " + Cursor::describe(f));
      }
      has_format = true;
    } else if (key == "element") {
      PlyElement e;
      e.name = std::string(line_cursor.token());
      const std::string_view n = line_cursor.token();
      std::uint64_t count = 0;
      const auto [ptr, ec] = std::from_chars(n.data(), n.data() + n.size(), count);
      if (e.name.empty() || ec != std::errc() || ptr != n.data() + n.size()) {
        c.fail("malformed element line (expected 'element <name> <count>')");
      }
      e.count = count;
      elements.push_back(std::move(e));
    } else if (key == "property") {
      if (elements.empty()) c.fail("property before any element");
      PlyProperty p;
      std::string_view t = line_cursor.token();
      if (t == "list") {
        p.count_type = ply_scalar(line_cursor.token());
        t = line_cursor.token();
        if (p.count_type == Scalar::Invalid || !is_integer(p.count_type)) c.fail("bad list count type");
      }
      p.type = ply_scalar(t);
      if (p.type == Scalar::Invalid) c.fail("unknown property type " + Cursor::describe(t));
      p.name = std::string(line_cursor.token());
      if (p.name.empty()) c.fail("property without a name");
      elements.back().properties.push_back(std::move(p));
    } else {
      c.fail("unknown PLY header line starting with " + Cursor::describe(key));
    }
  }
  if (!has_format) fail(path, "PLY header has no 'format' line");
  for (const auto& e : elements) {
    // an item without properties would consume no bytes: 10^12 of them would never end
    if (e.count > 0 && e.properties.empty()) fail(path, "PLY element '" + e.name + "' has no properties");
  }

  TriangleSoup soup;
  const bool binary = format != PlyFormat::Ascii;
  const bool big = format == PlyFormat::BinaryBig;
  if (binary) {
    // Check the declared counts against the file size before allocating anything.
    std::uint64_t needed = 0;
    for (const auto& e : elements) {
      const std::uint64_t s = e.min_binary_size();
      if (s > 0 && e.count > (std::numeric_limits<std::uint64_t>::max() - needed) / s) {
        fail(path, "element '" + e.name + "' declares an impossible count " + std::to_string(e.count));
      }
      needed += e.count * s;
    }
    c.need(needed, "the elements declared in the PLY header");
  }
  std::vector<std::int64_t> poly;
  bool seen_vertex = false;
  for (const auto& e : elements) {
    const bool is_vertex = e.name == "vertex";
    const bool is_face = e.name == "face";
    int ix = -1, iy = -1, iz = -1, iface = -1;
    for (std::size_t k = 0; k < e.properties.size(); ++k) {
      const auto& p = e.properties[k];
      if (is_vertex && !p.is_list()) {
        if (p.name == "x") ix = static_cast<int>(k);
        if (p.name == "y") iy = static_cast<int>(k);
        if (p.name == "z") iz = static_cast<int>(k);
      }
      if (is_face && p.is_list() && (p.name == "vertex_indices" || p.name == "vertex_index")) {
        if (!is_integer(p.type)) fail(path, "face vertex indices must have an integer type");
        iface = static_cast<int>(k);
      }
    }
    if (is_vertex) {
      if (ix < 0 || iy < 0 || iz < 0) fail(path, "PLY vertex element lacks x, y or z");
      check_point_count(c, e.count);
      reserve_bounded(soup.points, e.count, c.remaining(), binary ? e.min_binary_size() : 6);
      seen_vertex = true;
    }
    if (is_face) {
      if (iface < 0) fail(path, "PLY face element lacks a 'vertex_indices' list");
      reserve_bounded(soup.triangles, e.count, c.remaining(), binary ? e.min_binary_size() : 2);
    }
    // Fast paths for the usual binary layouts, item by item (an item they do not take, e.g.
    // at the end of the data or a face that is not a valid triangle, goes through the
    // general loop below, which gives the same values and the same errors): a vertex
    // element of scalars only; a face element of just the index list, with a one-byte
    // count and 4-byte indices, little-endian.
    std::size_t vertex_item_bytes = 0;
    std::array<std::size_t, 3> xyz_offset{};
    const bool fast_vertex = binary && is_vertex && std::none_of(e.properties.begin(), e.properties.end(), [](const PlyProperty& p) { return p.is_list(); });
    if (fast_vertex) {
      for (std::size_t k = 0; k < e.properties.size(); ++k) {
        if (static_cast<int>(k) == ix) xyz_offset[0] = vertex_item_bytes;
        if (static_cast<int>(k) == iy) xyz_offset[1] = vertex_item_bytes;
        if (static_cast<int>(k) == iz) xyz_offset[2] = vertex_item_bytes;
        vertex_item_bytes += scalar_size(e.properties[k].type);
      }
    }
    const bool fast_face = binary && !big && std::endian::native == std::endian::little && is_face && iface == 0 &&
                           e.properties.size() == 1 &&
                           scalar_size(e.properties[0].count_type) == 1 &&
                           (e.properties[0].type == Scalar::I32 || e.properties[0].type == Scalar::U32);
    const bool signed_index = fast_face && e.properties[0].type == Scalar::I32;
    constexpr std::size_t kTriangleItemBytes = 1 + 3 * 4;
    std::array<double, 3> xyz{};
    for (std::uint64_t item = 0; item < e.count; ++item) {
      if (fast_vertex && c.remaining() >= vertex_item_bytes) {
        const char* q = c.here();
        soup.points.emplace_back(load_as_double(e.properties[static_cast<std::size_t>(ix)].type, q + xyz_offset[0], big),
                                 load_as_double(e.properties[static_cast<std::size_t>(iy)].type, q + xyz_offset[1], big),
                                 load_as_double(e.properties[static_cast<std::size_t>(iz)].type, q + xyz_offset[2], big));
        c.advance(vertex_item_bytes);
        continue;
      }
      if (fast_face && c.remaining() >= kTriangleItemBytes && *c.here() == 3) {
        std::array<std::uint32_t, 3> t{};
        std::memcpy(t.data(), c.here() + 1, 3 * 4);
        // Valid indices are below kMaxPoints (2^32 - 1), and non-negative when signed.
        const std::uint32_t bound = signed_index ? 0x80000000u : static_cast<std::uint32_t>(kMaxPoints);
        if (t[0] < bound && t[1] < bound && t[2] < bound) {
          soup.triangles.push_back(t);
          c.advance(kTriangleItemBytes);
          continue;
        }
      }
      for (std::size_t k = 0; k < e.properties.size(); ++k) {
        const auto& p = e.properties[k];
        const int ik = static_cast<int>(k);
        if (p.is_list()) {
          std::int64_t n = 0;
          if (binary) {
            c.need(scalar_size(p.count_type), "a list length");
            n = load_as_int(p.count_type, c.here(), big);
            c.advance(scalar_size(p.count_type));
          } else {
            n = c.integer();
          }
          if (n < 0) c.fail("negative list length");
          if (ik == iface) poly.clear();
          if (binary) {
            const std::size_t s = scalar_size(p.type);
            c.need_items(static_cast<std::uint64_t>(n), s, "a list");
            for (std::int64_t j = 0; j < n; ++j) {
              if (ik == iface) poly.push_back(is_integer(p.type) ? load_as_int(p.type, c.here(), big) : -1);
              c.advance(s);
            }
          } else {
            for (std::int64_t j = 0; j < n; ++j) {
              if (ik == iface) {
                poly.push_back(c.integer());
              } else {
                (void)c.real();
              }
            }
          }
          if (ik == iface) add_polygon(soup, poly, c);
        } else {
          double v = 0.0;
          if (binary) {
            // the header check covered the minimum; lists read before may have used it up
            c.need(scalar_size(p.type), "a property value");
            v = load_as_double(p.type, c.here(), big);
            c.advance(scalar_size(p.type));
          } else {
            v = c.real();
          }
          if (ik == ix) xyz[0] = v;
          if (ik == iy) xyz[1] = v;
          if (ik == iz) xyz[2] = v;
        }
      }
      if (is_vertex) soup.points.emplace_back(xyz[0], xyz[1], xyz[2]);
    }
  }
  if (!seen_vertex) fail(path, "PLY file has no vertex element");
  if (!binary && !c.at_end()) c.fail("unexpected data after the last element: " + Cursor::describe(c.token()));
  return soup;
}

// ---------------------------------------------------------------------------------
// STL

constexpr std::size_t kStlHeaderBytes = 84;
constexpr std::size_t kStlTriangleBytes = 50;

TriangleSoup read_stl_binary(std::string_view data, const fs::path& path) {
  if (data.size() < kStlHeaderBytes) {
    fail(path, "truncated binary STL: " + std::to_string(data.size()) + " bytes, the header alone needs 84");
  }
  const std::uint64_t n = load<std::uint32_t>(data.data() + 80, false);
  const std::uint64_t needed = kStlHeaderBytes + n * kStlTriangleBytes;
  if (data.size() < needed) {
    fail(path, "truncated binary STL: the header declares " + std::to_string(n) + " triangles (" +
                   std::to_string(needed) + " bytes) but the file has " + std::to_string(data.size()) + " bytes");
  }
  if (3 * n > kMaxPoints) fail(path, "too many triangles for 32-bit indices");
  TriangleSoup soup;
  soup.points.resize(3 * n);
  soup.triangles.resize(n);
  const char* p = data.data() + kStlHeaderBytes;
  for (std::uint64_t f = 0; f < n; ++f, p += kStlTriangleBytes) {
    for (std::uint64_t k = 0; k < 3; ++k) {
      const char* q = p + 12 + 12 * k;  // skip the normal
      soup.points[3 * f + k] = Eigen::Vector3d(load<float>(q, false), load<float>(q + 4, false), load<float>(q + 8, false));
    }
    const auto i = static_cast<std::uint32_t>(3 * f);
    soup.triangles[f] = {i, i + 1, i + 2};
  }
  return soup;
}

TriangleSoup read_stl_ascii(std::string_view data, const fs::path& path) {
  Cursor c(data, path);
  c.expect("solid");
  c.skip_line();  // the solid's name
  TriangleSoup soup;
  for (;;) {
    const std::string_view key = c.token();
    if (key == "endsolid") {
      c.skip_line();
      if (c.at_end()) break;
      c.expect("solid");  // several solids in one file
      c.skip_line();
      continue;
    }
    if (key != "facet") {
      c.fail(key.empty() ? "truncated: missing 'endsolid'"
                         : "expected 'facet' or 'endsolid', found " + Cursor::describe(key));
    }
    c.expect("normal");
    for (int k = 0; k < 3; ++k) (void)c.real();
    c.expect("outer");
    c.expect("loop");
    const auto i = static_cast<std::uint32_t>(soup.points.size());
    if (soup.points.size() + 3 > kMaxPoints) c.fail("too many triangles for 32-bit indices");
    for (int k = 0; k < 3; ++k) {
      c.expect("vertex");
      const double x = c.real();
      const double y = c.real();
      const double z = c.real();
      soup.points.emplace_back(x, y, z);
    }
    c.expect("endloop");
    c.expect("endfacet");
    soup.triangles.push_back({i, i + 1, i + 2});
  }
  return soup;
}

TriangleSoup read_stl(std::string_view data, const fs::path& path) {
  // A binary STL's size is fixed by its count; ASCII files start with "solid" (some
  // binary headers do too, hence the size test first).
  if (data.size() >= kStlHeaderBytes) {
    const std::uint64_t n = load<std::uint32_t>(data.data() + 80, false);
    if (data.size() == kStlHeaderBytes + n * kStlTriangleBytes) return read_stl_binary(data, path);
  }
  std::size_t start = 0;
  while (start < data.size() && std::isspace(static_cast<unsigned char>(data[start]))) ++start;
  if (data.substr(start, 5) == "solid") return read_stl_ascii(data, path);
  return read_stl_binary(data, path);
}

// ---------------------------------------------------------------------------------
// OFF

TriangleSoup read_off(std::string_view data, const fs::path& path) {
  Cursor c(data, path);
  c.set_comments(true);
  const std::string_view magic = c.token();
  if (magic != "OFF" && magic != "COFF" && magic != "NOFF" && magic != "CNOFF") {
    fail(path, "not an OFF file (first word is " + Cursor::describe(magic) + ")");
  }
  if (!c.at_eol()) {
    // counts may follow on the same line; "OFF BINARY" is not supported
    c.skip_blank();
    const char* p = c.here();
    if (*p < '0' || *p > '9') fail(path, "binary or unknown OFF variant is not supported");
  }
  const std::uint64_t nv = c.count("vertex count");
  const std::uint64_t nf = c.count("face count");
  (void)c.count("edge count");
  c.skip_line();
  check_point_count(c, nv);
  TriangleSoup soup;
  reserve_bounded(soup.points, nv, c.remaining(), 6);
  for (std::uint64_t i = 0; i < nv; ++i) {
    const double x = c.real();
    const double y = c.real();
    const double z = c.real();
    soup.points.emplace_back(x, y, z);
    c.skip_line();  // normals or colours of NOFF/COFF
  }
  reserve_bounded(soup.triangles, nf, c.remaining(), 8);
  std::vector<std::int64_t> poly;
  for (std::uint64_t f = 0; f < nf; ++f) {
    const std::int64_t n = c.integer();
    if (n < 0) c.fail("negative polygon size");
    poly.clear();
    for (std::int64_t k = 0; k < n; ++k) poly.push_back(c.integer_in_line());
    add_polygon(soup, poly, c);
    c.skip_line();  // optional face colour
  }
  if (!c.at_end()) c.fail("unexpected data after the last face: " + Cursor::describe(c.token()));
  return soup;
}

// ---------------------------------------------------------------------------------
// Legacy VTK POLYDATA

//! Reads n values of the given VTK type, ASCII or big-endian binary.
std::vector<std::int64_t> vtk_integers(Cursor& c, std::uint64_t n, Scalar type, bool binary) {
  std::vector<std::int64_t> out;
  if (binary) {
    if (!is_integer(type)) c.fail("cell data must have an integer type");
    const std::size_t s = scalar_size(type);
    c.need_items(n, s, "cell values");
    out.resize(n);
    for (std::uint64_t i = 0; i < n; ++i, c.advance(s)) out[i] = load_as_int(type, c.here(), true);
  } else {
    reserve_bounded(out, n, c.remaining(), 2);
    for (std::uint64_t i = 0; i < n; ++i) out.push_back(c.integer());
  }
  return out;
}

//! Cells of a POLYGONS or TRIANGLE_STRIPS section, as (offsets, connectivity).
struct VtkCells {
  std::vector<std::int64_t> offsets;
  std::vector<std::int64_t> connectivity;
};

VtkCells vtk_cells(Cursor& c, bool binary) {
  const std::uint64_t a = c.count("cell count");
  const std::uint64_t b = c.count("cell size");
  VtkCells cells;
  const std::size_t mark = c.pos();
  const std::string_view next = c.token();
  if (next == "OFFSETS") {
    // VTK >= 5.1 layout: OFFSETS <type> n+1 values, CONNECTIVITY <type> values.
    const Scalar ot = vtk_scalar(c.token());
    if (binary) c.skip_line();
    cells.offsets = vtk_integers(c, a, ot, binary);
    c.expect("CONNECTIVITY");
    const Scalar ct = vtk_scalar(c.token());
    if (binary) c.skip_line();
    cells.connectivity = vtk_integers(c, b, ct, binary);
    if (cells.offsets.empty() || cells.offsets.front() != 0 ||
        cells.offsets.back() != static_cast<std::int64_t>(cells.connectivity.size())) {
      c.fail("inconsistent OFFSETS/CONNECTIVITY arrays");
    }
    for (std::size_t i = 1; i < cells.offsets.size(); ++i) {
      if (cells.offsets[i] < cells.offsets[i - 1]) c.fail("decreasing OFFSETS");
    }
    return cells;
  }
  // Classic layout: a cells, b integers in all, each cell "k i1 ... ik".
  c.set_pos(mark);
  if (binary) c.skip_line();
  const std::vector<std::int64_t> flat = vtk_integers(c, b, Scalar::I32, binary);
  reserve_bounded(cells.offsets, a + 1, flat.size(), 1);
  reserve_bounded(cells.connectivity, b, flat.size(), 1);
  cells.offsets.push_back(0);
  std::size_t i = 0;
  for (std::uint64_t cell = 0; cell < a; ++cell) {
    if (i >= flat.size()) c.fail("cell list shorter than its declared " + std::to_string(a) + " cells");
    const std::int64_t k = flat[i++];
    if (k < 0 || static_cast<std::uint64_t>(k) > flat.size() - i) c.fail("cell size out of range");
    cells.connectivity.insert(cells.connectivity.end(), flat.begin() + static_cast<std::ptrdiff_t>(i),
                              flat.begin() + static_cast<std::ptrdiff_t>(i) + k);
    i += static_cast<std::size_t>(k);
    cells.offsets.push_back(static_cast<std::int64_t>(cells.connectivity.size()));
  }
  if (i != flat.size()) c.fail("cell list size does not match its cells");
  return cells;
}

TriangleSoup read_vtk(std::string_view data, const fs::path& path) {
  Cursor c(data, path);
  if (c.line().rfind("# vtk DataFile Version", 0) != 0) fail(path, "not a legacy VTK file");
  (void)c.line();  // title
  const std::string_view mode = c.token();
  if (mode != "ASCII" && mode != "BINARY") c.fail("expected ASCII or BINARY, found " + Cursor::describe(mode));
  const bool binary = mode == "BINARY";
  c.expect("DATASET");
  const std::string_view kind = c.token();
  if (kind != "POLYDATA") c.fail("only DATASET POLYDATA is supported, found " + Cursor::describe(kind));
  TriangleSoup soup;
  bool has_points = false;
  std::vector<std::int64_t> poly;
  for (;;) {
    const std::string_view key = c.token();
    if (key.empty() || key == "POINT_DATA" || key == "CELL_DATA" || key == "FIELD") break;  // attributes ignored
    if (key == "POINTS") {
      const std::uint64_t n = c.count("point count");
      check_point_count(c, n);
      const Scalar type = vtk_scalar(c.token());
      if (type == Scalar::Invalid) c.fail("unknown POINTS data type");
      if (binary) {
        c.skip_line();
        const std::size_t s = scalar_size(type);
        c.need_items(n, 3 * s, "points");
        soup.points.resize(n);
        for (auto& p : soup.points) {
          for (int k = 0; k < 3; ++k, c.advance(s)) p[k] = load_as_double(type, c.here(), true);
        }
      } else {
        reserve_bounded(soup.points, n, c.remaining(), 6);
        for (std::uint64_t i = 0; i < n; ++i) {
          const double x = c.real();
          const double y = c.real();
          const double z = c.real();
          soup.points.emplace_back(x, y, z);
        }
      }
      has_points = true;
    } else if (key == "VERTICES" || key == "LINES") {
      (void)vtk_cells(c, binary);  // not surface elements
    } else if (key == "POLYGONS") {
      const VtkCells cells = vtk_cells(c, binary);
      for (std::size_t i = 0; i + 1 < cells.offsets.size(); ++i) {
        poly.assign(cells.connectivity.begin() + cells.offsets[i], cells.connectivity.begin() + cells.offsets[i + 1]);
        add_polygon(soup, poly, c);
      }
    } else if (key == "TRIANGLE_STRIPS") {
      const VtkCells cells = vtk_cells(c, binary);
      for (std::size_t i = 0; i + 1 < cells.offsets.size(); ++i) {
        const std::int64_t* s = cells.connectivity.data() + cells.offsets[i];
        const std::int64_t k = cells.offsets[i + 1] - cells.offsets[i];
        if (k < 3) c.fail("triangle strip with fewer than 3 points");
        for (std::int64_t j = 0; j + 2 < k; ++j) {
          // every other triangle of a strip is flipped to keep one orientation
          if (j % 2 == 0) {
            poly = {s[j], s[j + 1], s[j + 2]};
          } else {
            poly = {s[j + 1], s[j], s[j + 2]};
          }
          add_polygon(soup, poly, c);
        }
      }
    } else if (key == "METADATA") {
      // VTK 9 writes "METADATA" blocks closed by an empty line.
      c.skip_line();
      while (c.remaining() > 0 && !c.line().empty()) {
      }
    } else {
      c.fail("unexpected keyword " + Cursor::describe(key));
    }
  }
  if (!has_points) fail(path, "VTK file has no POINTS");
  return soup;
}

}  // namespace

MeshFormat mesh_format_from_path(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  if (ext == ".obj") return MeshFormat::Obj;
  if (ext == ".ply") return MeshFormat::Ply;
  if (ext == ".stl") return MeshFormat::Stl;
  if (ext == ".off") return MeshFormat::Off;
  if (ext == ".vtk") return MeshFormat::Vtk;
  if (ext == ".vtu") return MeshFormat::Vtu;
  throw IoError("'" + path.string() + "': unsupported mesh format '" + ext +
                "' (supported: .obj .ply .stl .off .vtk .vtu)");
}

TriangleSoup read_soup(const std::filesystem::path& path) {
  const MeshFormat format = mesh_format_from_path(path);
  if (format == MeshFormat::Vtu) fail(path, "reading .vtu is not supported (write only)");
  const std::string data = load_file(path);
  TriangleSoup soup;
  switch (format) {
    case MeshFormat::Obj: soup = read_obj(data, path); break;
    case MeshFormat::Ply: soup = read_ply(data, path); break;
    case MeshFormat::Stl: soup = read_stl(data, path); break;
    case MeshFormat::Off: soup = read_off(data, path); break;
    case MeshFormat::Vtk: soup = read_vtk(data, path); break;
    case MeshFormat::Vtu: break;
  }
  validate_soup(path, soup);
  return soup;
}

TriMesh read_mesh(const std::filesystem::path& path, const CleanOptions& options) {
  options.validate();
  CleanResult cleaned = clean(read_soup(path), options);
  // to_trimesh() runs check_manifold() (the points are finite: read_soup checked them);
  // the check is repeated only to name the file in the error.
  TriMesh mesh;  // the one return value (named return value: OpenMesh meshes have no move)
  try {
    to_trimesh(cleaned.soup, mesh, parallel::thread_count(options.threads));
  } catch (const TopologyError&) {
    const ManifoldCheck check = check_manifold(cleaned.soup);
    throw TopologyError("'" + path.string() + "' is not an oriented 2-manifold after cleaning: " + check.message() +
                        " (prepare_mesh() repairs that: `nurbsfront convert --repair`)");
  }
  return mesh;
}

}  // namespace nurbsfront
