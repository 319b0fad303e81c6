// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/isosurface/volume_io.h"

#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <string_view>

#include "nurbsfront/core/error.h"

namespace nurbsfront {
namespace {

// Largest number of samples a volume may declare (2^34 floats = 64 GiB): guards the size
// arithmetic against overflow; the real guard is the check against the data present.
constexpr std::uint64_t kMaxSamples = std::uint64_t{1} << 34;
// Decompression works in chunks of this many bytes, so a lying header never causes a large allocation.
constexpr std::size_t kInflateChunk = std::size_t{1} << 20;

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& what) {
  throw IoError("nurbsfront: " + path.string() + ": " + what);
}

std::string read_bytes(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) fail(path, "no such file");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open file");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  std::string bytes = buffer.str();
  if (in.bad()) fail(path, "read error");
  if (bytes.empty()) fail(path, "file is empty");
  return bytes;
}

std::string read_gz_bytes(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) fail(path, "no such file");
  if (std::filesystem::file_size(path, ec) == 0) fail(path, "file is empty");
  gzFile file = gzopen(path.c_str(), "rb");
  if (file == nullptr) fail(path, "cannot open file");
  std::string bytes;
  std::vector<char> chunk(kInflateChunk);
  for (;;) {
    const int n = gzread(file, chunk.data(), static_cast<unsigned>(chunk.size()));
    if (n < 0) {
      int code = 0;
      const std::string message = gzerror(file, &code);
      gzclose(file);
      fail(path, "corrupt gzip data (" + message + ")");
    }
    if (n == 0) break;
    bytes.append(chunk.data(), static_cast<std::size_t>(n));
  }
  gzclose(file);
  if (bytes.empty()) fail(path, "file is empty after decompression");
  return bytes;
}

// zlib stream -> exactly `expected` bytes; fails on corrupt, short or long streams.
std::string inflate_exact(const std::filesystem::path& path, std::string_view src, std::uint64_t expected) {
  z_stream zs{};
  if (inflateInit(&zs) != Z_OK) fail(path, "zlib initialisation failed");
  std::string out;
  std::vector<char> chunk(kInflateChunk);
  zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(src.data()));
  zs.avail_in = static_cast<uInt>(std::min<std::size_t>(src.size(), std::numeric_limits<uInt>::max()));
  int status = Z_OK;
  while (status != Z_STREAM_END) {
    zs.next_out = reinterpret_cast<Bytef*>(chunk.data());
    zs.avail_out = static_cast<uInt>(chunk.size());
    status = inflate(&zs, Z_NO_FLUSH);
    if (status != Z_OK && status != Z_STREAM_END) {
      inflateEnd(&zs);
      fail(path, status == Z_BUF_ERROR ? "compressed data is truncated" : "corrupt compressed data");
    }
    out.append(chunk.data(), chunk.size() - zs.avail_out);
    if (out.size() > expected) {
      inflateEnd(&zs);
      fail(path, "compressed data holds more samples than the header's sizes");
    }
  }
  inflateEnd(&zs);
  if (out.size() != expected) {
    fail(path, "compressed data holds " + std::to_string(out.size()) + " bytes, the header's sizes need " +
                   std::to_string(expected));
  }
  return out;
}

enum class Elem { U8, I8, U16, I16, U32, I32, U64, I64, F32, F64 };

std::size_t elem_size(Elem e) {
  switch (e) {
    case Elem::U8:
    case Elem::I8: return 1;
    case Elem::U16:
    case Elem::I16: return 2;
    case Elem::U32:
    case Elem::I32:
    case Elem::F32: return 4;
    default: return 8;
  }
}

template <class T>
T load(const unsigned char* p, bool big_endian) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, p, sizeof(T));
  constexpr bool host_big = std::endian::native == std::endian::big;
  if (big_endian != host_big) std::reverse(b, b + sizeof(T));
  T v;
  std::memcpy(&v, b, sizeof(T));
  return v;
}

template <class T>
void convert_as(const unsigned char* p, std::size_t n, bool big_endian, std::vector<float>& out) {
  for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<float>(load<T>(p + i * sizeof(T), big_endian));
}

