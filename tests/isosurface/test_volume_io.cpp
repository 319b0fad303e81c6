// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <zlib.h>

#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <set>

#include "isosurface/surface_checks.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/volume_io.h"
#include "support/test_data.h"

namespace nurbsfront {
namespace {

void write_file(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string big_endian_u16(const std::vector<std::uint16_t>& v) {
  std::string s;
  for (auto x : v) {
    s.push_back(static_cast<char>(x >> 8));
    s.push_back(static_cast<char>(x & 0xff));
  }
  return s;
}

std::string little_endian_i16(const std::vector<std::int16_t>& v) {
  std::string s;
  for (auto x : v) {
    const auto u = static_cast<std::uint16_t>(x);
    s.push_back(static_cast<char>(u & 0xff));
    s.push_back(static_cast<char>(u >> 8));
  }
  return s;
}

std::string big_endian_f32(const std::vector<float>& v) {
  std::string s;
  for (float x : v) {
    std::uint32_t u;
    std::memcpy(&u, &x, 4);
    for (int b = 3; b >= 0; --b) s.push_back(static_cast<char>((u >> (8 * b)) & 0xff));
  }
  return s;
}

std::string inr_header(const std::string& fields) {
  std::string h = "#INRIMAGE-4#{\n" + fields;
  while ((h.size() + 4) % 256 != 0) h.push_back('\n');
  return h + "##}\n";
}

// ---------------------------------------------------------------- the real volumes

TEST(VolumeIo, HeadsqMetaImage) {
  const ScalarGrid g = read_volume(test::test_data("volumes/headsq.mha"));
  EXPECT_EQ(g.dims, (std::array<int, 3>{64, 64, 93}));
  EXPECT_NEAR(g.spacing.x(), 3.2, 1e-6);
  EXPECT_NEAR(g.spacing.y(), 3.2, 1e-6);
  EXPECT_DOUBLE_EQ(g.spacing.z(), 1.5);
  EXPECT_TRUE(g.origin.isApprox(Eigen::Vector3d(0, 0, 1.5)));
  const auto range = g.value_range();
  EXPECT_EQ(range[0], 0.0f);
  EXPECT_EQ(range[1], 3926.0f);
}

TEST(VolumeIo, IronProtLegacyVtk) {
  const ScalarGrid g = read_volume(test::test_data("volumes/ironProt.vtk"));
  EXPECT_EQ(g.dims, (std::array<int, 3>{68, 68, 68}));
  EXPECT_TRUE(g.spacing.isApprox(Eigen::Vector3d::Ones()));
  EXPECT_TRUE(g.origin.isZero());
  const auto range = g.value_range();
  EXPECT_EQ(range[0], 0.0f);
  EXPECT_EQ(range[1], 255.0f);
}

TEST(VolumeIo, LiverGzippedInr) {
  const ScalarGrid g = read_volume(test::test_data("volumes/liver.inr.gz"));
  EXPECT_EQ(g.dims, (std::array<int, 3>{438, 353, 165}));
  EXPECT_NEAR(g.spacing.x(), 0.617188, 1e-6);
  EXPECT_NEAR(g.spacing.z(), 1.33333, 1e-6);
  std::array<bool, 256> seen{};
  std::size_t n_other = 0;
  for (const float v : g.values) {
    if (v >= 0.0f && v <= 255.0f && v == std::floor(v)) {
      seen[static_cast<std::size_t>(v)] = true;
    } else {
      ++n_other;
    }
  }
  EXPECT_EQ(n_other, 0u);
  std::set<int> labels;
  for (int i = 0; i < 256; ++i) {
    if (seen[i]) labels.insert(i);
  }
  EXPECT_EQ(labels, (std::set<int>{0, 84, 85, 127, 255}));
}

// ---------------------------------------------------------------- marching cubes on them

void check_volume(const std::filesystem::path& path, double iso) {
  SCOPED_TRACE(path.filename().string() + " at " + std::to_string(iso));
  const ScalarGrid g = read_volume(path);
  MarchingCubesOptions o;
  o.iso = iso;
  o.inside_above = true;
  const TriangleSoup open = marching_cubes(g, o);
  EXPECT_FALSE(open.triangles.empty());
  test::expect_clean_surface(open, false, "unpadded");
  o.pad = true;
  const TriangleSoup closed = marching_cubes(g, o);
  test::expect_clean_surface(closed, true, "padded");
  EXPECT_GE(closed.triangles.size(), open.triangles.size());
}

TEST(VolumeMarchingCubes, HeadsqSkinAndBone) {
  check_volume(test::test_data("volumes/headsq.mha"), 500);
  check_volume(test::test_data("volumes/headsq.mha"), 1150);
}

TEST(VolumeMarchingCubes, IronProt) { check_volume(test::test_data("volumes/ironProt.vtk"), 128); }

TEST(VolumeMarchingCubesSlow, LiverLabel) { check_volume(test::test_data("volumes/liver.inr.gz"), 127.5); }

// ---------------------------------------------------------------- small written files

TEST(VolumeIo, MetaImageVariants) {
  const auto dir = test::temp_dir("volume_io_mha");
  const std::vector<std::int16_t> v = {-3, 0, 7, 1000, -1000, 12, 5, 6};
  // Uncompressed, little-endian, LOCAL.
  write_file(dir / "a.mha",
             "ObjectType = Image\nNDims = 3\nDimSize = 2 2 2\nElementSpacing = 0.5 1 2\nOffset = 1 2 3\n"
             "ElementType = MET_SHORT\nBinaryDataByteOrderMSB = False\nElementDataFile = LOCAL\n" +
                 little_endian_i16(v));
  const ScalarGrid a = read_volume(dir / "a.mha");
  EXPECT_EQ(a.values, std::vector<float>(v.begin(), v.end()));
  EXPECT_TRUE(a.spacing.isApprox(Eigen::Vector3d(0.5, 1, 2)));
  EXPECT_TRUE(a.origin.isApprox(Eigen::Vector3d(1, 2, 3)));
  EXPECT_EQ(a.value(1, 1, 0), 1000.0f);  // x fastest
  // Header + separate raw data (.mhd), big-endian unsigned short.
  write_file(dir / "b.raw", big_endian_u16({1, 2, 3, 65535}));
  write_file(dir / "b.mhd",
             "NDims = 3\nDimSize = 4 1 1\nElementType = MET_USHORT\nElementByteOrderMSB = True\n"
             "ElementDataFile = b.raw\n");
  EXPECT_EQ(read_volume(dir / "b.mhd").values, (std::vector<float>{1, 2, 3, 65535}));
  // zlib-compressed floats.
  const std::vector<float> f = {0.5f, -1.25f, 3.0f, 8.0f};
  std::string raw(reinterpret_cast<const char*>(f.data()), f.size() * sizeof(float));
  uLongf len = compressBound(raw.size());
  std::string packed(len, '\0');
  ASSERT_EQ(compress(reinterpret_cast<Bytef*>(packed.data()), &len, reinterpret_cast<const Bytef*>(raw.data()), raw.size()), Z_OK);
  packed.resize(len);
  write_file(dir / "c.mha",
             "NDims = 3\nDimSize = 2 2 1\nElementType = MET_FLOAT\nCompressedData = True\nCompressedDataSize = " +
                 std::to_string(len) + "\nElementDataFile = LOCAL\n" + packed);
  EXPECT_EQ(read_volume(dir / "c.mha").values, f);
  // The same stream with a header claiming more samples, and a corrupt stream.
  write_file(dir / "d.mha", "NDims = 3\nDimSize = 2 2 2\nElementType = MET_FLOAT\nCompressedData = True\n"
                            "ElementDataFile = LOCAL\n" + packed);
  EXPECT_THROW((void)read_volume(dir / "d.mha"), IoError);
  std::string broken = packed;
  broken[broken.size() / 2] ^= 0x5a;
  broken[2] ^= 0x33;
  write_file(dir / "e.mha", "NDims = 3\nDimSize = 2 2 1\nElementType = MET_FLOAT\nCompressedData = True\n"
                            "ElementDataFile = LOCAL\n" + broken);
  EXPECT_THROW((void)read_volume(dir / "e.mha"), IoError);
  // ASCII data.
  write_file(dir / "f.mha", "NDims = 3\nDimSize = 3 1 1\nElementType = MET_UCHAR\nBinaryData = False\n"
                            "ElementDataFile = LOCAL\n4 5 6\n");
  EXPECT_EQ(read_volume(dir / "f.mha").values, (std::vector<float>{4, 5, 6}));
}

TEST(VolumeIo, LegacyVtkAsciiAndBinary) {
  const auto dir = test::temp_dir("volume_io_vtk");
  write_file(dir / "a.vtk",
             "# vtk DataFile Version 3.0\nsmall\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 1 2\n"
             "SPACING 1 2 3\nORIGIN -1 0 1\nPOINT_DATA 4\nSCALARS s float 1\nLOOKUP_TABLE default\n1.5 -2\n3e2 4\n");
  const ScalarGrid a = read_volume(dir / "a.vtk");
  EXPECT_EQ(a.values, (std::vector<float>{1.5f, -2.0f, 300.0f, 4.0f}));
  EXPECT_TRUE(a.spacing.isApprox(Eigen::Vector3d(1, 2, 3)));
  EXPECT_TRUE(a.origin.isApprox(Eigen::Vector3d(-1, 0, 1)));
  const std::vector<float> f = {1.0f, -0.5f, 2.25f, 1e6f};
  write_file(dir / "b.vtk",
             "# vtk DataFile Version 3.0\nsmall\nBINARY\nDATASET STRUCTURED_POINTS\nDIMENSIONS 4 1 1\n"
             "ASPECT_RATIO 1 1 1\nORIGIN 0 0 0\nPOINT_DATA 4\nSCALARS s float\nLOOKUP_TABLE default\n" +
                 big_endian_f32(f));
  EXPECT_EQ(read_volume(dir / "b.vtk").values, f);
}

TEST(VolumeIo, InrPlainAndGzipped) {
  const auto dir = test::temp_dir("volume_io_inr");
  const std::string header = inr_header("XDIM=2\nYDIM=2\nZDIM=1\nVDIM=1\nTYPE=unsigned fixed\nPIXSIZE=16 bits\n"
                                        "SCALE=2**0\nCPU=sun\nVX=0.5\nVY=0.25\nVZ=2\n");
  ASSERT_EQ(header.size(), 256u);
  const std::string file = header + big_endian_u16({10, 20, 30, 40});
  write_file(dir / "a.inr", file);
  const ScalarGrid a = read_volume(dir / "a.inr");
  EXPECT_EQ(a.values, (std::vector<float>{10, 20, 30, 40}));
  EXPECT_TRUE(a.spacing.isApprox(Eigen::Vector3d(0.5, 0.25, 2)));
  gzFile gz = gzopen((dir / "b.inr.gz").c_str(), "wb");
  ASSERT_NE(gz, nullptr);
  ASSERT_EQ(gzwrite(gz, file.data(), static_cast<unsigned>(file.size())), static_cast<int>(file.size()));
  gzclose(gz);
  EXPECT_EQ(read_volume(dir / "b.inr.gz").values, a.values);
}

TEST(VolumeIo, BadFilesAreIoErrors) {
  const auto dir = test::temp_dir("volume_io_bad");
  EXPECT_THROW((void)read_volume(dir / "missing.mha"), IoError);
  write_file(dir / "empty.mha", "");
  EXPECT_THROW((void)read_volume(dir / "empty.mha"), IoError);
  write_file(dir / "volume.xyz", "1 2 3");
  EXPECT_THROW((void)read_volume(dir / "volume.xyz"), IoError);
  // Header sizes larger than the data (truncated), and larger than any plausible data.
  write_file(dir / "short.mha", "NDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\nElementDataFile = LOCAL\nabc");
  EXPECT_THROW((void)read_volume(dir / "short.mha"), IoError);
  write_file(dir / "huge.mha",
             "NDims = 3\nDimSize = 100000 100000 100000\nElementType = MET_UCHAR\nElementDataFile = LOCAL\nabc");
  EXPECT_THROW((void)read_volume(dir / "huge.mha"), IoError);
  write_file(dir / "long.mha", "NDims = 3\nDimSize = 1 1 1\nElementType = MET_UCHAR\nElementDataFile = LOCAL\nabc");
  EXPECT_THROW((void)read_volume(dir / "long.mha"), IoError);
  write_file(dir / "notype.mha", "NDims = 3\nDimSize = 1 1 3\nElementDataFile = LOCAL\nabc");
  EXPECT_THROW((void)read_volume(dir / "notype.mha"), IoError);
  write_file(dir / "badtype.mha", "NDims = 3\nDimSize = 1 1 3\nElementType = MET_FOO\nElementDataFile = LOCAL\nabc");
  EXPECT_THROW((void)read_volume(dir / "badtype.mha"), IoError);
  write_file(dir / "nodata.mhd", "NDims = 3\nDimSize = 1 1 3\nElementType = MET_UCHAR\nElementDataFile = gone.raw\n");
  EXPECT_THROW((void)read_volume(dir / "nodata.mhd"), IoError);
  // VTK: POINT_DATA disagreeing with DIMENSIONS; truncated binary; wrong dataset.
  const std::string vtk_head = "# vtk DataFile Version 3.0\nx\nBINARY\nDATASET STRUCTURED_POINTS\nDIMENSIONS 4 4 4\n";
  write_file(dir / "mismatch.vtk", vtk_head + "POINT_DATA 10\nSCALARS s unsigned_char\nLOOKUP_TABLE default\n0123456789");
  EXPECT_THROW((void)read_volume(dir / "mismatch.vtk"), IoError);
  write_file(dir / "short.vtk", vtk_head + "POINT_DATA 64\nSCALARS s unsigned_char\nLOOKUP_TABLE default\n0123456789");
  EXPECT_THROW((void)read_volume(dir / "short.vtk"), IoError);
  write_file(dir / "poly.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 0 float\n");
  EXPECT_THROW((void)read_volume(dir / "poly.vtk"), IoError);
  write_file(dir / "short_ascii.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 1 1\n"
                                      "POINT_DATA 2\nSCALARS s float\nLOOKUP_TABLE default\n1.0\n");
  EXPECT_THROW((void)read_volume(dir / "short_ascii.vtk"), IoError);
  // INR: not an INR header; truncated data; header without its end tag.
  write_file(dir / "bad.inr", std::string(256, 'x') + "data");
  EXPECT_THROW((void)read_volume(dir / "bad.inr"), IoError);
  write_file(dir / "short.inr",
             inr_header("XDIM=8\nYDIM=8\nZDIM=8\nTYPE=unsigned fixed\nPIXSIZE=8 bits\nCPU=decm\n") + "tiny");
  EXPECT_THROW((void)read_volume(dir / "short.inr"), IoError);
  write_file(dir / "noend.inr", "#INRIMAGE-4#{\nXDIM=1\n");
  EXPECT_THROW((void)read_volume(dir / "noend.inr"), IoError);
  // Not gzip at all behind a .inr.gz name is read as plain bytes by zlib; a broken gzip is an error.
  write_file(dir / "broken.inr.gz", std::string("\x1f\x8b\x08\x00garbage-garbage", 19));
  EXPECT_THROW((void)read_volume(dir / "broken.inr.gz"), IoError);
}

}  // namespace
}  // namespace nurbsfront
