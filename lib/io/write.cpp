// SPDX-License-Identifier: BSD-3-Clause
// Writers. Our own rather than OpenMesh's: they take a TriangleSoup (so broken meshes can
// be dumped for inspection), write per-face fields to VTK/VTU/PLY, and never print.
// Output goes through a 1 MiB buffer; numbers are formatted with std::to_chars (the
// shortest text that reads back to the same double).
#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

#include "nurbsfront/core/error.h"
#include "nurbsfront/io/mesh_io.h"

namespace nurbsfront {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kFlushBytes = std::size_t{1} << 20;

class Writer {
 public:
  explicit Writer(const fs::path& path) : path_(path), out_(path, std::ios::binary | std::ios::trunc) {
    if (!out_) throw IoError("cannot write '" + path.string() + "': cannot open the file for writing");
    buffer_.reserve(kFlushBytes + 4096);
  }
  Writer& operator<<(std::string_view s) {
    buffer_.append(s);
    maybe_flush();
    return *this;
  }
  Writer& operator<<(char ch) {
    buffer_.push_back(ch);
    return *this;
  }
  Writer& operator<<(double v) {
    std::array<char, 32> tmp;
    const auto [ptr, ec] = std::to_chars(tmp.data(), tmp.data() + tmp.size(), v);
    buffer_.append(tmp.data(), ptr);
    maybe_flush();
    return *this;
  }
  Writer& operator<<(std::uint64_t v) {
    std::array<char, 24> tmp;
    const auto [ptr, ec] = std::to_chars(tmp.data(), tmp.data() + tmp.size(), v);
    buffer_.append(tmp.data(), ptr);
    maybe_flush();
    return *this;
  }
  //! Raw binary value in the given byte order.
  template <typename T>
  void raw(T value, bool big_endian) {
    std::array<char, sizeof(T)> bytes;
    std::memcpy(bytes.data(), &value, sizeof(T));
    if (big_endian != (std::endian::native == std::endian::big)) std::reverse(bytes.begin(), bytes.end());
    buffer_.append(bytes.data(), bytes.size());
    maybe_flush();
  }
  void close() {
    flush();
    out_.close();
    if (!out_) fail();
  }