// The raw data must hold exactly the bytes the header's sizes need.
void check_data_size(const std::filesystem::path& path, std::string_view data, std::uint64_t n_bytes) {
  if (data.size() < n_bytes) {
    fail(path, "data is truncated: " + std::to_string(data.size()) + " bytes, the header's sizes need " +
                   std::to_string(n_bytes));
  }
  if (data.size() > n_bytes) {
    fail(path, "data holds " + std::to_string(data.size()) + " bytes, more than the header's sizes (" +
                   std::to_string(n_bytes) + ")");
  }
}

std::vector<float> convert(const std::filesystem::path& path, std::string_view data, std::uint64_t n, Elem e,
                           bool big_endian) {
  if (data.size() < n * elem_size(e)) fail(path, "data is truncated");
  std::vector<float> out(n);
  const auto* p = reinterpret_cast<const unsigned char*>(data.data());
  switch (e) {
    case Elem::U8: convert_as<std::uint8_t>(p, n, big_endian, out); break;
    case Elem::I8: convert_as<std::int8_t>(p, n, big_endian, out); break;
    case Elem::U16: convert_as<std::uint16_t>(p, n, big_endian, out); break;
    case Elem::I16: convert_as<std::int16_t>(p, n, big_endian, out); break;
    case Elem::U32: convert_as<std::uint32_t>(p, n, big_endian, out); break;
    case Elem::I32: convert_as<std::int32_t>(p, n, big_endian, out); break;
    case Elem::U64: convert_as<std::uint64_t>(p, n, big_endian, out); break;
    case Elem::I64: convert_as<std::int64_t>(p, n, big_endian, out); break;
    case Elem::F32: convert_as<float>(p, n, big_endian, out); break;
    case Elem::F64: convert_as<double>(p, n, big_endian, out); break;
  }
  for (const float v : out) {
    if (!std::isfinite(v)) fail(path, "data contains a non-finite value");
  }
  return out;
}

// Whitespace-separated numbers of ASCII data; exactly n are required (more is a mismatch).
std::vector<float> parse_ascii(const std::filesystem::path& path, std::string_view text, std::uint64_t n) {
  std::vector<float> out;
  std::size_t pos = 0;
  while (true) {
    while (pos < text.size() && std::isspace(static_cast<unsigned char>(text[pos]))) ++pos;
    if (pos >= text.size()) break;
    std::size_t end = pos;
    while (end < text.size() && !std::isspace(static_cast<unsigned char>(text[end]))) ++end;
    if (out.size() >= n) fail(path, "data holds more values than the header's sizes");
    const std::string token(text.substr(pos, end - pos));
    char* stop = nullptr;
    const double v = std::strtod(token.c_str(), &stop);
    if (stop == token.c_str() || *stop != '\0' || !std::isfinite(v)) fail(path, "bad number '" + token + "' in data");
    out.push_back(static_cast<float>(v));
    pos = end;
  }
  if (out.size() != n) {
    fail(path, "data is truncated: " + std::to_string(out.size()) + " values, the header's sizes need " +
                   std::to_string(n));
  }
  return out;
}

std::string trim(std::string_view s) {
  std::size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return std::string(s.substr(a, b - a));
}

std::vector<std::string> split_words(const std::string& s) {
  std::istringstream in(s);
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  return words;
}

std::vector<double> parse_numbers(const std::filesystem::path& path, const std::string& key, const std::string& s,
                                  std::size_t count) {
  const auto words = split_words(s);
  if (words.size() < count) fail(path, "header field " + key + " needs " + std::to_string(count) + " numbers");
  std::vector<double> out;
  for (std::size_t i = 0; i < count; ++i) {
    char* stop = nullptr;
    const double v = std::strtod(words[i].c_str(), &stop);
    if (stop == words[i].c_str() || *stop != '\0' || !std::isfinite(v)) {
      fail(path, "header field " + key + " has a bad number '" + words[i] + "'");
    }
    out.push_back(v);
  }
  return out;
}

std::array<int, 3> checked_dims(const std::filesystem::path& path, const std::vector<double>& d) {
  std::array<int, 3> dims{1, 1, 1};
  std::uint64_t total = 1;
  for (std::size_t a = 0; a < d.size() && a < 3; ++a) {
    if (d[a] < 1 || d[a] > std::numeric_limits<int>::max() || d[a] != std::floor(d[a])) {
      fail(path, "bad dimension " + std::to_string(d[a]) + " in header");
    }
    dims[a] = static_cast<int>(d[a]);
    total *= static_cast<std::uint64_t>(dims[a]);
    if (total > kMaxSamples) fail(path, "header declares too many samples");
  }
  return dims;
}

