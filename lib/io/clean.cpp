// SPDX-License-Identifier: BSD-3-Clause
// clean(): weld by a grid hash, drop collapsed, duplicate and unreferenced elements.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "nurbsfront/core/error.h"
#include "nurbsfront/core/parallel.h"
#include "nurbsfront/core/tolerances.h"
#include "nurbsfront/io/mesh_io.h"

namespace nurbsfront {
namespace {

using Triangle = std::array<std::uint32_t, 3>;
constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
constexpr std::size_t kNoIndex = std::numeric_limits<std::size_t>::max();
//! Grid cell edge in units of the weld tolerance. Larger cells mean fewer neighbour cells
//! to look into (a point is near a face along an axis with probability 2 / 8) but longer
//! chains per cell when points are denser than the tolerance.
constexpr double kCellsPerTolerance = 8.0;
//! Points or triangles per task of clean()'s parallel passes.
constexpr std::size_t kCleanChunk = 16384;

struct CellKey {
  std::int64_t x, y, z;
  bool operator==(const CellKey&) const = default;
};

std::uint64_t mix(std::uint64_t h) {
  // splitmix64 finaliser: spreads neighbouring cells over the whole table
  h ^= h >> 30;
  h *= 0xbf58476d1ce4e5b9ULL;
  h ^= h >> 27;
  h *= 0x94d049bb133111ebULL;
  return h ^ (h >> 31);
}

std::uint64_t hash_key(const CellKey& k) {
  return mix(static_cast<std::uint64_t>(k.x) * 0x9e3779b97f4a7c15ULL ^ static_cast<std::uint64_t>(k.y) * 0xc2b2ae3d27d4eb4fULL ^
             static_cast<std::uint64_t>(k.z) * 0x165667b19e3779f9ULL);
}

//! Open-addressing hash table (linear probing) whose slots hold point indices only: the
//! key of a slot is recomputed from its point, so the table costs 4 bytes per slot.
class PointTable {
 public:
  explicit PointTable(std::size_t n_max) {
    std::size_t capacity = 16;
    while (capacity < 2 * n_max) capacity <<= 1;  // load factor <= 1/2
    slots_.assign(capacity, kNone);
    mask_ = capacity - 1;
  }
  //! The slot holding a point for which same(point) is true, or the empty slot where
  //! such a point would go (its value is kNone then; the caller may write into it).
  template <typename Same>
  std::uint32_t& find(std::uint64_t hash, Same&& same) {
    std::size_t i = static_cast<std::size_t>(hash) & mask_;
    while (slots_[i] != kNone && !same(slots_[i])) i = (i + 1) & mask_;
    return slots_[i];
  }

