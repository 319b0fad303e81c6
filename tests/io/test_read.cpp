// SPDX-License-Identifier: BSD-3-Clause
// Readers: every format parsed correctly on small hand-written files, the VTK brain
// surface welded to a closed genus-0 manifold, and every kind of bad input rejected
// with an IoError (never a crash, a hang or a huge allocation).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "io/io_test_util.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/io/mesh_io.h"
#include "support/test_data.h"

namespace nurbsfront {
namespace {

using Tri = std::array<std::uint32_t, 3>;

int euler(const TriMesh& m) {
  return static_cast<int>(m.n_vertices()) - static_cast<int>(m.n_edges()) + static_cast<int>(m.n_faces());
}

std::size_t n_boundary_edges(const TriMesh& m) {
  std::size_t n = 0;
  for (auto e : m.edges()) n += m.is_boundary(e) ? 1 : 0;
  return n;
}

TEST(MeshFormat, ByExtensionCaseInsensitive) {
  EXPECT_EQ(mesh_format_from_path("a/b.obj"), MeshFormat::Obj);
  EXPECT_EQ(mesh_format_from_path("x.PLY"), MeshFormat::Ply);
  EXPECT_EQ(mesh_format_from_path("x.Stl"), MeshFormat::Stl);
  EXPECT_EQ(mesh_format_from_path("x.off"), MeshFormat::Off);
  EXPECT_EQ(mesh_format_from_path("x.vtk"), MeshFormat::Vtk);
  EXPECT_EQ(mesh_format_from_path("x.vtu"), MeshFormat::Vtu);
  EXPECT_THROW((void)mesh_format_from_path("x.xyz"), IoError);
  EXPECT_THROW((void)mesh_format_from_path("noextension"), IoError);
}

TEST(ReadObj, PolygonsAreFanTriangulatedAndIndexFormsAccepted) {
  const auto dir = test::temp_dir("io_obj");
  const auto path = test::write_file(dir / "quad.obj",
                                     "# a quad and a triangle\n"
                                     "o thing\n"
                                     "v 0 0 0\nv 1 0 0 0.5 0.5 0.5\nv 1 1 0\nv 0 1 0 1.0\n"
                                     "vn 0 0 1\nvt 0 0\n"
                                     "v +0.5 0.5 1e0\n"
                                     "f 1/1/1 2/1/1 3//1 4\n"
                                     "f -1 1 2   # relative index\n");
  const TriangleSoup s = read_soup(path);
  ASSERT_EQ(s.points.size(), 5u);
  EXPECT_EQ(s.points[4], Eigen::Vector3d(0.5, 0.5, 1.0));
  ASSERT_EQ(s.triangles.size(), 3u);
  EXPECT_EQ(s.triangles[0], (Tri{0, 1, 2}));
  EXPECT_EQ(s.triangles[1], (Tri{0, 2, 3}));
  EXPECT_EQ(s.triangles[2], (Tri{4, 0, 1}));
}

TEST(ReadOff, CommentsColoursAndPentagon) {
  const auto dir = test::temp_dir("io_off");
  const auto path = test::write_file(dir / "p.off",
                                     "OFF\n# comment\n5 1 0\n0 0 0\n1 0 0\n2 1 0 255 0 0\n1 2 0\n0 1 0\n"
                                     "5 0 1 2 3 4 0.5 0.5 0.5\n");
  const TriangleSoup s = read_soup(path);
  ASSERT_EQ(s.points.size(), 5u);
  EXPECT_EQ(s.points[2], Eigen::Vector3d(2, 1, 0));
  ASSERT_EQ(s.triangles.size(), 3u);
  EXPECT_EQ(s.triangles[2], (Tri{0, 3, 4}));
}

TEST(ReadPly, BigEndianWithExtraPropertiesAndElements) {
  std::string ply =
      "ply\nformat binary_big_endian 1.0\ncomment test\n"
      "element vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\n"
      "element face 1\nproperty uchar flags\nproperty list uchar uint vertex_indices\nproperty float q\n"
      "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n";
  const float xyz[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 2, 0}, {0, 2, 0.5f}};
  for (const auto& p : xyz) {
    for (float c : p) test::pack(ply, c, true);
    test::pack(ply, std::uint8_t{200}, true);
  }
  test::pack(ply, std::uint8_t{7}, true);
  test::pack(ply, std::uint8_t{4}, true);
  for (std::uint32_t i : {3u, 2u, 1u, 0u}) test::pack(ply, i, true);
  test::pack(ply, 0.25f, true);
  test::pack(ply, std::int32_t{0}, true);
  test::pack(ply, std::int32_t{1}, true);
  const auto path = test::write_file(test::temp_dir("io_ply_be") / "q.ply", ply);
  const TriangleSoup s = read_soup(path);
  ASSERT_EQ(s.points.size(), 4u);
  EXPECT_EQ(s.points[3], Eigen::Vector3d(0, 2, 0.5));
  ASSERT_EQ(s.triangles.size(), 2u);
  EXPECT_EQ(s.triangles[0], (Tri{3, 2, 1}));
  EXPECT_EQ(s.triangles[1], (Tri{3, 1, 0}));
}

TEST(ReadPly, AsciiWithVertexIndexName) {
  const auto path = test::write_file(test::temp_dir("io_ply_a") / "t.ply",
                                     "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\n"
                                     "property double y\nproperty double z\nelement face 1\n"
                                     "property list uchar int vertex_index\nend_header\n"
                                     "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  const TriangleSoup s = read_soup(path);
  ASSERT_EQ(s.triangles.size(), 1u);
  EXPECT_EQ(s.triangles[0], (Tri{0, 1, 2}));
}

// The little-endian layouts the reader takes item by item without the general property loop
// (scalar-only vertices; faces of just the index list with 4-byte indices): same values as
// the general loop, quads and bad items falling back to it, same errors.
TEST(ReadPly, LittleEndianTrianglesQuadsAndBadFaces) {
  auto file = [](const std::vector<std::vector<std::int32_t>>& faces, std::size_t cut = 0) {
    std::string ply = "ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\nproperty uchar flag\n"
                      "property float y\nproperty double z\nelement face " +
                      std::to_string(faces.size()) + "\nproperty list uchar int vertex_indices\nend_header\n";
    for (int i = 0; i < 5; ++i) {
      test::pack(ply, static_cast<float>(i), false);
      test::pack(ply, std::uint8_t{9}, false);
      test::pack(ply, static_cast<float>(2 * i), false);
      test::pack(ply, 0.5 * i, false);
    }
    for (const auto& f : faces) {
      test::pack(ply, static_cast<std::uint8_t>(f.size()), false);
      for (const std::int32_t i : f) test::pack(ply, i, false);
    }
    ply.resize(ply.size() - cut);
    return ply;
  };
  const auto dir = test::temp_dir("io_ply_le");
  const TriangleSoup s = read_soup(test::write_file(dir / "a.ply", file({{0, 1, 2}, {0, 2, 3, 4}, {4, 3, 2}})));
  ASSERT_EQ(s.points.size(), 5u);
  EXPECT_EQ(s.points[3], Eigen::Vector3d(3, 6, 1.5));
  ASSERT_EQ(s.triangles.size(), 4u);
  EXPECT_EQ(s.triangles[0], (Tri{0, 1, 2}));
  EXPECT_EQ(s.triangles[1], (Tri{0, 2, 3}));
  EXPECT_EQ(s.triangles[2], (Tri{0, 3, 4}));
  EXPECT_EQ(s.triangles[3], (Tri{4, 3, 2}));
  auto message = [&](const std::string& name, const std::string& content) {
    try {
      (void)read_soup(test::write_file(dir / name, content));
    } catch (const IoError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("neg.ply", file({{0, 1, 2}, {0, -1, 2}})).find("vertex index -1 out of range"), std::string::npos);
  EXPECT_NE(message("cut.ply", file({{0, 1, 2}, {2, 3, 4}}, 2)).find(".ply"), std::string::npos);
  EXPECT_NE(message("two.ply", file({{0, 1, 2}, {3, 4}})).find("polygon with 2 vertices"), std::string::npos);
}

TEST(ReadStl, AsciiWithTwoSolidsAndBinaryWithSolidHeader) {
  const auto dir = test::temp_dir("io_stl");
  const std::string facet =
      " facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1 0\n  endloop\n endfacet\n";
  const TriangleSoup a = read_soup(test::write_file(dir / "a.stl", "solid one\n" + facet + "endsolid one\nsolid two\n" +
                                                                       facet + "endsolid two\n"));
  EXPECT_EQ(a.points.size(), 6u);
  EXPECT_EQ(a.triangles.size(), 2u);
  EXPECT_EQ(a.triangles[1], (Tri{3, 4, 5}));
  // Binary whose 80-byte header starts with "solid": detected by its exact size.
  std::string bin = "solid but really binary";
  bin.resize(80, ' ');
  test::pack(bin, std::uint32_t{1}, false);
  for (float v : {0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 2.f, 0.f, 0.f, 0.f, 3.f, 0.f}) test::pack(bin, v, false);
  test::pack(bin, std::uint16_t{0}, false);
  const TriangleSoup b = read_soup(test::write_file(dir / "b.stl", bin));
  ASSERT_EQ(b.points.size(), 3u);
  EXPECT_EQ(b.points[2], Eigen::Vector3d(0, 3, 0));
}

TEST(ReadVtk, BinaryTriangleStripsAlternateOrientation) {
  std::string vtk = "# vtk DataFile Version 3.0\nstrip\nBINARY\nDATASET POLYDATA\nPOINTS 4 float\n";
  for (float v : {0.f, 0.f, 0.f, 0.f, 1.f, 0.f, 1.f, 0.f, 0.f, 1.f, 1.f, 0.f}) test::pack(vtk, v, true);
  vtk += "\nTRIANGLE_STRIPS 1 5\n";
  for (std::int32_t v : {4, 0, 1, 2, 3}) test::pack(vtk, v, true);
  vtk += "\nPOINT_DATA 4\nSCALARS s float 1\nLOOKUP_TABLE default\n";
  for (int i = 0; i < 4; ++i) test::pack(vtk, 1.0f, true);
  const TriangleSoup s = read_soup(test::write_file(test::temp_dir("io_vtk_strip") / "s.vtk", vtk));
  ASSERT_EQ(s.points.size(), 4u);
  EXPECT_EQ(s.points[3], Eigen::Vector3d(1, 1, 0));
  ASSERT_EQ(s.triangles.size(), 2u);
  EXPECT_EQ(s.triangles[0], (Tri{0, 1, 2}));
  EXPECT_EQ(s.triangles[1], (Tri{2, 1, 3}));  // both triangles oriented alike
  EXPECT_TRUE(check_manifold(s).ok());
}

TEST(ReadVtk, NewOffsetsConnectivityLayout) {
  const TriangleSoup s = read_soup(test::write_file(
      test::temp_dir("io_vtk51") / "n.vtk",
      "# vtk DataFile Version 5.1\nnew\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n0 0 0 1 0 0 1 1 0 0 1 0\n"
      "POLYGONS 3 7\nOFFSETS vtktypeint64\n0 3 7\nCONNECTIVITY vtktypeint64\n0 1 2 0 1 2 3\n"));
  ASSERT_EQ(s.triangles.size(), 3u);
  EXPECT_EQ(s.triangles[2], (Tri{0, 2, 3}));
}

TEST(ReadVtk, BrainStripsWeldToClosedGenusZeroManifold) {
  const auto path = test::test_data("io/brainImageSmooth.vtk");
  const TriangleSoup raw = read_soup(path);
  EXPECT_EQ(raw.points.size(), 5153u);
  EXPECT_EQ(raw.triangles.size(), 9522u);
  EXPECT_GT(n_boundary_edges(to_trimesh(raw)), 0u);  // duplicated seam points leave it open
  const CleanResult cleaned = clean(raw);
  EXPECT_EQ(cleaned.report.n_welded_vertices, 390u);
  EXPECT_EQ(cleaned.soup.points.size(), 4763u);
  const ManifoldCheck check = check_manifold(cleaned.soup);
  ASSERT_TRUE(check.ok()) << check.message();
  const TriMesh mesh = read_mesh(path);
  EXPECT_EQ(mesh.n_vertices(), 4763u);
  EXPECT_EQ(mesh.n_faces(), cleaned.soup.triangles.size());
  EXPECT_EQ(n_boundary_edges(mesh), 0u);
  EXPECT_EQ(euler(mesh), 2);
}

TEST(ReadVtk, FranCutPolygonsFromSharedData) {
  const auto path = test::shared_data("meshes/vtk_fran_cut/fran_cut.vtk");
  if (!path) GTEST_SKIP() << "../shared/data not available";
  const TriangleSoup raw = read_soup(*path);
  EXPECT_EQ(raw.points.size(), 2205u);
  EXPECT_EQ(raw.triangles.size(), 4224u);
  const TriMesh mesh = read_mesh(*path);
  EXPECT_EQ(n_boundary_edges(mesh), 184u);
}

// ---------------------------------------------------------------------------------
// Bad input

class BadInput : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test::temp_dir("io_bad"); }
  std::filesystem::path file(const std::string& name, std::string_view content) {
    return test::write_file(dir_ / name, content);
  }
  //! Expects read_soup to throw an IoError whose message names the file and contains what.
  void expect_io_error(const std::filesystem::path& path, const std::string& what) {
    try {
      (void)read_soup(path);
      ADD_FAILURE() << "no IoError for " << path;
    } catch (const IoError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(path.filename().string()), std::string::npos) << message;
      EXPECT_NE(message.find(what), std::string::npos) << "expected '" << what << "' in: " << message;
    }
  }
  std::filesystem::path dir_;
};