std::uint64_t count(const std::array<int, 3>& dims) {
  return static_cast<std::uint64_t>(dims[0]) * static_cast<std::uint64_t>(dims[1]) * static_cast<std::uint64_t>(dims[2]);
}

void check_spacing(const std::filesystem::path& path, const Eigen::Vector3d& spacing) {
  if (!spacing.allFinite() || (spacing.array() <= 0.0).any()) fail(path, "spacing must be positive");
}

// Reads the next line (without its end of line) from text at pos; false at the end.
bool next_line(std::string_view text, std::size_t& pos, std::string& line) {
  if (pos >= text.size()) return false;
  std::size_t end = text.find('\n', pos);
  if (end == std::string_view::npos) end = text.size();
  line = std::string(text.substr(pos, end - pos));
  if (!line.empty() && line.back() == '\r') line.pop_back();
  pos = std::min(end + 1, text.size());
  return true;
}

bool is_true(const std::string& s) {
  std::string l = s;
  std::transform(l.begin(), l.end(), l.begin(), [](unsigned char c) { return std::tolower(c); });
  return l == "true" || l == "1";
}

// ------------------------------------------------------------------------- MetaImage

ScalarGrid read_metaimage(const std::filesystem::path& path) {
  const std::string bytes = read_bytes(path);
  std::map<std::string, std::string> header;
  std::size_t pos = 0;
  std::string line;
  bool has_data_file = false;
  while (next_line(bytes, pos, line)) {
    const std::size_t eq = line.find('=');
    if (trim(line).empty()) continue;
    if (eq == std::string::npos) fail(path, "malformed MetaImage header line '" + trim(line).substr(0, 80) + "'");
    const std::string key = trim(std::string_view(line).substr(0, eq));
    header[key] = trim(std::string_view(line).substr(eq + 1));
    if (key == "ElementDataFile") {
      has_data_file = true;
      break;
    }
  }
  if (!has_data_file) fail(path, "MetaImage header has no ElementDataFile");
  auto get = [&](const std::string& key) -> const std::string* {
    auto it = header.find(key);
    return it == header.end() ? nullptr : &it->second;
  };
  const std::string* ndims_s = get("NDims");
  if (ndims_s == nullptr) fail(path, "MetaImage header has no NDims");
  const int ndims = static_cast<int>(parse_numbers(path, "NDims", *ndims_s, 1)[0]);
  if (ndims != 2 && ndims != 3) fail(path, "only 2D or 3D MetaImages are supported");
  const std::string* dim_s = get("DimSize");
  if (dim_s == nullptr) fail(path, "MetaImage header has no DimSize");
  ScalarGrid grid;
  grid.dims = checked_dims(path, parse_numbers(path, "DimSize", *dim_s, ndims));
  for (const char* key : {"ElementSpacing", "ElementSize"}) {
    if (const std::string* s = get(key)) {
      const auto v = parse_numbers(path, key, *s, ndims);
      for (int a = 0; a < ndims; ++a) grid.spacing[a] = v[a];
      break;
    }
  }
  check_spacing(path, grid.spacing);
  for (const char* key : {"Offset", "Position", "Origin"}) {
    if (const std::string* s = get(key)) {
      const auto v = parse_numbers(path, key, *s, ndims);
      for (int a = 0; a < ndims; ++a) grid.origin[a] = v[a];
      break;
    }
  }
  if (const std::string* s = get("ElementNumberOfChannels")) {
    if (parse_numbers(path, "ElementNumberOfChannels", *s, 1)[0] != 1) fail(path, "only one channel is supported");
  }
  const std::string* type_s = get("ElementType");
  if (type_s == nullptr) fail(path, "MetaImage header has no ElementType");
  static constexpr std::pair<std::string_view, Elem> kTypes[] = {
      {"MET_UCHAR", Elem::U8}, {"MET_CHAR", Elem::I8},  {"MET_USHORT", Elem::U16}, {"MET_SHORT", Elem::I16},
      {"MET_UINT", Elem::U32}, {"MET_INT", Elem::I32},  {"MET_ULONG_LONG", Elem::U64}, {"MET_LONG_LONG", Elem::I64},
      {"MET_FLOAT", Elem::F32}, {"MET_DOUBLE", Elem::F64}};
  const auto type_it = std::find_if(std::begin(kTypes), std::end(kTypes), [&](const auto& t) { return t.first == *type_s; });
  if (type_it == std::end(kTypes)) fail(path, "unsupported ElementType " + *type_s);
  const Elem elem = type_it->second;
  bool big_endian = false;
  for (const char* key : {"BinaryDataByteOrderMSB", "ElementByteOrderMSB"}) {
    if (const std::string* s = get(key)) big_endian = big_endian || is_true(*s);
  }
  const bool binary = get("BinaryData") == nullptr || is_true(*get("BinaryData"));
  const bool compressed = get("CompressedData") != nullptr && is_true(*get("CompressedData"));
  const std::string& data_file = *get("ElementDataFile");

  std::string external;
  std::string_view data;
  if (data_file == "LOCAL") {
    data = std::string_view(bytes).substr(pos);
  } else {
    if (data_file.rfind("LIST", 0) == 0 || data_file.find('%') != std::string::npos) {
      fail(path, "ElementDataFile lists and patterns are not supported");
    }
    external = read_bytes(path.parent_path() / data_file);
    data = external;
  }
  const std::uint64_t n = count(grid.dims);
  const std::uint64_t n_bytes = n * elem_size(elem);
  if (compressed) {
    if (!binary) fail(path, "compressed ASCII data is not supported");
    if (const std::string* s = get("CompressedDataSize")) {
      const double size = parse_numbers(path, "CompressedDataSize", *s, 1)[0];
      if (size < 0 || size > static_cast<double>(data.size())) fail(path, "compressed data is truncated");
      data = data.substr(0, static_cast<std::size_t>(size));
    }
    const std::string raw = inflate_exact(path, data, n_bytes);
    grid.values = convert(path, raw, n, elem, big_endian);
  } else if (!binary) {
    grid.values = parse_ascii(path, data, n);
  } else {
    if (const std::string* s = get("HeaderSize")) {
      const double skip = parse_numbers(path, "HeaderSize", *s, 1)[0];
      if (skip == -1) {
        if (data.size() < n_bytes) fail(path, "data is truncated");
        data = data.substr(data.size() - n_bytes);
      } else if (skip >= 0) {
        if (skip > static_cast<double>(data.size())) fail(path, "data is truncated");
        data = data.substr(static_cast<std::size_t>(skip));
      }
    }
    check_data_size(path, data, n_bytes);
    grid.values = convert(path, data, n, elem, big_endian);
  }
  return grid;
}