 private:
  void maybe_flush() {
    if (buffer_.size() >= kFlushBytes) flush();
  }
  void flush() {
    out_.write(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
    buffer_.clear();
    if (!out_) fail();
  }
  [[noreturn]] void fail() const { throw IoError("cannot write '" + path_.string() + "': write error (disk full?)"); }

  fs::path path_;
  std::ofstream out_;
  std::string buffer_;
};

Eigen::Vector3d face_normal(const TriangleSoup& soup, const std::array<std::uint32_t, 3>& t) {
  const Eigen::Vector3d& a = soup.points[t[0]];
  const Eigen::Vector3d n = (soup.points[t[1]] - a).cross(soup.points[t[2]] - a);
  const double len = n.norm();
  return len > 0.0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

void write_obj(const TriangleSoup& soup, Writer& w) {
  w << "# written by nurbsfront\n";
  for (const auto& p : soup.points) w << "v " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  for (const auto& t : soup.triangles) {
    w << "f " << std::uint64_t{t[0]} + 1 << ' ' << std::uint64_t{t[1]} + 1 << ' ' << std::uint64_t{t[2]} + 1 << '\n';
  }
}

void write_off(const TriangleSoup& soup, Writer& w) {
  w << "OFF\n" << std::uint64_t{soup.points.size()} << ' ' << std::uint64_t{soup.triangles.size()} << " 0\n";
  for (const auto& p : soup.points) w << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  for (const auto& t : soup.triangles) {
    w << "3 " << std::uint64_t{t[0]} << ' ' << std::uint64_t{t[1]} << ' ' << std::uint64_t{t[2]} << '\n';
  }
}

void write_ply(const TriangleSoup& soup, Writer& w, const WriteOptions& options) {
  const bool binary = options.binary;
  const bool big = false;
  w << "ply\nformat " << (binary ? "binary_little_endian" : "ascii") << " 1.0\ncomment written by nurbsfront\n";
  w << "element vertex " << std::uint64_t{soup.points.size()} << "\nproperty double x\nproperty double y\nproperty double z\n";
  w << "element face " << std::uint64_t{soup.triangles.size()} << "\nproperty list uchar int vertex_indices\n";
  for (const auto& field : options.face_fields) w << "property double " << field.name << '\n';
  w << "end_header\n";
  for (const auto& p : soup.points) {
    if (binary) {
      for (int k = 0; k < 3; ++k) w.raw(p[k], big);
    } else {
      w << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
    }
  }
  for (std::size_t f = 0; f < soup.triangles.size(); ++f) {
    const auto& t = soup.triangles[f];
    if (binary) {
      w.raw(std::uint8_t{3}, big);
      for (int k = 0; k < 3; ++k) w.raw(static_cast<std::int32_t>(t[k]), big);
      for (const auto& field : options.face_fields) w.raw(field.values[f], big);
    } else {
      w << "3 " << std::uint64_t{t[0]} << ' ' << std::uint64_t{t[1]} << ' ' << std::uint64_t{t[2]};
      for (const auto& field : options.face_fields) w << ' ' << field.values[f];
      w << '\n';
    }
  }
}

void write_stl(const TriangleSoup& soup, Writer& w, bool binary) {
  if (binary) {
    std::string header = "binary STL written by nurbsfront";
    header.resize(80, ' ');
    w << header;
    w.raw(static_cast<std::uint32_t>(soup.triangles.size()), false);
    for (const auto& t : soup.triangles) {
      const Eigen::Vector3d n = face_normal(soup, t);
      for (int k = 0; k < 3; ++k) w.raw(static_cast<float>(n[k]), false);
      for (const std::uint32_t v : t) {
        for (int k = 0; k < 3; ++k) w.raw(static_cast<float>(soup.points[v][k]), false);
      }
      w.raw(std::uint16_t{0}, false);
    }
    return;
  }
  w << "solid nurbsfront\n";
  for (const auto& t : soup.triangles) {
    const Eigen::Vector3d n = face_normal(soup, t);
    w << " facet normal " << n.x() << ' ' << n.y() << ' ' << n.z() << "\n  outer loop\n";
    for (const std::uint32_t v : t) {
      const auto& p = soup.points[v];
      w << "   vertex " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
    }
    w << "  endloop\n endfacet\n";
  }
  w << "endsolid nurbsfront\n";
}

void write_vtk(const TriangleSoup& soup, Writer& w, const WriteOptions& options) {
  const bool binary = options.binary;
  const auto nf = std::uint64_t{soup.triangles.size()};
  w << "# vtk DataFile Version 3.0\nwritten by nurbsfront\n" << (binary ? "BINARY" : "ASCII") << "\nDATASET POLYDATA\n";
  w << "POINTS " << std::uint64_t{soup.points.size()} << " double\n";
  for (const auto& p : soup.points) {
    if (binary) {
      for (int k = 0; k < 3; ++k) w.raw(p[k], true);
    } else {
      w << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
    }
  }
  if (binary) w << '\n';
  w << "POLYGONS " << nf << ' ' << 4 * nf << '\n';
  for (const auto& t : soup.triangles) {
    if (binary) {
      w.raw(std::int32_t{3}, true);
      for (int k = 0; k < 3; ++k) w.raw(static_cast<std::int32_t>(t[k]), true);
    } else {
      w << "3 " << std::uint64_t{t[0]} << ' ' << std::uint64_t{t[1]} << ' ' << std::uint64_t{t[2]} << '\n';
    }
  }
  if (binary) w << '\n';
  if (options.face_fields.empty()) return;
  w << "CELL_DATA " << nf << '\n';
  for (const auto& field : options.face_fields) {
    w << "SCALARS " << field.name << " double 1\nLOOKUP_TABLE default\n";
    for (const double v : field.values) {
      if (binary) {
        w.raw(v, true);
      } else {
        w << v << '\n';
      }
    }
    if (binary) w << '\n';
  }
}

//! XML UnstructuredGrid of triangles. Binary: raw appended data, each array preceded by
//! its byte count as UInt64 (header_type="UInt64"), little endian.
void write_vtu(const TriangleSoup& soup, Writer& w, const WriteOptions& options) {
  const bool binary = options.binary;
  const auto np = std::uint64_t{soup.points.size()};
  const auto nf = std::uint64_t{soup.triangles.size()};
  std::uint64_t offset = 0;
  // Opens a DataArray; binary arrays are appended after the XML, so only their offset
  // is written here.
  auto open_array = [&](std::string_view type, std::string_view name, int components, std::uint64_t bytes) {
    w << "        <DataArray type=\"" << type << "\" Name=\"" << name << "\"";
    if (components > 1) w << " NumberOfComponents=\"" << std::uint64_t(components) << "\"";
    if (binary) {
      w << " format=\"appended\" offset=\"" << offset << "\"/>\n";
      offset += 8 + bytes;
    } else {
      w << " format=\"ascii\">\n";
    }
  };
  auto close_array = [&] {
    if (!binary) w << "\n        </DataArray>\n";
  };
  w << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\""
    << " header_type=\"UInt64\">\n  <UnstructuredGrid>\n    <Piece NumberOfPoints=\"" << np << "\" NumberOfCells=\""
    << nf << "\">\n      <Points>\n";
  open_array("Float64", "Points", 3, 24 * np);
  if (!binary) {
    for (const auto& p : soup.points) w << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  }
  close_array();
  w << "      </Points>\n      <Cells>\n";
  open_array("Int64", "connectivity", 1, 24 * nf);
  if (!binary) {
    for (const auto& t : soup.triangles) {
      w << std::uint64_t{t[0]} << ' ' << std::uint64_t{t[1]} << ' ' << std::uint64_t{t[2]} << '\n';
    }
  }
  close_array();
  open_array("Int64", "offsets", 1, 8 * nf);
  if (!binary) {
    for (std::uint64_t f = 0; f < nf; ++f) w << 3 * (f + 1) << '\n';
  }
  close_array();
  open_array("UInt8", "types", 1, nf);
  if (!binary) {
    for (std::uint64_t f = 0; f < nf; ++f) w << "5\n";  // VTK_TRIANGLE
  }
  close_array();
  w << "      </Cells>\n";
  if (!options.face_fields.empty()) {
    w << "      <CellData Scalars=\"" << options.face_fields.front().name << "\">\n";
    for (const auto& field : options.face_fields) {
      open_array("Float64", field.name, 1, 8 * nf);
      if (!binary) {
        for (const double v : field.values) w << v << '\n';
      }
      close_array();
    }
    w << "      </CellData>\n";
  }
  w << "    </Piece>\n  </UnstructuredGrid>\n";
  if (binary) {
    w << "  <AppendedData encoding=\"raw\">\n   _";
    w.raw(24 * np, false);
    for (const auto& p : soup.points) {
      for (int k = 0; k < 3; ++k) w.raw(p[k], false);
    }
    w.raw(24 * nf, false);
    for (const auto& t : soup.triangles) {
      for (int k = 0; k < 3; ++k) w.raw(static_cast<std::int64_t>(t[k]), false);
    }
    w.raw(8 * nf, false);
    for (std::uint64_t f = 0; f < nf; ++f) w.raw(static_cast<std::int64_t>(3 * (f + 1)), false);
    w.raw(nf, false);
    for (std::uint64_t f = 0; f < nf; ++f) w.raw(std::uint8_t{5}, false);
    for (const auto& field : options.face_fields) {
      w.raw(8 * nf, false);
      for (const double v : field.values) w.raw(v, false);
    }
    w << "\n  </AppendedData>\n";
  }
  w << "</VTKFile>\n";
}

bool valid_field_name(std::string_view name) {
  if (name.empty()) return false;
  return std::all_of(name.begin(), name.end(), [](char ch) {
    return (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') || ch == '_' ||
           ch == '-' || ch == '.';
  });
}

}  // namespace

void WriteOptions::validate() const {
  for (std::size_t i = 0; i < face_fields.size(); ++i) {
    const std::string& name = face_fields[i].name;
    if (!valid_field_name(name)) {
      throw InvalidInput("WriteOptions: face field name '" + name +
                         "' must be non-empty and use only letters, digits, '_', '-' and '.'");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (face_fields[j].name == name) throw InvalidInput("WriteOptions: face field '" + name + "' given twice");
    }
    if (name == "x" || name == "y" || name == "z" || name == "vertex_indices") {
      throw InvalidInput("WriteOptions: face field name '" + name + "' is reserved");
    }
  }
}

void write_soup(const TriangleSoup& soup, const std::filesystem::path& path, const WriteOptions& options) {
  options.validate();
  const MeshFormat format = mesh_format_from_path(path);
  const std::size_t n = soup.points.size();
  if (n > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) {
    throw InvalidInput("write_soup: more than 2^31-1 points");
  }
  for (std::size_t f = 0; f < soup.triangles.size(); ++f) {
    for (const std::uint32_t v : soup.triangles[f]) {
      if (v >= n) {
        throw InvalidInput("write_soup: triangle " + std::to_string(f) + " has out-of-range index " + std::to_string(v));
      }
    }
  }
  for (const auto& field : options.face_fields) {
    if (field.values.size() != soup.triangles.size()) {
      throw InvalidInput("write_soup: face field '" + field.name + "' has " + std::to_string(field.values.size()) +
                         " values for " + std::to_string(soup.triangles.size()) + " triangles");
    }
  }
  Writer w(path);
  switch (format) {
    case MeshFormat::Obj: write_obj(soup, w); break;
    case MeshFormat::Off: write_off(soup, w); break;
    case MeshFormat::Ply: write_ply(soup, w, options); break;
    case MeshFormat::Stl: write_stl(soup, w, options.binary); break;
    case MeshFormat::Vtk: write_vtk(soup, w, options); break;
    case MeshFormat::Vtu: write_vtu(soup, w, options); break;
  }
  w.close();
}

void write_mesh(const TriMesh& mesh, const std::filesystem::path& path, const WriteOptions& options) {
  write_soup(to_soup(mesh), path, options);
}

}  // namespace nurbsfront