 private:
  std::vector<std::uint32_t> slots_;
  std::size_t mask_ = 0;
};

//! For each point, the index of the point it is welded into (itself if it is kept).
//! Points are processed in order; each is merged into the lowest-index representative
//! within tol, found in the own grid cell (edge kCellsPerTolerance * tol) and the
//! neighbours across faces p is within tol of.
std::vector<std::uint32_t> weld(const std::vector<Eigen::Vector3d>& points, double tol, unsigned threads) {
  const std::size_t n = points.size();
  std::vector<std::uint32_t> rep(n);
  PointTable table(n);
  if (tol <= 0.0) {
    // Exact welding: identical coordinates only (-0 and +0 are equal).
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d p = points[i].array() + 0.0;
      CellKey bits{};
      std::memcpy(&bits.x, &p.x(), sizeof(double));
      std::memcpy(&bits.y, &p.y(), sizeof(double));
      std::memcpy(&bits.z, &p.z(), sizeof(double));
      std::uint32_t& slot = table.find(hash_key(bits), [&](std::uint32_t j) { return points[j] == p; });
      if (slot == kNone) slot = static_cast<std::uint32_t>(i);
      rep[i] = slot;
    }
    return rep;
  }
  const double inv_cell = 1.0 / (kCellsPerTolerance * tol);
  const double tol2 = tol * tol;
  // the margin covers the rounding of p * inv_cell; checking a neighbour too many is harmless
  const double near_face = (1.0 + tolerance::kNearFaceMargin) / kCellsPerTolerance;
  auto cell_of = [inv_cell](const Eigen::Vector3d& p) {
    return CellKey{static_cast<std::int64_t>(std::floor(p.x() * inv_cell)),
                   static_cast<std::int64_t>(std::floor(p.y() * inv_cell)),
                   static_cast<std::int64_t>(std::floor(p.z() * inv_cell))};
  };
  // Every point's cell and sides first (on `threads` threads: a function of the point
  // alone), so the serial pass below compares stored keys instead of recomputing them.
  // A point within tol lies in the own cell or, along an axis where p is within tol of a
  // cell face, in the neighbour across that face (side -1 or 1 along that axis).
  std::vector<CellKey> cell(n);
  std::vector<std::array<std::int8_t, 3>> side(n);
  parallel::for_chunks(n, threads, kCleanChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t i = begin; i < end; ++i) {
      const Eigen::Vector3d& p = points[i];
      const CellKey own = cell_of(p);
      cell[i] = own;
      for (int a = 0; a < 3; ++a) {
        const double frac = p[a] * inv_cell - static_cast<double>(a == 0 ? own.x : a == 1 ? own.y : own.z);
        side[i][a] = static_cast<std::int8_t>(frac < near_face ? -1 : frac > 1.0 - near_face ? 1 : 0);
      }
    }
  });
  // Each occupied slot holds the newest representative of a cell; older ones of the
  // same cell follow through next[] (kNone ends the chain).
  std::vector<std::uint32_t> next(n, kNone);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d& p = points[i];
    const CellKey own = cell[i];
    const std::array<std::int8_t, 3> near = side[i];
    std::uint32_t best = kNone;
    for (int m = 0; m < 8; ++m) {
      if (((m & 1) && near[0] == 0) || ((m & 2) && near[1] == 0) || ((m & 4) && near[2] == 0)) continue;
      const CellKey key{own.x + ((m & 1) ? near[0] : 0), own.y + ((m & 2) ? near[1] : 0),
                        own.z + ((m & 4) ? near[2] : 0)};
      const std::uint32_t head = table.find(hash_key(key), [&](std::uint32_t j) { return cell[j] == key; });
      for (std::uint32_t j = head; j != kNone; j = next[j]) {
        if (j < best && (points[j] - p).squaredNorm() <= tol2) best = j;
      }
    }
    if (best != kNone) {
      rep[i] = best;
    } else {
      rep[i] = static_cast<std::uint32_t>(i);
      std::uint32_t& slot = table.find(hash_key(own), [&](std::uint32_t j) { return cell[j] == own; });
      next[i] = slot;  // kNone for a new cell
      slot = static_cast<std::uint32_t>(i);
    }
  }
  return rep;
}

}  // namespace

void CleanOptions::validate() const {
  if (!std::isfinite(weld_tolerance_relative) || weld_tolerance_relative < 0.0 || weld_tolerance_relative >= 1.0) {
    throw InvalidInput("CleanOptions::weld_tolerance_relative must be in [0, 1), got " +
                       std::to_string(weld_tolerance_relative));
  }
  if (threads < 0) throw InvalidInput("CleanOptions::threads must be >= 0, got " + std::to_string(threads));
}