// ------------------------------------------------------------------------- legacy VTK

Elem vtk_type(const std::filesystem::path& path, const std::string& t) {
  if (t == "unsigned_char" || t == "bit") {
    if (t == "bit") fail(path, "VTK bit data is not supported");
    return Elem::U8;
  }
  if (t == "char" || t == "signed_char") return Elem::I8;
  if (t == "unsigned_short") return Elem::U16;
  if (t == "short") return Elem::I16;
  if (t == "unsigned_int") return Elem::U32;
  if (t == "int") return Elem::I32;
  if (t == "unsigned_long" || t == "vtktypeuint64") return Elem::U64;
  if (t == "long" || t == "vtktypeint64") return Elem::I64;
  if (t == "float") return Elem::F32;
  if (t == "double") return Elem::F64;
  fail(path, "unsupported VTK scalar type " + t);
}

ScalarGrid read_vtk(const std::filesystem::path& path) {
  const std::string bytes = read_bytes(path);
  std::size_t pos = 0;
  std::string line;
  if (!next_line(bytes, pos, line) || line.rfind("# vtk DataFile", 0) != 0) fail(path, "not a legacy VTK file");
  if (!next_line(bytes, pos, line)) fail(path, "VTK header is truncated");  // title
  do {  // blank lines may precede the format line
    if (!next_line(bytes, pos, line)) fail(path, "VTK header is truncated");
  } while (trim(line).empty());
  const std::string mode = trim(line);
  if (mode != "ASCII" && mode != "BINARY") fail(path, "VTK file is neither ASCII nor BINARY");
  const bool binary = mode == "BINARY";
  ScalarGrid grid;
  bool has_dims = false, has_dataset = false, has_scalars = false;
  std::uint64_t n_points = 0;
  Elem elem = Elem::F32;
  while (next_line(bytes, pos, line)) {
    const auto words = split_words(line);
    if (words.empty()) continue;
    std::string key = words[0];
    std::transform(key.begin(), key.end(), key.begin(), [](unsigned char c) { return std::toupper(c); });
    const std::string rest = words.size() > 1 ? line.substr(line.find(words[0]) + words[0].size()) : std::string();
    if (key == "DATASET") {
      if (words.size() < 2 || words[1] != "STRUCTURED_POINTS") fail(path, "only VTK STRUCTURED_POINTS datasets are supported");
      has_dataset = true;
    } else if (key == "DIMENSIONS") {
      grid.dims = checked_dims(path, parse_numbers(path, "DIMENSIONS", rest, 3));
      has_dims = true;
    } else if (key == "SPACING" || key == "ASPECT_RATIO") {
      const auto v = parse_numbers(path, key, rest, 3);
      grid.spacing = {v[0], v[1], v[2]};
      check_spacing(path, grid.spacing);
    } else if (key == "ORIGIN") {
      const auto v = parse_numbers(path, key, rest, 3);
      grid.origin = {v[0], v[1], v[2]};
    } else if (key == "POINT_DATA") {
      n_points = static_cast<std::uint64_t>(parse_numbers(path, key, rest, 1)[0]);
    } else if (key == "SCALARS") {
      if (words.size() < 3) fail(path, "malformed SCALARS line");
      elem = vtk_type(path, words[2]);
      if (words.size() > 3 && words[3] != "1") fail(path, "only one scalar component is supported");
      has_scalars = true;
      // The LOOKUP_TABLE line is optional in practice; consume it if it follows.
      std::size_t peek = pos;
      std::string next;
      if (next_line(bytes, peek, next) && trim(next).rfind("LOOKUP_TABLE", 0) == 0) pos = peek;
      break;
    } else if (key == "CELL_DATA" || key == "FIELD" || key == "VECTORS") {
      fail(path, "VTK " + key + " data is not supported (need POINT_DATA SCALARS)");
    }
  }
  if (!has_dataset) fail(path, "VTK file has no DATASET STRUCTURED_POINTS");
  if (!has_dims) fail(path, "VTK file has no DIMENSIONS");
  if (!has_scalars) fail(path, "VTK file has no POINT_DATA SCALARS");
  const std::uint64_t n = count(grid.dims);
  if (n_points != n) {
    fail(path, "POINT_DATA " + std::to_string(n_points) + " does not match DIMENSIONS (" + std::to_string(n) + ")");
  }
  const std::string_view data = std::string_view(bytes).substr(pos);
  if (binary) {
    if (data.size() < n * elem_size(elem)) {
      fail(path, "data is truncated: " + std::to_string(data.size()) + " bytes, the header's sizes need " +
                     std::to_string(n * elem_size(elem)));
    }
    grid.values = convert(path, data, n, elem, true);
  } else {
    // ASCII: the scalars end where a next section (a keyword) starts.
    std::size_t end = data.size();
    for (std::size_t p = 0; p < data.size(); ++p) {
      if (std::isalpha(static_cast<unsigned char>(data[p])) && data[p] != 'e' && data[p] != 'E' &&
          (p == 0 || data[p - 1] == '\n')) {
        end = p;
        break;
      }
    }
    grid.values = parse_ascii(path, data.substr(0, end), n);
  }
  return grid;
}