const std::string kPlyHeader3 =
    "element vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n";

std::string binary_ply_triangle() {
  std::string ply = "ply\nformat binary_little_endian 1.0\n" + kPlyHeader3;
  for (double v : {0., 0., 0., 1., 0., 0., 0., 1., 0.}) test::pack(ply, v, false);
  test::pack(ply, std::uint8_t{3}, false);
  for (std::int32_t i : {0, 1, 2}) test::pack(ply, i, false);
  return ply;
}

TEST_F(BadInput, MissingAndEmptyFiles) {
  expect_io_error(dir_ / "missing.obj", "no such file");
  expect_io_error(file("empty.ply", ""), "empty");
  expect_io_error(file("empty.stl", ""), "empty");
}

TEST_F(BadInput, UnsupportedExtension) {
  expect_io_error(file("mesh.xyz", "0 0 0\n"), "unsupported");
  expect_io_error(file("mesh.vtu", "<VTKFile/>"), "not supported");
}

TEST_F(BadInput, TruncatedBinaryPlyAndStl) {
  const std::string ply = binary_ply_triangle();
  EXPECT_NO_THROW((void)read_soup(file("ok.ply", ply)));
  for (std::size_t cut : {ply.size() - 1, ply.size() - 13, ply.size() - 40}) {
    expect_io_error(file("cut.ply", ply.substr(0, cut)), "truncated");
  }
  std::string stl(80, ' ');
  test::pack(stl, std::uint32_t{2}, false);
  stl += std::string(50 + 20, '\0');  // one and a bit triangles of two
  expect_io_error(file("cut.stl", stl), "truncated");
  expect_io_error(file("short.stl", std::string(40, '\0')), "truncated");
}