CleanResult clean(const TriangleSoup& soup, const CleanOptions& options) {
  options.validate();
  const unsigned threads = parallel::thread_count(options.threads);
  const std::size_t n = soup.points.size();
  const std::size_t n_triangles = soup.triangles.size();
  if (n >= kNone) throw InvalidInput("clean: more than 2^32-2 points");
  // The first bad point and the first bad triangle (the same errors for any thread count:
  // each chunk finds its first, the smallest is reported).
  std::vector<std::size_t> first_bad(2 * (n / kCleanChunk + n_triangles / kCleanChunk + 2), kNoIndex);
  parallel::for_chunks(n, threads, kCleanChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t i = begin; i < end && first_bad[begin / kCleanChunk] == kNoIndex; ++i)
      if (!soup.points[i].allFinite()) first_bad[begin / kCleanChunk] = i;
  });
  const std::size_t n_point_chunks = n / kCleanChunk + 1;
  for (std::size_t c = 0; c < n_point_chunks; ++c)
    if (first_bad[c] != kNoIndex) throw InvalidInput("clean: point " + std::to_string(first_bad[c]) + " is not finite");
  std::size_t* const first_bad_triangle = first_bad.data() + n_point_chunks;
  parallel::for_chunks(n_triangles, threads, kCleanChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t f = begin; f < end && first_bad_triangle[begin / kCleanChunk] == kNoIndex; ++f) {
      const Triangle& t = soup.triangles[f];
      if (t[0] >= n || t[1] >= n || t[2] >= n) first_bad_triangle[begin / kCleanChunk] = f;
    }
  });
  for (std::size_t c = 0; c <= n_triangles / kCleanChunk; ++c) {
    const std::size_t f = first_bad_triangle[c];
    if (f == kNoIndex) continue;
    for (const std::uint32_t v : soup.triangles[f]) {
      if (v >= n) throw InvalidInput("clean: triangle " + std::to_string(f) + " has out-of-range index " + std::to_string(v));
    }
  }
  CleanResult result;
  CleanReport& report = result.report;

  // 1. weld
  const double tol = options.weld_tolerance_relative * bounding_box(soup).diagonal();
  const std::vector<std::uint32_t> rep = weld(soup.points, tol, threads);
  for (std::size_t i = 0; i < n; ++i) report.n_welded_vertices += rep[i] != i ? 1 : 0;

  // 2. remap faces, drop collapsed ones. Each triangle's remapped corners and kind (kept,
  // collapsed, collinear) on `threads` threads, then the kept ones in order.
  constexpr std::uint8_t kKept = 0, kCollapsed = 1, kCollinear = 2;
  std::vector<Triangle> remapped(n_triangles);
  std::vector<std::uint8_t> kind(n_triangles);
  parallel::for_chunks(n_triangles, threads, kCleanChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t f = begin; f < end; ++f) {
      const Triangle& t = soup.triangles[f];
      const Triangle r{rep[t[0]], rep[t[1]], rep[t[2]]};
      remapped[f] = r;
      if (r[0] == r[1] || r[1] == r[2] || r[2] == r[0]) {
        kind[f] = kCollapsed;
        continue;
      }
      const Eigen::Vector3d& a = soup.points[r[0]];
      const Eigen::Vector3d normal = (soup.points[r[1]] - a).cross(soup.points[r[2]] - a);
      kind[f] = normal.squaredNorm() == 0.0 ? kCollinear : kKept;
    }
  });
  std::vector<Triangle> faces;
  faces.reserve(n_triangles);
  for (std::size_t f = 0; f < n_triangles; ++f) {
    if (kind[f] == kCollapsed && options.drop_degenerate) {
      ++report.n_degenerate_faces;
      continue;
    }
    report.n_collinear_faces += kind[f] == kCollinear ? 1 : 0;
    faces.push_back(remapped[f]);
  }
  remapped = {};
  kind = {};

  // 3. duplicates: same vertex set in any order; the first occurrence is kept (hashed)
  if (options.drop_duplicate_faces && faces.size() > 1) {
    std::vector<Triangle> sorted(faces.size());
    parallel::for_chunks(faces.size(), threads, kCleanChunk, [&](std::size_t begin, std::size_t end, unsigned) {
      for (std::size_t f = begin; f < end; ++f) {
        Triangle t = faces[f];
        if (t[0] > t[1]) std::swap(t[0], t[1]);
        if (t[1] > t[2]) std::swap(t[1], t[2]);
        if (t[0] > t[1]) std::swap(t[0], t[1]);
        sorted[f] = t;
      }
    });
    PointTable seen(faces.size());
    std::size_t out = 0;
    for (std::size_t f = 0; f < faces.size(); ++f) {
      const Triangle& t = sorted[f];
      const CellKey key{t[0], t[1], t[2]};
      std::uint32_t& slot = seen.find(hash_key(key), [&](std::uint32_t g) { return sorted[g] == t; });
      if (slot == kNone) {
        slot = static_cast<std::uint32_t>(f);
        faces[out++] = faces[f];
      } else {
        ++report.n_duplicate_faces;
      }
    }
    faces.resize(out);
  }

  // 4. renumber: kept points in input order
  std::vector<char> used(n, 0);
  if (options.drop_unreferenced) {
    for (const Triangle& t : faces) used[t[0]] = used[t[1]] = used[t[2]] = 1;
  } else {
    for (std::size_t i = 0; i < n; ++i) used[i] = rep[i] == i ? 1 : 0;
  }
  std::vector<std::uint32_t> new_index(n, kNone);
  result.soup.points.reserve(n - report.n_welded_vertices);
  for (std::size_t i = 0; i < n; ++i) {
    if (used[i]) {
      new_index[i] = static_cast<std::uint32_t>(result.soup.points.size());
      result.soup.points.push_back(soup.points[i]);
    } else if (rep[i] == i) {
      ++report.n_unreferenced_vertices;
    }
  }
  result.soup.triangles.resize(faces.size());
  parallel::for_chunks(faces.size(), threads, kCleanChunk, [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t f = begin; f < end; ++f) {
      for (int k = 0; k < 3; ++k) result.soup.triangles[f][k] = new_index[faces[f][k]];
    }
  });
  return result;
}

}  // namespace nurbsfront