// ------------------------------------------------------------------------- INRIA .inr

ScalarGrid read_inr(const std::filesystem::path& path, bool gz) {
  const std::string bytes = gz ? read_gz_bytes(path) : read_bytes(path);
  if (bytes.rfind("#INRIMAGE-4#{", 0) != 0) fail(path, "not an INRIMAGE-4 file");
  const std::size_t end_tag = bytes.find("##}");
  if (end_tag == std::string::npos) fail(path, "INR header has no end tag '##}'");
  std::size_t data_start = bytes.find('\n', end_tag);
  if (data_start == std::string::npos) fail(path, "INR header is truncated");
  ++data_start;
  if (data_start % 256 != 0) fail(path, "INR header length is not a multiple of 256 bytes");
  std::map<std::string, std::string> header;
  std::size_t pos = 0;
  std::string line;
  const std::string_view head = std::string_view(bytes).substr(0, end_tag);
  next_line(head, pos, line);  // #INRIMAGE-4#{
  while (next_line(head, pos, line)) {
    const std::size_t eq = line.find('=');
    if (line.empty() || line[0] == '#' || eq == std::string::npos) continue;
    header[trim(std::string_view(line).substr(0, eq))] = trim(std::string_view(line).substr(eq + 1));
  }
  auto number = [&](const std::string& key, double fallback, bool required) {
    auto it = header.find(key);
    if (it == header.end()) {
      if (required) fail(path, "INR header has no " + key);
      return fallback;
    }
    return parse_numbers(path, key, it->second, 1)[0];
  };
  ScalarGrid grid;
  grid.dims = checked_dims(path, {number("XDIM", 1, true), number("YDIM", 1, true), number("ZDIM", 1, true)});
  if (number("VDIM", 1, false) != 1) fail(path, "only VDIM=1 INR images are supported");
  grid.spacing = {number("VX", 1, false), number("VY", 1, false), number("VZ", 1, false)};
  check_spacing(path, grid.spacing);
  grid.origin = {number("XO", number("TX", 0, false), false), number("YO", number("TY", 0, false), false),
                 number("ZO", number("TZ", 0, false), false)};
  const std::string type = header.count("TYPE") ? header["TYPE"] : std::string();
  const std::string pixsize = header.count("PIXSIZE") ? header["PIXSIZE"] : std::string();
  const auto bits_words = split_words(pixsize);
  if (bits_words.empty()) fail(path, "INR header has no PIXSIZE");
  const int bits = static_cast<int>(parse_numbers(path, "PIXSIZE", bits_words[0], 1)[0]);
  Elem elem = Elem::U8;
  if (type == "unsigned fixed") {
    if (bits == 8) elem = Elem::U8;
    else if (bits == 16) elem = Elem::U16;
    else if (bits == 32) elem = Elem::U32;
    else if (bits == 64) elem = Elem::U64;
    else fail(path, "unsupported PIXSIZE " + pixsize);
  } else if (type == "signed fixed") {
    if (bits == 8) elem = Elem::I8;
    else if (bits == 16) elem = Elem::I16;
    else if (bits == 32) elem = Elem::I32;
    else if (bits == 64) elem = Elem::I64;
    else fail(path, "unsupported PIXSIZE " + pixsize);
  } else if (type == "float") {
    if (bits == 32) elem = Elem::F32;
    else if (bits == 64) elem = Elem::F64;
    else fail(path, "unsupported PIXSIZE " + pixsize);
  } else {
    fail(path, "unsupported INR TYPE '" + type + "'");
  }
  const std::string cpu = header.count("CPU") ? header["CPU"] : std::string("decm");
  bool big_endian = false;
  if (cpu == "sun" || cpu == "sgi") big_endian = true;
  else if (cpu != "decm" && cpu != "alpha" && cpu != "pc") fail(path, "unknown INR CPU '" + cpu + "'");
  const std::uint64_t n = count(grid.dims);
  const std::string_view data = std::string_view(bytes).substr(data_start);
  const std::uint64_t n_bytes = n * elem_size(elem);
  check_data_size(path, data, n_bytes);
  grid.values = convert(path, data, n, elem, big_endian);
  return grid;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

}  // namespace

ScalarGrid read_volume(const std::filesystem::path& path) {
  const std::string name = lower(path.filename().string());
  auto ends_with = [&](std::string_view suffix) {
    return name.size() >= suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
  };
  ScalarGrid grid;
  if (ends_with(".mha") || ends_with(".mhd")) {
    grid = read_metaimage(path);
  } else if (ends_with(".vtk")) {
    grid = read_vtk(path);
  } else if (ends_with(".inr.gz")) {
    grid = read_inr(path, true);
  } else if (ends_with(".inr")) {
    grid = read_inr(path, false);
  } else {
    fail(path, "unknown volume file extension (expected .mha, .mhd, .vtk, .inr or .inr.gz)");
  }
  try {
    grid.validate();
  } catch (const InvalidInput& e) {
    fail(path, e.what());
  }
  return grid;
}

}  // namespace nurbsfront