TEST_F(BadInput, NonFiniteCoordinates) {
  expect_io_error(file("nan.obj", "v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), "non-finite");
  expect_io_error(file("inf.off", "OFF\n3 1 0\n0 0 0\ninf 0 0\n0 1 0\n3 0 1 2\n"), "non-finite");
  expect_io_error(file("big.obj", "v 0 0 1e999\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), "range");
  std::string ply = binary_ply_triangle();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::string bad;
  test::pack(bad, nan, false);
  ply.replace(ply.find("end_header\n") + 11 + 8, 8, bad);  // y of point 0
  expect_io_error(file("nan.ply", ply), "non-finite");
  std::string stl(80, ' ');
  test::pack(stl, std::uint32_t{1}, false);
  for (float v : {0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 2.f, 0.f, 0.f, 0.f, std::numeric_limits<float>::infinity(), 0.f}) {
    test::pack(stl, v, false);
  }
  test::pack(stl, std::uint16_t{0}, false);
  expect_io_error(file("inf.stl", stl), "non-finite");
}

TEST_F(BadInput, OutOfRangeIndices) {
  expect_io_error(file("idx.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"), "references vertex 3");
  expect_io_error(file("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"), "index 0");
  expect_io_error(file("neg.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -5 1 2\n"), "out of range");
  expect_io_error(file("idx.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"), "references vertex 3");
  expect_io_error(file("neg.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n"), "out of range");
  expect_io_error(file("idx.ply", "ply\nformat ascii 1.0\n" + kPlyHeader3 + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"),
                  "references vertex 7");
  expect_io_error(file("idx.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n"
                                  "0 0 0 1 0 0 0 1 0\nPOLYGONS 1 4\n3 0 1 9\n"),
                  "references vertex 9");
}

TEST_F(BadInput, GarbageContent) {
  std::mt19937 rng(42);
  std::string junk(4096, '\0');
  for (char& c : junk) c = static_cast<char>(rng() & 0xff);
  for (const char* name : {"g.obj", "g.off", "g.ply", "g.vtk", "g.stl"}) {
    EXPECT_THROW((void)read_soup(file(name, junk)), IoError) << name;
  }
  expect_io_error(file("words.obj", "hello world\n"), "unknown OBJ record");
  expect_io_error(file("letters.obj", "v 0 0 zero\n"), "expected a number");
  expect_io_error(file("words.off", "OFF\n3 1 0\n0 0 0\n1 zero 0\n"), "expected a number");
  expect_io_error(file("words.ply", "ply\nformat ascii 1.0\n" + kPlyHeader3 + "0 0 0\n1 0 0\n0 1 x\n3 0 1 2\n"),
                  "expected a number");
  expect_io_error(file("nomagic.ply", "plx\n"), "not a PLY");
  expect_io_error(file("nomagic.vtk", "hello\n"), "not a legacy VTK");
  expect_io_error(file("grid.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET STRUCTURED_POINTS\n"), "POLYDATA");
  expect_io_error(file("tail.ply", "ply\nformat ascii 1.0\n" + kPlyHeader3 + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n9 9\n"),
                  "after the last element");
  expect_io_error(file("nothing.obj", "# only a comment\n"), "no vertices");
}

TEST_F(BadInput, TruncatedAscii) {
  expect_io_error(file("cut.obj", "v 0 0 0\nv 1 0"), "expected a number");
  expect_io_error(file("cut.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n"), "truncated");
  expect_io_error(file("cut.ply", "ply\nformat ascii 1.0\n" + kPlyHeader3 + "0 0 0\n1 0 0\n"), "truncated");
  expect_io_error(file("cut2.ply", "ply\nformat ascii 1.0\nelement vertex 3\n"), "end_header");
  expect_io_error(file("cut.stl", "solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n"), "expected 'vertex'");
  expect_io_error(file("noend.stl", "solid x\n"), "endsolid");
  expect_io_error(file("cut.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1"),
                  "truncated");
}

TEST_F(BadInput, HugeHeaderCountsAreNotTrusted) {
  // Each would ask for ~10^12 elements; the readers must fail on the file size instead.
  const std::string big = "1000000000000";
  expect_io_error(file("huge.ply", "ply\nformat binary_little_endian 1.0\nelement vertex " + big +
                                       "\nproperty float x\nproperty float y\nproperty float z\nend_header\n" +
                                       std::string(24, '\0')),
                  "truncated");
  expect_io_error(file("huge_list.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 0\n"
                                        "property float x\nproperty float y\nproperty float z\n"
                                        "element face 1\nproperty list uint int vertex_indices\nend_header\n" +
                                            std::string("\xff\xff\xff\x7f", 4)),
                  "truncated");
  expect_io_error(file("huge_ascii.ply", "ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\n"
                                         "property float y\nproperty float z\nend_header\n0 0 0\n"),
                  "truncated");
  expect_io_error(file("huge.off", "OFF\n4000000000 4000000000 0\n0 0 0\n"), "truncated");
  expect_io_error(file("huge.vtk", "# vtk DataFile Version 3.0\nx\nBINARY\nDATASET POLYDATA\nPOINTS " + big +
                                       " float\n" + std::string(24, '\0')),
                  "points");
  expect_io_error(file("hugecells.vtk", "# vtk DataFile Version 3.0\nx\nBINARY\nDATASET POLYDATA\nPOINTS 0 float\n\n"
                                        "POLYGONS " + big + " " + big + "\n" + std::string(24, '\0')),
                  "truncated");
  expect_io_error(file("noprops.ply", "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\n"
                                     "property float y\nproperty float z\nelement junk " + big + "\nend_header\n"),
                  "no properties");
  std::string stl(80, ' ');
  test::pack(stl, std::uint32_t{0xffffffffu}, false);
  stl += std::string(100, '\0');
  expect_io_error(file("huge.stl", stl), "truncated");
}

}  // namespace
}  // namespace nurbsfront

namespace nurbsfront {
namespace {

// Every prefix and many random byte corruptions of a valid file of each format either
// read or throw IoError: no other exception, no crash (run under ASan in CI).
//! Tries n_prefixes prefixes (evenly spread; all if the file is shorter) and
//! n_corruptions random 3-byte corruptions of each format's file.
void prefixes_and_corruptions(const std::string& dir_name, std::size_t n_prefixes, int n_corruptions) {
  const auto dir = test::temp_dir(dir_name);
  TriangleSoup s;
  s.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  s.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  std::mt19937 rng(3);
  for (const char* name : {"t.obj", "t.off", "t.ply", "t.stl", "t.vtk"}) {
    for (const bool binary : {false, true}) {
      WriteOptions options;
      options.binary = binary;
      options.face_fields = {{"q", {1, 2, 3, 4}}};
      const auto source = dir / (std::string(binary ? "b" : "a") + name);
      write_soup(s, source, options);
      const std::string bytes = test::read_file(source);
      std::size_t n_attempts = 0;
      auto attempt = [&](const std::string& content) {
        // a fresh name each time: rewriting one file in place makes ext4 flush it to disk
        const auto target = dir / (std::to_string(n_attempts++) + name);
        test::write_file(target, content);
        try {
          (void)read_soup(target);
        } catch (const IoError&) {
        } catch (const std::exception& e) {
          ADD_FAILURE() << name << ": unexpected exception " << e.what();
        }
      };
      const std::size_t step = std::max<std::size_t>(1, bytes.size() / n_prefixes);
      for (std::size_t cut = 0; cut < bytes.size(); cut += step) attempt(bytes.substr(0, cut));
      for (int trial = 0; trial < n_corruptions; ++trial) {
        std::string corrupted = bytes;
        for (int k = 0; k < 3; ++k) corrupted[rng() % corrupted.size()] = static_cast<char>(rng() & 0xff);
        attempt(corrupted);
      }
    }
  }
}

TEST(ReadRobustness, PrefixesAndCorruptionsGiveIoErrorOrASoup) { prefixes_and_corruptions("io_fuzz", 25, 25); }

TEST(ReadRobustnessSlow, EveryPrefixAndManyCorruptions) {
  prefixes_and_corruptions("io_fuzz_slow", std::numeric_limits<std::size_t>::max(), 500);
}

}  // namespace
}  // namespace nurbsfront
