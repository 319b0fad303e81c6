// SPDX-License-Identifier: BSD-3-Clause
// Writers: every format reads back to the same points and triangles, and the VTK/VTU
// outputs with per-face fields are well formed (fields parsed back from the files).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>

#include "fixtures/shapes.h"
#include "io/io_test_util.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/io/mesh_io.h"
#include "support/test_data.h"

namespace nurbsfront {
namespace {

//! A torus with coordinates that are not short decimals (1/3, offsets, ...).
TriangleSoup awkward_torus() {
  TriangleSoup s = test::torus(24, 12, 1.0 / 3.0, 0.1);
  for (auto& p : s.points) p = p * 7.123456789 + Eigen::Vector3d(1e3 / 7.0, -2.5e-3, 123.456);
  return s;
}

struct Case {
  const char* file;
  bool binary;
};

class RoundTrip : public ::testing::TestWithParam<Case> {};

TEST_P(RoundTrip, SamePointsAndTriangles) {
  const Case c = GetParam();
  const TriangleSoup s = awkward_torus();
  const auto path = test::temp_dir(std::string("io_rt_") + (c.binary ? "b_" : "a_") + c.file) / c.file;
  WriteOptions options;
  options.binary = c.binary;
  write_soup(s, path, options);
  const TriangleSoup back = read_soup(path);
  const bool is_float = mesh_format_from_path(path) == MeshFormat::Stl && c.binary;
  // single precision STL: half an ulp of float relative to the coordinate size
  const double tol = is_float ? 200.0 * 0.5 * 1.2e-7 : 0.0;
  if (mesh_format_from_path(path) == MeshFormat::Stl) {
    // STL stores three corners per facet: compare corner by corner, then weld.
    ASSERT_EQ(back.triangles.size(), s.triangles.size());
    for (std::size_t f = 0; f < s.triangles.size(); ++f) {
      for (int k = 0; k < 3; ++k) {
        const double d = (back.points[back.triangles[f][k]] - s.points[s.triangles[f][k]]).cwiseAbs().maxCoeff();
        ASSERT_LE(d, tol) << "triangle " << f << " corner " << k;
      }
    }
    const CleanResult welded = clean(back);
    EXPECT_EQ(welded.soup.points.size(), s.points.size());
    EXPECT_EQ(welded.soup.triangles.size(), s.triangles.size());
    EXPECT_TRUE(check_manifold(welded.soup).ok());
    return;
  }
  ASSERT_EQ(back.points.size(), s.points.size());
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    ASSERT_EQ(back.points[i], s.points[i]) << "point " << i;  // shortest round-trip text or raw doubles
  }
  EXPECT_EQ(back.triangles, s.triangles);
}

INSTANTIATE_TEST_SUITE_P(AllFormats, RoundTrip,
                         ::testing::Values(Case{"m.obj", false}, Case{"m.off", false}, Case{"m.ply", false},
                                           Case{"m.ply", true}, Case{"m.stl", false}, Case{"m.stl", true},
                                           Case{"m.vtk", false}, Case{"m.vtk", true}),
                         [](const auto& param_info) {
                           std::string name = param_info.param.file;
                           return name.substr(2) + (param_info.param.binary ? "_binary" : "_ascii");
                         });

TEST(WriteMesh, TriMeshRoundTripThroughReadMesh) {
  const TriMesh mesh = to_trimesh(test::icosphere(2));
  const auto path = test::temp_dir("io_trimesh") / "s.ply";
  write_mesh(mesh, path);
  const TriMesh back = read_mesh(path);
  EXPECT_EQ(back.n_vertices(), mesh.n_vertices());
  EXPECT_EQ(back.n_faces(), mesh.n_faces());
  EXPECT_EQ(to_soup(back).triangles, to_soup(mesh).triangles);
}

std::vector<FaceField> two_fields(std::size_t n) {
  FaceField quality{"quality", {}};
  FaceField patch{"patch_id", {}};
  for (std::size_t f = 0; f < n; ++f) {
    quality.values.push_back(1.0 / static_cast<double>(f + 3));
    patch.values.push_back(static_cast<double>(f % 5));
  }
  return {quality, patch};
}

//! Values following "SCALARS <name> double 1\nLOOKUP_TABLE default\n" in an ASCII VTK file.
std::vector<double> vtk_scalars(const std::string& text, const std::string& name, std::size_t n) {
  const std::string key = "SCALARS " + name + " double 1\nLOOKUP_TABLE default\n";
  const auto at = text.find(key);
  if (at == std::string::npos) return {};
  std::istringstream in(text.substr(at + key.size()));
  std::vector<double> values(n);
  for (double& v : values) in >> v;
  return values;
}

TEST(WriteVtk, AsciiFaceFieldsParseBack) {
  const TriangleSoup s = test::icosphere(1);
  WriteOptions options;
  options.binary = false;
  options.face_fields = two_fields(s.triangles.size());
  const auto path = test::temp_dir("io_vtk_fields") / "f.vtk";
  write_soup(s, path, options);
  const std::string text = test::read_file(path);
  EXPECT_NE(text.find("CELL_DATA " + std::to_string(s.triangles.size()) + "\n"), std::string::npos);
  for (const auto& field : options.face_fields) {
    const std::vector<double> values = vtk_scalars(text, field.name, s.triangles.size());
    ASSERT_EQ(values.size(), field.values.size()) << field.name;
    for (std::size_t f = 0; f < values.size(); ++f) EXPECT_DOUBLE_EQ(values[f], field.values[f]);
  }
  // the reader skips the attributes and still gets the mesh
  EXPECT_EQ(read_soup(path).triangles, s.triangles);
  // binary variant: also readable, same mesh
  options.binary = true;
  write_soup(s, path, options);
  EXPECT_EQ(read_soup(path).triangles, s.triangles);
}

//! The text between <DataArray ... Name="name" ...> and </DataArray>.
std::string vtu_array(const std::string& text, const std::string& name) {
  const auto at = text.find("Name=\"" + name + "\"");
  if (at == std::string::npos) return {};
  const auto begin = text.find('>', at) + 1;
  const auto end = text.find("</DataArray>", begin);
  return text.substr(begin, end - begin);
}

TEST(WriteVtu, AsciiIsWellFormedWithFields) {
  const TriangleSoup s = test::cube();
  WriteOptions options;
  options.binary = false;
  options.face_fields = two_fields(s.triangles.size());
  const auto path = test::temp_dir("io_vtu_a") / "c.vtu";
  write_soup(s, path, options);
  const std::string text = test::read_file(path);
  EXPECT_EQ(text.rfind("<?xml", 0), 0u);
  EXPECT_NE(text.find("NumberOfPoints=\"8\" NumberOfCells=\"12\""), std::string::npos);
  EXPECT_NE(text.find("</VTKFile>"), std::string::npos);
  // as many DataArray opened as closed
  std::size_t n_open = 0, n_close = 0;
  for (auto p = text.find("<DataArray"); p != std::string::npos; p = text.find("<DataArray", p + 1)) ++n_open;
  for (auto p = text.find("</DataArray>"); p != std::string::npos; p = text.find("</DataArray>", p + 1)) ++n_close;
  EXPECT_EQ(n_open, 6u);  // points, connectivity, offsets, types, 2 fields
  EXPECT_EQ(n_close, n_open);
  std::istringstream conn(vtu_array(text, "connectivity"));
  for (const auto& t : s.triangles) {
    for (const std::uint32_t v : t) {
      std::uint32_t read = 0;
      conn >> read;
      EXPECT_EQ(read, v);
    }
  }
  std::istringstream offsets(vtu_array(text, "offsets"));
  for (std::size_t f = 0; f < s.triangles.size(); ++f) {
    std::size_t o = 0;
    offsets >> o;
    EXPECT_EQ(o, 3 * (f + 1));
  }
  for (const auto& field : options.face_fields) {
    std::istringstream in(vtu_array(text, field.name));
    std::size_t n = 0;
    for (double v = 0; in >> v; ++n) {
      ASSERT_LT(n, field.values.size());
      EXPECT_DOUBLE_EQ(v, field.values[n]);
    }
    EXPECT_EQ(n, field.values.size()) << field.name;
  }
}

TEST(WriteVtu, BinaryAppendedBlocksHaveDeclaredSizes) {
  const TriangleSoup s = test::icosphere(1);
  WriteOptions options;
  options.face_fields = two_fields(s.triangles.size());
  const auto path = test::temp_dir("io_vtu_b") / "s.vtu";
  write_soup(s, path, options);
  const std::string text = test::read_file(path);
  const auto marker = text.find("<AppendedData encoding=\"raw\">");
  ASSERT_NE(marker, std::string::npos);
  const std::size_t base = text.find('_', marker) + 1;
  const std::size_t np = s.points.size(), nf = s.triangles.size();
  // blocks in order: points, connectivity, offsets, types, quality, patch_id
  const std::vector<std::size_t> sizes = {24 * np, 24 * nf, 8 * nf, nf, 8 * nf, 8 * nf};
  std::size_t pos = base;
  std::vector<std::size_t> starts;
  for (const std::size_t expected : sizes) {
    ASSERT_LE(pos + 8, text.size());
    std::uint64_t declared = 0;
    std::memcpy(&declared, text.data() + pos, 8);
    EXPECT_EQ(declared, expected);
    // the XML offset attribute points at this block
    EXPECT_NE(text.find("offset=\"" + std::to_string(pos - base) + "\""), std::string::npos);
    starts.push_back(pos + 8);
    pos += 8 + expected;
  }
  EXPECT_EQ(text.substr(pos), "\n  </AppendedData>\n</VTKFile>\n");
  for (std::size_t f = 0; f < nf; ++f) {
    double q = 0.0;
    std::memcpy(&q, text.data() + starts[4] + 8 * f, 8);
    EXPECT_EQ(q, options.face_fields[0].values[f]);
  }
}

TEST(WritePly, FaceFieldsAreExtraPropertiesTheReaderSkips) {
  const TriangleSoup s = test::cube();
  WriteOptions options;
  options.face_fields = two_fields(s.triangles.size());
  const auto path = test::temp_dir("io_ply_fields") / "c.ply";
  for (const bool binary : {true, false}) {
    options.binary = binary;
    write_soup(s, path, options);
    EXPECT_NE(test::read_file(path).find("property double patch_id\n"), std::string::npos);
    const TriangleSoup back = read_soup(path);
    EXPECT_EQ(back.points, s.points);
    EXPECT_EQ(back.triangles, s.triangles);
  }
}

TEST(Write, RejectsBadInput) {
  const TriangleSoup s = test::cube();
  const auto dir = test::temp_dir("io_write_bad");
  WriteOptions options;
  options.face_fields = {{"quality", {1.0, 2.0}}};  // wrong size
  EXPECT_THROW(write_soup(s, dir / "a.vtk", options), InvalidInput);
  options.face_fields = {{"bad name", std::vector<double>(s.triangles.size(), 0.0)}};
  EXPECT_THROW(options.validate(), InvalidInput);
  options.face_fields = {{"q", std::vector<double>(s.triangles.size())}, {"q", std::vector<double>(s.triangles.size())}};
  EXPECT_THROW(options.validate(), InvalidInput);
  TriangleSoup broken = s;
  broken.triangles.push_back({0, 1, 8});
  EXPECT_THROW(write_soup(broken, dir / "b.obj"), InvalidInput);
  EXPECT_THROW(write_soup(s, dir / "c.xyz"), IoError);
  EXPECT_FALSE(std::filesystem::exists(dir / "c.xyz"));
  EXPECT_THROW(write_soup(s, dir / "no_such_dir" / "d.obj"), IoError);
}

}  // namespace
}  // namespace nurbsfront
