// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/front2d/front.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <functional>
#include <limits>
#include <numbers>
#include <optional>
#include <queue>
#include <unordered_map>
#include <unordered_set>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "nurbsfront/core/error.h"
#include "nurbsfront/core/stopwatch.h"
#include "nurbsfront/core/tolerances.h"
#include "nurbsfront/front2d/cholesky2.h"
#include "nurbsfront/front2d/domain.h"
#include "nurbsfront/front2d/predicates.h"

namespace nurbsfront {
namespace {

using Vec = Eigen::Vector2d;
using Mat = Eigen::Matrix2d;
using front2d::orient2d;

// Named constants of the front (all relative to the local target side d of the ideal triangle).
constexpr double kMinSideFactor = 0.55;    // ideal side >= this times the base edge length
constexpr double kMaxSideFactor = 2.0;     // ideal side <= this times the base edge length
constexpr double kSnapRadius = 0.6;        // existing nodes this close to the ideal point are preferred
constexpr double kWideRadius = 1.2;        // existing nodes considered at all
constexpr double kNodeClearance = 0.5;     // a new point keeps this distance from front nodes
constexpr double kEdgeClearance = 0.35;    // ... and this distance from front edges
constexpr int kCornerMinLoop = 6;          // the corner rule adds no node in a front loop of fewer nodes
constexpr double kCornerMaxAngleDeg = 80.0; // ... nor one that would make an angle above this in either half of the corner
constexpr double kSmoothAcceptAlpha = 0.6; // smoothing may lower the worst alpha down to this
constexpr double kMinAngleTargetDeg = 30.0; // relocation treats new points of triangles below this angle
constexpr double kRelocateFirstStep = 0.1;  // first compass step, times the shortest star edge
constexpr int kRelocateIterations = 24;     // compass search iterations per point
constexpr int kRelocateRounds = 2;          // relocation + swaps rounds
// Delaunay refinement (Optimiser::refine).
constexpr std::size_t kMaxCavity = 4096;          // triangles examined for encroachment per circumcentre
constexpr double kRefineMaxPointsFactor = 2.0;     // at most this times the triangles (+1000) new points
constexpr double kAutoSizeDivisor = 40.0;  // automatic uniform size: bbox diagonal / this
constexpr int kSizingGridCells = SizingField::kMaxCallbackGridCells;  // background grid of callback sizing fields, per side
constexpr int kSegmentSamples = 16;        // sizing samples per segment when splitting it
constexpr std::size_t kMaxGridCells = std::size_t{1} << 22;
constexpr std::size_t kProgressEvery = 1u << 14;
const double kSqrt3 = std::sqrt(3.0);

std::uint64_t dkey(int a, int b) { return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b); }
std::uint64_t ukey(int a, int b) { return a < b ? dkey(a, b) : dkey(b, a); }

double alpha(const Vec& a, const Vec& b, const Vec& c) {
  const double area2 = front2d::orient2d_naive(a, b, c);
  const double s = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
  return s > 0 ? 2.0 * kSqrt3 * area2 / s : 0.0;
}

// alpha of the image of abc under M^{1/2}: lengths sqrt(e^T M e), area sqrt(det M) A.
double alpha_in_metric(const Vec& a, const Vec& b, const Vec& c, const Mat& M) {
  const Vec ab = b - a, bc = c - b, ca = a - c;
  const double area2 = front2d::orient2d_naive(a, b, c);
  const double s = ab.dot(M * ab) + bc.dot(M * bc) + ca.dot(M * ca);
  return s > 0 ? 2.0 * kSqrt3 * std::sqrt(std::max(0.0, M.determinant())) * area2 / s : 0.0;
}

// Largest cosine of the three angles of abc measured in M (the cosine of its smallest angle).
// Each edge's length serves the angles at both its ends (3 square roots, not 6): an edge
// vector and its negation give the same length bit for bit, so the result is the one of
// the angle-by-angle evaluation.
double max_cos_in_metric(const Vec& a, const Vec& b, const Vec& c, const Mat& M) {
  const Vec ab = b - a, bc = c - b, ca = a - c;
  const double l_ab = std::sqrt(ab.dot(M * ab)), l_bc = std::sqrt(bc.dot(M * bc)), l_ca = std::sqrt(ca.dot(M * ca));
  // Angle at a between ab and ac = -ca, at b between bc and ba = -ab, at c between ca and cb = -bc.
  const std::array<double, 3> n{l_ab * l_ca, l_bc * l_ab, l_ca * l_bc};  // = |u| |w| exactly for M = I
  const std::array<const Vec*, 3> u{&ab, &bc, &ca};
  const std::array<Vec, 3> w{c - a, a - b, b - c};
  double m = -1.0;
  for (std::size_t i = 0; i < 3; ++i) m = std::max(m, n[i] > 0 ? u[i]->dot(M * w[i]) / n[i] : 1.0);
  return m;
}

using detail::distance_to_segment;

// Evaluates a SizingField, gradation-limited.
class Sizing {
 public:
  Sizing(const SizingField& f, const std::vector<Vec>& input, const Vec& lo, const Vec& hi) : f_(f), pts_(input) {
    slope_ = f.gradation - 1.0;
    const double diag = (hi - lo).norm();
    if (f.kind == SizingField::Kind::Uniform) {
      h_ = f.uniform_size > 0 ? f.uniform_size : diag / kAutoSizeDivisor;
    } else if (f.kind == SizingField::Kind::Callback) {
      lo_ = lo;
      n_ = f.callback_grid_cells > 0 ? std::min(f.callback_grid_cells, kSizingGridCells) : kSizingGridCells;
      cell_ = std::max((hi - lo).maxCoeff() / n_, diag * tolerance::kZeroLengthRelative);
      grid_.resize(static_cast<std::size_t>((n_ + 1) * (n_ + 1)));
      for (int j = 0; j <= n_; ++j)
        for (int i = 0; i <= n_; ++i) {
          const double v = f.callback(lo + cell_ * Vec(i, j));
          if (!std::isfinite(v) || v <= 0) throw InvalidInput("SizingField: the callback returned a size <= 0 or not finite");
          grid_[idx(i, j)] = v;
        }
      // Gradation limit by repeated sweeps (a discrete distance transform).
      const double step = slope_ * cell_;
      const double diag_step = slope_ * cell_ * std::sqrt(2.0);
      for (int pass = 0; pass < 4; ++pass) {
        for (int j = 0; j <= n_; ++j)
          for (int i = 0; i <= n_; ++i) relax(i, j, step, diag_step, pass % 2 == 0 ? -1 : 1);
        for (int j = n_; j >= 0; --j)
          for (int i = n_; i >= 0; --i) relax(i, j, step, diag_step, pass % 2 == 0 ? 1 : -1);
      }
    }
  }

  // The uniform case inline: the front asks for sizes at every step (and 1024 times per
  // mesh for its size estimate).
  [[nodiscard]] double operator()(const Vec& x) const { return f_.kind == SizingField::Kind::Uniform ? h_ : varying(x); }

 private:
  [[nodiscard]] double varying(const Vec& x) const {
    switch (f_.kind) {
      case SizingField::Kind::Uniform:
        return h_;
      case SizingField::Kind::PerVertex: {
        double wsum = 0;
        double hsum = 0;
        double cone = std::numeric_limits<double>::infinity();
        for (std::size_t i = 0; i < pts_.size(); ++i) {
          const double d2 = (x - pts_[i]).squaredNorm();
          const double hi = f_.vertex_sizes[i];
          if (d2 == 0) return hi;
          wsum += 1.0 / d2;
          hsum += hi / d2;
          cone = std::min(cone, hi + slope_ * std::sqrt(d2));
        }
        return std::min(hsum / wsum, cone);
      }
      case SizingField::Kind::Callback: {
        const double u = std::clamp((x.x() - lo_.x()) / cell_, 0.0, static_cast<double>(n_));
        const double v = std::clamp((x.y() - lo_.y()) / cell_, 0.0, static_cast<double>(n_));
        const int i = std::min(static_cast<int>(u), n_ - 1);
        const int j = std::min(static_cast<int>(v), n_ - 1);
        const double s = u - i;
        const double t = v - j;
        const double g = (1 - s) * (1 - t) * grid_[idx(i, j)] + s * (1 - t) * grid_[idx(i + 1, j)] +
                         (1 - s) * t * grid_[idx(i, j + 1)] + s * t * grid_[idx(i + 1, j + 1)];
        const double c = f_.callback(x);
        return std::isfinite(c) && c > 0 ? std::min(c, g) : g;
      }
    }
    return h_;
  }

  [[nodiscard]] std::size_t idx(int i, int j) const { return static_cast<std::size_t>(j * (n_ + 1) + i); }
  void relax(int i, int j, double step, double diag_step, int dir) {
    double& v = grid_[idx(i, j)];
    const int jj = j + dir;
    for (int di = -1; di <= 1; ++di) {
      const int ii = i + di;
      if (ii >= 0 && ii <= n_) {
        v = std::min(v, grid_[idx(ii, j)] + step);
        if (jj >= 0 && jj <= n_) v = std::min(v, grid_[idx(ii, jj)] + (di == 0 ? step : diag_step));
      }
    }
  }
  const SizingField& f_;
  const std::vector<Vec>& pts_;
  double h_ = 0;
  double slope_ = 0.5;
  Vec lo_ = Vec::Zero();
  int n_ = 0;
  double cell_ = 1;
  std::vector<double> grid_;
};

// Length of d in the metric at x.
double metric_length(const Metric* m, const Vec& x, const Vec& d) {
  if (!m) return d.norm();
  return std::sqrt(std::max(0.0, d.dot(m->tensor(x) * d)));
}

// Uniform grid of front edges (isolated points are edges with a == b).
class EdgeGrid {
 public:
  EdgeGrid(const Vec& lo, const Vec& hi, double cell) : lo_(lo) {
    const Vec ext = hi - lo;
    cell_ = std::max(cell, ext.maxCoeff() * 1e-6);
    while (true) {
      nx_ = static_cast<int>(ext.x() / cell_) + 1;
      ny_ = static_cast<int>(ext.y() / cell_) + 1;
      if (static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_) <= kMaxGridCells) break;
      cell_ *= 1.5;
    }
    inv_ = 1.0 / cell_;
    cells_.resize(static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_));
  }
  [[nodiscard]] int cx(double x) const { return std::clamp(static_cast<int>((x - lo_.x()) * inv_), 0, nx_ - 1); }
  [[nodiscard]] int cy(double y) const { return std::clamp(static_cast<int>((y - lo_.y()) * inv_), 0, ny_ - 1); }
  // Each cell keeps up to kInline edges in place (one cache line, no allocation); more go
  // to a linked overflow list in a shared pool with a free list.
  void insert(int e, const Vec& p, const Vec& q) {
    for (int j = cy(std::min(p.y(), q.y())); j <= cy(std::max(p.y(), q.y())); ++j)
      for (int i = cx(std::min(p.x(), q.x())); i <= cx(std::max(p.x(), q.x())); ++i) {
        Cell& c = cell(i, j);
        if (c.n < kInline) {
          c.e[static_cast<std::size_t>(c.n++)] = e;
          continue;
        }
        int node = free_;
        if (node >= 0) {
          free_ = pool_[static_cast<std::size_t>(node)].next;
        } else {
          node = static_cast<int>(pool_.size());
          pool_.emplace_back();
        }
        pool_[static_cast<std::size_t>(node)] = {e, c.overflow};
        c.overflow = node;
      }
  }
  void erase(int e, const Vec& p, const Vec& q) {
    for (int j = cy(std::min(p.y(), q.y())); j <= cy(std::max(p.y(), q.y())); ++j)
      for (int i = cx(std::min(p.x(), q.x())); i <= cx(std::max(p.x(), q.x())); ++i) erase_in(cell(i, j), e);
  }
  //! Calls f(edge) for every edge in the cells meeting the box (an edge may come twice).
  template <class F>
  void visit(const Vec& lo, const Vec& hi, F&& f) const {
    const int i0 = cx(lo.x()), i1 = cx(hi.x()), j0 = cy(lo.y()), j1 = cy(hi.y());
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const Cell& c = cells_[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(i)];
        for (int k = 0; k < c.n; ++k) f(c.e[static_cast<std::size_t>(k)]);
        for (int node = c.overflow; node >= 0; node = pool_[static_cast<std::size_t>(node)].next) f(pool_[static_cast<std::size_t>(node)].edge);
      }
  }
  [[nodiscard]] bool covers_all(const Vec& lo, const Vec& hi) const {
    return cx(lo.x()) == 0 && cy(lo.y()) == 0 && cx(hi.x()) == nx_ - 1 && cy(hi.y()) == ny_ - 1;
  }

 private:
  static constexpr int kInline = 6;
  struct Cell {
    int n = 0;
    int overflow = -1;
    std::array<int, kInline> e{};
  };
  struct Node {
    int edge = -1;
    int next = -1;
  };
  Cell& cell(int i, int j) { return cells_[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(i)]; }
  void erase_in(Cell& c, int e) {
    for (int k = 0; k < c.n; ++k)
      if (c.e[static_cast<std::size_t>(k)] == e) {
        if (c.overflow >= 0) {  // refill the slot from the overflow list
          const int node = c.overflow;
          c.e[static_cast<std::size_t>(k)] = pool_[static_cast<std::size_t>(node)].edge;
          c.overflow = pool_[static_cast<std::size_t>(node)].next;
          pool_[static_cast<std::size_t>(node)].next = free_;
          free_ = node;
        } else {
          c.e[static_cast<std::size_t>(k)] = c.e[static_cast<std::size_t>(--c.n)];
        }
        return;
      }
    for (int* link = &c.overflow; *link >= 0; link = &pool_[static_cast<std::size_t>(*link)].next)
      if (pool_[static_cast<std::size_t>(*link)].edge == e) {
        const int node = *link;
        *link = pool_[static_cast<std::size_t>(node)].next;
        pool_[static_cast<std::size_t>(node)].next = free_;
        free_ = node;
        return;
      }
  }

  Vec lo_;
  double cell_ = 1, inv_ = 1;
  int nx_ = 1, ny_ = 1;
  std::vector<Cell> cells_;
  std::vector<Node> pool_;
  int free_ = -1;
};

// Binary min-heap of front edges by (squared length, creation order), indexed so that an edge is
// removed when it dies: the heap holds only the live front (a few thousand entries that stay
// in cache) instead of every dead edge until it surfaces.
class EdgeHeap {
 public:
  [[nodiscard]] bool empty() const { return h_.empty(); }
  //! Ties of key are broken by `birth` (a creation counter), so the order does not depend
  //! on how edge ids are recycled.
  void push(int e, double key, std::uint32_t birth) {
    if (pos_.size() <= static_cast<std::size_t>(e)) pos_.resize(static_cast<std::size_t>(e) + 1024, -1);
    h_.push_back({key, birth, e});
    up(h_.size() - 1);
  }
  int pop() {
    const int e = h_.front().e;
    remove(e);
    return e;
  }
  void remove(int e) {
    if (static_cast<std::size_t>(e) >= pos_.size() || pos_[static_cast<std::size_t>(e)] < 0) return;
    const auto i = static_cast<std::size_t>(pos_[static_cast<std::size_t>(e)]);
    pos_[static_cast<std::size_t>(e)] = -1;
    const Entry last = h_.back();
    h_.pop_back();
    if (i == h_.size()) return;
    h_[i] = last;
    pos_[static_cast<std::size_t>(last.e)] = static_cast<int>(i);
    down(i);
    up(static_cast<std::size_t>(pos_[static_cast<std::size_t>(last.e)]));
  }

 private:
  struct Entry {  // 16 bytes
    double key;
    std::uint32_t birth;
    int e;
  };
  static bool less(const Entry& x, const Entry& y) { return x.key < y.key || (x.key == y.key && x.birth < y.birth); }
  void place(std::size_t i, const Entry& x) {
    h_[i] = x;
    pos_[static_cast<std::size_t>(x.e)] = static_cast<int>(i);
  }
  void up(std::size_t i) {
    const Entry x = h_[i];
    while (i > 0) {
      const std::size_t parent = (i - 1) / 2;
      if (!less(x, h_[parent])) break;
      place(i, h_[parent]);
      i = parent;
    }
    place(i, x);
  }
  void down(std::size_t i) {
    const Entry x = h_[i];
    const std::size_t n = h_.size();
    while (true) {
      std::size_t c = 2 * i + 1;
      if (c >= n) break;
      if (c + 1 < n && less(h_[c + 1], h_[c])) ++c;
      if (!less(h_[c], x)) break;
      place(i, h_[c]);
      i = c;
    }
    place(i, x);
  }
  std::vector<Entry> h_;
  std::vector<int> pos_;  // per edge: index in h_, -1 if absent
};

struct FrontEdge {
  int a = -1, b = -1;
  bool alive = false;
  int next_out = -1;  // next front edge leaving a (per-vertex singly linked list)
};

class AdvancingFront {
 public:
  AdvancingFront(std::vector<Vec>& pts, const Sizing& size, const Metric* metric, EdgeGrid grid, double corner_split_angle_deg)
      : P_(pts), size_(size), metric_(metric), grid_(std::move(grid)), first_new_(static_cast<int>(pts.size())),
        corner_cos_(corner_split_angle_deg >= 180.0 ? -2.0 : std::cos(corner_split_angle_deg * std::numbers::pi / 180.0)) {}

  //! Boundary edges never cancel: both sides of an interior segment are on the front.
  void add_boundary_edge(int a, int b) {
    const int e = new_edge(a, b);
    heap_.push(e, (pt(a) - pt(b)).squaredNorm(), births_);
  }
  void add_isolated_point(int p) {
    const int e = new_edge(p, p);
    iso_edge_[p] = e;
  }

  //! Runs the front; returns the number of edges left open.
  std::size_t run(std::size_t max_new_points, std::size_t expected_triangles, const ProgressCallback& progress,
                  FrontReport& report) {
    std::size_t open = 0;
    while (!heap_.empty()) {
      const int e = heap_.pop();
      if (!E_[static_cast<std::size_t>(e)].alive) continue;
      const bool allow_new = report.n_new_points < max_new_points;
      if (!advance(e, allow_new, report)) ++open;
      if (tris_.size() % kProgressEvery == 0 && progress)
        report_progress(progress, "front2d: front",
                        std::min(1.0, static_cast<double>(tris_.size()) / static_cast<double>(std::max<std::size_t>(1, expected_triangles))));
    }
    return open;
  }

  std::vector<std::array<int, 3>>& triangles() { return tris_; }

 private:
  int new_edge(int a, int b) {
    // Dead edges' ids are recycled: the edge arrays stay as small as the front.
    ++births_;
    int e = -1;
    if (!free_edges_.empty()) {
      e = free_edges_.back();
      free_edges_.pop_back();
      E_[static_cast<std::size_t>(e)] = {a, b, true, -1};
    } else {
      e = static_cast<int>(E_.size());
      E_.push_back({a, b, true, -1});
      stamp_e_.push_back(0);
    }
    if (a != b) {
      if (out_head_.size() < P_.size()) out_head_.resize(P_.size() + P_.size() / 2 + 16, -1);
      E_[static_cast<std::size_t>(e)].next_out = out_head_[static_cast<std::size_t>(a)];
      out_head_[static_cast<std::size_t>(a)] = e;
    }
    grid_.insert(e, P_[static_cast<std::size_t>(a)], P_[static_cast<std::size_t>(b)]);
    return e;
  }
  void kill(int e) {
    auto& f = E_[static_cast<std::size_t>(e)];
    f.alive = false;
    heap_.remove(e);
    free_edges_.push_back(e);
    grid_.erase(e, P_[static_cast<std::size_t>(f.a)], P_[static_cast<std::size_t>(f.b)]);
    if (f.a != f.b) {
      int* link = &out_head_[static_cast<std::size_t>(f.a)];
      while (*link != e) link = &E_[static_cast<std::size_t>(*link)].next_out;
      *link = f.next_out;
    }
  }
  [[nodiscard]] int find_edge(int a, int b) const {
    if (static_cast<std::size_t>(a) >= out_head_.size()) return -1;
    for (int e = out_head_[static_cast<std::size_t>(a)]; e >= 0; e = E_[static_cast<std::size_t>(e)].next_out)
      if (E_[static_cast<std::size_t>(e)].b == b) return e;
    return -1;
  }
  void add_edge(int a, int b) {
    if (const int r = find_edge(b, a); r >= 0) {
      kill(r);
      return;
    }
    const int e = new_edge(a, b);
    heap_.push(e, (P_[static_cast<std::size_t>(a)] - P_[static_cast<std::size_t>(b)]).squaredNorm(), births_);
  }
  [[nodiscard]] const Vec& pt(int i) const { return P_[static_cast<std::size_t>(i)]; }
  void next_stamp() {
    if (++stamp_ == 0) {  // wrapped around: clear the marks
      std::fill(stamp_e_.begin(), stamp_e_.end(), 0u);
      std::fill(stamp_v_.begin(), stamp_v_.end(), 0u);
      stamp_ = 1;
    }
  }

  // Exact validity of triangle (a, b, p); p == -1 means the new point q. With clearance, a
  // new point must also keep distances cn from nodes and ce from edges.
  bool valid(int a, int b, int p, const Vec& q, double cn, double ce) {
    const Vec& A = pt(a);
    const Vec& B = pt(b);
    if (orient2d(A, B, q) <= 0) return false;
    const Vec tlo = A.cwiseMin(B).cwiseMin(q);
    const Vec thi = A.cwiseMax(B).cwiseMax(q);
    Vec lo = tlo, hi = thi;
    const bool is_new = p < 0;
    if (is_new) {
      lo.array() -= std::max(cn, ce);
      hi.array() += std::max(cn, ce);
    }
    // A front edge whose box lies farther than `reach` from q in x or in y keeps both
    // clearances: reach exceeds max(cn, ce) by far more than the rounding of the distances
    // computed below (relative 1e-9 against about 1e-15), so those would not flag it either.
    const double reach = is_new ? std::max(cn, ce) + tolerance::kClearanceSlack * (std::max(cn, ce) + q.cwiseAbs().maxCoeff()) : 0.0;
    auto inside = [&](const Vec& v) { return orient2d(A, B, v) >= 0 && orient2d(B, q, v) >= 0 && orient2d(q, A, v) >= 0; };
    auto conflict = [&](int u, const Vec& U, int w, const Vec& W, int s, int t) {
      // New edge (u, w) against front edge (s, t); the pair {u, w} == {s, t} was skipped.
      int shared = -1, x = -1, y = -1;
      if (s == u) { shared = u; x = w; y = t; }
      else if (s == w) { shared = w; x = u; y = t; }
      else if (t == u) { shared = u; x = w; y = s; }
      else if (t == w) { shared = w; x = u; y = s; }
      if (shared >= 0) {
        const Vec& C = shared == u ? U : W;
        const Vec& X = x == u ? U : W;
        const Vec& Y = pt(y);
        return orient2d(C, X, Y) == 0 && (X - C).dot(Y - C) > 0;
      }
      const Vec& S = pt(s);
      const Vec& T = pt(t);
      // Boxes apart (exact comparisons): the closed segments share no point.
      if (std::max(U.x(), W.x()) < std::min(S.x(), T.x()) || std::min(U.x(), W.x()) > std::max(S.x(), T.x()) ||
          std::max(U.y(), W.y()) < std::min(S.y(), T.y()) || std::min(U.y(), W.y()) > std::max(S.y(), T.y()))
        return false;
      return front2d::segments_intersect(U, W, S, T);
    };
    bool ok = true;
    auto check = [&](int e) {
      const FrontEdge& f = E_[static_cast<std::size_t>(e)];
      const int s = f.a, t = f.b;
      if (s == a && t == b) return;
      const Vec& S = pt(s);
      const Vec& T = pt(t);
      if (std::max(S.x(), T.x()) < tlo.x() || std::min(S.x(), T.x()) > thi.x() || std::max(S.y(), T.y()) < tlo.y() ||
          std::min(S.y(), T.y()) > thi.y()) {
        // Disjoint from the triangle's box: no containment, no crossing; only the clearance
        // of a new point remains to check.
        if (!is_new) return;
        if (std::min(S.x(), T.x()) > q.x() + reach || std::max(S.x(), T.x()) < q.x() - reach ||
            std::min(S.y(), T.y()) > q.y() + reach || std::max(S.y(), T.y()) < q.y() - reach)
          return;
        const bool s_free = s != a && s != b, t_free = t != a && t != b;
        if ((s_free && (S - q).squaredNorm() < cn * cn) || (t_free && (T - q).squaredNorm() < cn * cn)) {
          ok = false;
          return;
        }
        if (s != t && s_free && t_free) {
          const Vec d = T - S;
          const double l2 = d.squaredNorm();
          const double u = l2 > 0 ? std::clamp((q - S).dot(d) / l2, 0.0, 1.0) : 0.0;
          if ((S + u * d - q).squaredNorm() < ce * ce) ok = false;
        }
        return;
      }
      if (s == t) {
        if (s == p || s == a || s == b) return;
        if (inside(pt(s)) || (is_new && (pt(s) - q).squaredNorm() < cn * cn)) ok = false;
        return;
      }
      for (int v : {s, t}) {
        if (v == a || v == b || v == p) continue;
        if (inside(pt(v)) || (is_new && (pt(v) - q).squaredNorm() < cn * cn)) {
          ok = false;
          return;
        }
      }
      const bool same_ap = (s == a && t == p) || (s == p && t == a);
      const bool same_pb = (s == p && t == b) || (s == b && t == p);
      if (!same_ap && conflict(a, A, p, q, s, t)) { ok = false; return; }
      if (!same_pb && conflict(p, q, b, B, s, t)) { ok = false; return; }
      if (is_new && s != a && s != b && t != a && t != b) {
        const Vec d = T - S;
        const double l2 = d.squaredNorm();
        const double u = l2 > 0 ? std::clamp((q - S).dot(d) / l2, 0.0, 1.0) : 0.0;
        if ((S + u * d - q).squaredNorm() < ce * ce) ok = false;
      }
    };
    if (local_ok_ && lo.x() >= local_lo_.x() && lo.y() >= local_lo_.y() && hi.x() <= local_hi_.x() && hi.y() <= local_hi_.y()) {
      // Every edge registered in a cell meeting the box is in the local list.
      for (int e : local_edges_) {
        check(e);
        if (!ok) break;
      }
      return ok;
    }
    next_stamp();
    grid_.visit(lo, hi, [&](int e) {
      if (!ok || stamp_e_[static_cast<std::size_t>(e)] == stamp_) return;
      stamp_e_[static_cast<std::size_t>(e)] = stamp_;
      check(e);
    });
    return ok;
  }

  void accept(int e, int p) {
    local_ok_ = false;  // the front changes
    const int a = E_[static_cast<std::size_t>(e)].a;
    const int b = E_[static_cast<std::size_t>(e)].b;
    tris_.push_back({a, b, p});
    kill(e);
    if (auto it = iso_edge_.empty() ? iso_edge_.end() : iso_edge_.find(p); it != iso_edge_.end()) {
      kill(it->second);
      iso_edge_.erase(it);
    }
    add_edge(a, p);
    add_edge(p, b);
  }

  // Collects the front edges of the cells meeting the box (once each) into local_edges_, for
  // the validity checks of this step, and their nodes other than a and b into cand_.
  void gather_local(const Vec& lo, const Vec& hi, int a, int b) {
    cand_.clear();
    local_edges_.clear();
    local_lo_ = lo;
    local_hi_ = hi;
    local_ok_ = true;
    next_stamp();
    grid_.visit(lo, hi, [&](int e) {
      if (stamp_e_[static_cast<std::size_t>(e)] == stamp_) return;
      stamp_e_[static_cast<std::size_t>(e)] = stamp_;
      local_edges_.push_back(e);
      add_nodes(E_[static_cast<std::size_t>(e)], a, b, cand_);
    });
  }

  void gather(const Vec& lo, const Vec& hi, int a, int b, std::vector<int>& out) {
    out.clear();
    next_stamp();
    grid_.visit(lo, hi, [&](int e) { add_nodes(E_[static_cast<std::size_t>(e)], a, b, out); });
  }
  // Appends the nodes of f other than a and b not yet seen in this walk.
  void add_nodes(const FrontEdge& f, int a, int b, std::vector<int>& out) {
    for (int v : {f.a, f.b}) {
      if (v == a || v == b) continue;
      if (static_cast<std::size_t>(v) >= stamp_v_.size()) stamp_v_.resize(P_.size() + 1024, 0);
      if (stamp_v_[static_cast<std::size_t>(v)] == stamp_) continue;
      stamp_v_[static_cast<std::size_t>(v)] = stamp_;
      out.push_back(v);
    }
  }

  // The only front edge leaving x, or -1 when there is none or more than one (touching loops).
  [[nodiscard]] int single_out_edge(int x) const {
    if (static_cast<std::size_t>(x) >= out_head_.size()) return -1;
    const int e = out_head_[static_cast<std::size_t>(x)];
    return e >= 0 && E_[static_cast<std::size_t>(e)].next_out < 0 ? e : -1;
  }

  // Corner rule. Triangle (a, b, v) is valid; when it closes the front corner at b (front edge
  // (b, v)) or at a (front edge (v, a)), that corner is an input node and its inner angle in
  // the metric is over the threshold, it would have that angle: a new node on the corner's
  // bisector, at the mean metric length of its two legs, makes triangle (a, b, q) now and leaves the corner's other
  // half (half the angle) to the front. Not in a loop of under kCornerMinLoop nodes (the new
  // node would have too few neighbours to be free of obtuse angles). Returns true when the
  // new node passed the usual tests (clearances included) and was accepted.
  bool split_corner(int e, int a, int b, int v, bool allow_new, FrontReport& report) {
    if (!allow_new || corner_cos_ < -1.0) return false;
    const bool at_b = find_edge(b, v) >= 0;
    const bool at_a = find_edge(v, a) >= 0;
    if (at_a == at_b) return false;  // no corner, or the last triangle of a 3-node loop
    int x = b;
    for (int nodes = 2; nodes < kCornerMinLoop; ++nodes) {
      const int out = single_out_edge(x);
      if (out < 0) break;
      x = E_[static_cast<std::size_t>(out)].b;
      if (x == a) return false;
    }
    const int c = at_b ? b : a;
    const int n1 = at_b ? a : v, n2 = at_b ? v : b;
    // The corner must be an input node (it never moves: an obtuse angle there stays), its legs
    // may end at new points: a border node whose first-row triangles leave a wide gap between
    // them would get an obtuse closure (docs/front2d.md "Corner rule at border nodes").
    if (c >= first_new_) return false;
    const Vec& C = pt(c);
    const Vec d1 = pt(n1) - C, d2 = pt(n2) - C;
    Eigen::Matrix2d R = Eigen::Matrix2d::Identity();
    if (metric_) R = detail::cholesky_upper(metric_->tensor(C));
    const Vec u1 = R * d1, u2 = R * d2;
    const double l1 = u1.norm(), l2 = u2.norm();
    if (!(l1 > 0 && l2 > 0) || u1.dot(u2) >= corner_cos_ * l1 * l2) return false;
    const Vec bisector = u1 / l1 + u2 / l2;
    const double lb = bisector.norm();
    if (!(lb > 0)) return false;
    // At the geometric mean of the legs; both halves (c, n1, q) and (c, q, n2) must have every
    // angle under kCornerMaxAngleDeg in the metric (with legs of ratio over about 2 at a right
    // corner no point on the bisector does: then the old closure).
    const Vec w = bisector * (std::sqrt(l1 * l2) / lb);
    const double max_cos = std::cos(kCornerMaxAngleDeg * std::numbers::pi / 180.0);
    for (const Vec& u : {u1, u2}) {  // angles at u and at w of the half (0, u, w); the one at 0 is half the corner
      const Vec uw = w - u;
      const double luw = uw.norm();
      if (!(luw > 0) || (-u).dot(uw) < max_cos * u.norm() * luw || (-w).dot(-uw) < max_cos * w.norm() * luw) return false;
    }
    Vec offset = w;
    if (metric_) offset = R.triangularView<Eigen::Upper>().solve(offset);
    const Vec q = C + offset;
    const double r = offset.norm();
    if (!valid(a, b, -1, q, kNodeClearance * r, kEdgeClearance * r)) return false;
    P_.push_back(q);
    ++report.n_new_points;
    ++report.n_corner_points;
    accept(e, static_cast<int>(P_.size() - 1));
    return true;
  }

  bool advance(int e, bool allow_new, FrontReport& report) {
    const int a = E_[static_cast<std::size_t>(e)].a;
    const int b = E_[static_cast<std::size_t>(e)].b;
    const Vec& A = pt(a);
    const Vec& B = pt(b);
    const Vec mid = 0.5 * (A + B);
    const Vec ab = B - A;
    // Ideal point: apex of the isosceles triangle of side d over ab, in the metric.
    const double h = size_(mid);
    Vec offset;
    if (metric_) {
      const Eigen::Matrix2d M = metric_->tensor(mid);
      const Eigen::Matrix2d R = detail::cholesky_upper(M);
      const Vec u = R * ab;
      const double L = u.norm();
      const double d = std::clamp(h, kMinSideFactor * L, kMaxSideFactor * L);
      const double height = std::sqrt(std::max(0.0, d * d - 0.25 * L * L));
      offset = R.triangularView<Eigen::Upper>().solve(Vec(-u.y(), u.x()) / L * height);
    } else {
      const double L = ab.norm();
      const double d = std::clamp(h, kMinSideFactor * L, kMaxSideFactor * L);
      const double height = std::sqrt(std::max(0.0, d * d - 0.25 * L * L));
      offset = Vec(-ab.y(), ab.x()) / L * height;
    }
    const Vec ideal = mid + offset;
    const double side = 0.5 * ((ideal - A).norm() + (ideal - B).norm());
    const double wide = kWideRadius * side;
    // One grid walk gives the candidates and serves the validity checks of the triangles
    // that fit in its box (those over ab with a node near the ideal point).
    gather_local(ideal - Vec::Constant(wide), ideal + Vec::Constant(wide), a, b);
    near_.clear();
    for (int v : cand_) {
      const double dist = (pt(v) - ideal).norm();
      if (dist < wide && orient2d(A, B, pt(v)) > 0) near_.emplace_back(dist, v);
    }
    std::sort(near_.begin(), near_.end());
    for (const auto& [dist, v] : near_) {
      if (dist >= kSnapRadius * side) break;
      if (valid(a, b, v, pt(v), 0, 0)) {
        if (!split_corner(e, a, b, v, allow_new, report)) accept(e, v);
        return true;
      }
    }
    if (allow_new && valid(a, b, -1, ideal, kNodeClearance * side, kEdgeClearance * side)) {
      P_.push_back(ideal);
      ++report.n_new_points;
      accept(e, static_cast<int>(P_.size() - 1));
      return true;
    }
    for (auto& [key, v] : near_) key = -alpha(A, B, pt(v));
    std::sort(near_.begin(), near_.end());
    for (const auto& [key, v] : near_) {
      if (valid(a, b, v, pt(v), 0, 0)) {
        if (!split_corner(e, a, b, v, allow_new, report)) accept(e, v);
        return true;
      }
    }
    // Repair: the constrained-Delaunay-like choice among every visible node, searched in a
    // growing box. Such a node exists whenever the front bounds a valid polygonal domain.
    ++report.n_repairs;
    double r = 2.0 * ab.norm();
    while (true) {
      const Vec lo = mid - Vec::Constant(r);
      const Vec hi = mid + Vec::Constant(r);
      gather(lo, hi, a, b, cand_);
      int best = -1;
      for (int v : cand_) {
        if (orient2d(A, B, pt(v)) <= 0) continue;
        if (best >= 0 && front2d::incircle(A, B, pt(best), pt(v)) <= 0) continue;
        if (valid(a, b, v, pt(v), 0, 0)) best = v;
      }
      if (best >= 0) {
        accept(e, best);
        return true;
      }
      if (grid_.covers_all(lo, hi)) break;
      r *= 2.0;
    }
    // Unreachable for a valid front; leave the edge open rather than loop.
    E_[static_cast<std::size_t>(e)].alive = false;
    return false;
  }

  std::vector<Vec>& P_;
  const Sizing& size_;
  const Metric* metric_;
  EdgeGrid grid_;
  std::vector<FrontEdge> E_;
  std::vector<std::uint32_t> stamp_e_;
  std::vector<int> free_edges_;
  std::uint32_t births_ = 0;  // creation counter (wraps after 4e9 edges: only ties reorder)
  std::vector<std::uint32_t> stamp_v_;
  std::uint32_t stamp_ = 0;
  std::vector<int> out_head_;
  std::unordered_map<int, int> iso_edge_;
  EdgeHeap heap_;
  std::vector<std::array<int, 3>> tris_;
  std::vector<int> cand_;
  std::vector<int> local_edges_;
  Vec local_lo_ = Vec::Zero(), local_hi_ = Vec::Zero();
  bool local_ok_ = false;
  std::vector<std::pair<double, int>> near_;
  int first_new_;      // points from here on are created by the front
  double corner_cos_;  // cosine of the corner rule's angle; < -1 = off
};

// What the Delaunay refinement (Optimiser::refine) reads and updates besides the mesh.
struct RefineContext {
  std::unordered_map<std::uint64_t, int>* pieces = nullptr;       // constrained piece (ukey) -> domain segment
  std::vector<std::vector<int>>* chains = nullptr;                // per domain segment, its nodes in order
  std::vector<std::array<int, 2>>* slide = nullptr;               // per point: its segment's endpoints, or {-1, -1}
  std::unordered_map<std::uint64_t, int>* side_marker = nullptr;  // region marker of each directed piece
  const std::vector<std::array<int, 2>>* segments = nullptr;      // the domain segments
  std::vector<bool> acute;   // per input point: two consecutive segments there make < 60 deg (or a dangling end)
  int n_input = 0;           // input points precede every other point
  double min_length = 0;     // pieces shorter than twice this are not split
  const Sizing* size = nullptr;  // the sizing field h
  std::size_t max_points = 0;  // cap on the points the refinement inserts
};

// Per point: whether two consecutive segments at it make an angle below 60 deg, or a segment
// ends there without another (a dangling end).
std::vector<bool> acute_vertices(const std::vector<Vec>& pts, const std::vector<std::array<int, 2>>& segments) {
  std::vector<std::vector<double>> dirs(pts.size());
  for (const auto& sg : segments)
    for (int e = 0; e < 2; ++e) {
      const Vec d = pts[static_cast<std::size_t>(sg[static_cast<std::size_t>(1 - e)])] - pts[static_cast<std::size_t>(sg[static_cast<std::size_t>(e)])];
      dirs[static_cast<std::size_t>(sg[static_cast<std::size_t>(e)])].push_back(std::atan2(d.y(), d.x()));
    }
  std::vector<bool> acute(pts.size(), false);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    auto& d = dirs[i];
    if (d.size() == 1) acute[i] = true;
    if (d.size() < 2) continue;
    std::sort(d.begin(), d.end());
    for (std::size_t j = 0; j < d.size(); ++j) {
      const double gap = (j + 1 < d.size() ? d[j + 1] : d[0] + 2.0 * std::numbers::pi) - d[j];
      if (gap < std::numbers::pi / 3.0) acute[i] = true;
    }
  }
  return acute;
}

// Triangles with adjacency, for swaps and smoothing. With a metric, every quality measure
// (swap criterion, smoothing acceptance, angles of the relocation) is evaluated in the
// metric: per triangle, the mean of its vertices' tensors (cached per vertex, refreshed when
// a vertex moves).
class Optimiser {
 public:
  Optimiser(std::vector<Vec>& pts, std::vector<std::array<int, 3>>& tris, const std::unordered_map<std::uint64_t, int>& constraints,
            int first_free, const Metric* metric)
      : P_(pts), T_(tris), metric_(metric) {
    if (metric_) {
      Mv_.resize(P_.size());
      for (std::size_t i = 0; i < P_.size(); ++i) Mv_[i] = metric_->tensor(P_[i]);
    }
    N_.assign(3 * T_.size(), -1);
    C_.assign(3 * T_.size(), false);
    // Directed edges grouped by their first vertex (CSR of {second vertex, slot}); the twin
    // of slot a->b is the entry a of b's group.
    std::vector<int> start(P_.size() + 1, 0);
    for (const auto& t : T_)
      for (int x : t) ++start[static_cast<std::size_t>(x) + 1];
    for (std::size_t i = 0; i < P_.size(); ++i) start[i + 1] += start[i];
    std::vector<std::array<int, 2>> out(static_cast<std::size_t>(start.back()));
    {
      std::vector<int> fill(start.begin(), start.end() - 1);
      for (std::size_t t = 0; t < T_.size(); ++t)
        for (int i = 0; i < 3; ++i)
          out[static_cast<std::size_t>(fill[static_cast<std::size_t>(T_[t][static_cast<std::size_t>(i)])]++)] = {
              T_[t][static_cast<std::size_t>((i + 1) % 3)], static_cast<int>(3 * t) + i};
    }
    for (std::size_t t = 0; t < T_.size(); ++t)
      for (int i = 0; i < 3; ++i) {
        const std::size_t s = 3 * t + static_cast<std::size_t>(i);
        if (N_[s] >= 0) continue;
        const int a = T_[t][static_cast<std::size_t>(i)], b = T_[t][static_cast<std::size_t>((i + 1) % 3)];
        for (int k = start[static_cast<std::size_t>(b)]; k < start[static_cast<std::size_t>(b) + 1]; ++k)
          if (out[static_cast<std::size_t>(k)][0] == a) {
            const int o = out[static_cast<std::size_t>(k)][1];
            N_[s] = o;
            N_[static_cast<std::size_t>(o)] = static_cast<int>(s);
            // Constraint edges join segment nodes, which all precede first_free.
            C_[s] = C_[static_cast<std::size_t>(o)] = a < first_free && b < first_free && constraints.count(ukey(a, b)) > 0;
            break;
          }
        if (N_[s] < 0) C_[s] = true;  // boundary edges
      }
  }

  // Slots are never negative: unsigned division by 3 is a multiply and a shift, and each of
  // nxt and prv takes one remainder (the swaps ask for four vertices a test).
  [[nodiscard]] int v(int slot) const {
    const auto u = static_cast<std::size_t>(static_cast<unsigned>(slot));
    return T_[u / 3][u % 3];
  }
  [[nodiscard]] static int nxt(int slot) { return static_cast<unsigned>(slot) % 3 == 2 ? slot - 2 : slot + 1; }
  [[nodiscard]] static int prv(int slot) { return static_cast<unsigned>(slot) % 3 == 0 ? slot + 2 : slot - 1; }

  std::size_t delaunay_swaps() {
    std::vector<int> stack;
    for (std::size_t s = 0; s < N_.size(); ++s)
      if (N_[s] > static_cast<int>(s) && !C_[s]) stack.push_back(static_cast<int>(s));
    std::size_t n = 0;
    const std::size_t limit = 20 * T_.size() + 100;
    while (!stack.empty() && n < limit) {
      const int s = stack.back();
      stack.pop_back();
      const int o = N_[static_cast<std::size_t>(s)];
      if (o < 0 || C_[static_cast<std::size_t>(s)]) continue;
      const int a = v(s), b = v(nxt(s)), c = v(prv(s)), d = v(prv(o));
      if (known_no_swap(s, a, b, c, d)) continue;
      if (!should_swap(a, b, c, d)) {
        remember_no_swap(s, a, b, c, d);
        continue;
      }
      const Vec &A = pt(a), &B = pt(b), &Cc = pt(c), &D = pt(d);
      if (orient2d(A, D, Cc) <= 0 || orient2d(D, B, Cc) <= 0) continue;
      flip(s);
      ++n;
      const int t = s / 3, u = o / 3;
      for (int i = 0; i < 3; ++i) {
        stack.push_back(3 * t + i);
        stack.push_back(3 * u + i);
      }
    }
    return n;
  }

  // Laplacian smoothing of the points from first_free on. With `fixed` (per point, true for
  // points that must not move: segment split points after the refinement), those are skipped;
  // with keep_good, a move must also keep every star triangle that has no angle below
  // kMinAngleTargetDeg so, and must not make the smallest angle of any other star triangle
  // smaller (after the refinement: excused triangles stay as they are).
  void smooth(int passes, int first_free, const std::vector<std::array<int, 2>>* fixed = nullptr, bool keep_good = false) {
    const Incidence inc = incidence();
    const double target = std::cos(kMinAngleTargetDeg * std::numbers::pi / 180.0);
    // With keep_good: the cosine of the smallest angle of each star triangle before the move.
    std::vector<double> before;
    for (int pass = 0; pass < passes; ++pass) {
      for (std::size_t vtx = static_cast<std::size_t>(first_free); vtx < P_.size(); ++vtx) {
        const int b0 = inc.start[vtx], b1 = inc.start[vtx + 1];
        if (b0 == b1) continue;
        if (fixed && vtx < fixed->size() && (*fixed)[vtx][0] >= 0) continue;
        if (keep_good) {
          before.clear();
          for (int k = b0; k < b1; ++k) before.push_back(max_cos(T_[static_cast<std::size_t>(inc.tri[static_cast<std::size_t>(k)])]));
        }
        const Vec old = P_[vtx];
        const Mat old_m = metric_ ? Mv_[vtx] : Mat::Identity();
        move(static_cast<int>(vtx), smoothing_target(static_cast<int>(vtx), inc));
        // Kept if every triangle stays counter-clockwise and the worst alpha stays above
        // min(old worst, kSmoothAcceptAlpha); the old worst is needed only below that.
        bool ok = true;
        double worst_new = 2.0;
        for (int k = b0; k < b1 && ok; ++k) {
          const double q = checked_quality(T_[static_cast<std::size_t>(inc.tri[static_cast<std::size_t>(k)])]);
          ok = q > kNotOriented;
          worst_new = std::min(worst_new, q);
        }
        if (ok && worst_new < kSmoothAcceptAlpha) {
          const Vec moved = P_[vtx];
          const Mat moved_m = metric_ ? Mv_[vtx] : Mat::Identity();
          P_[vtx] = old;
          if (metric_) Mv_[vtx] = old_m;
          double worst = 2.0;
          for (int k = b0; k < b1; ++k) worst = std::min(worst, quality(T_[static_cast<std::size_t>(inc.tri[static_cast<std::size_t>(k)])]));
          ok = worst_new >= worst;
          if (ok) {
            P_[vtx] = moved;
            if (metric_) Mv_[vtx] = moved_m;
          }
        }
        for (int k = b0; k < b1 && ok && keep_good; ++k)
          ok = max_cos(T_[static_cast<std::size_t>(inc.tri[static_cast<std::size_t>(k)])]) <= std::max(before[static_cast<std::size_t>(k - b0)], target);
        if (!ok) {
          P_[vtx] = old;
          if (metric_) Mv_[vtx] = old_m;
        } else {
          mark_moved(static_cast<int>(vtx));
        }
      }
    }
  }

  // Min-angle-driven relocation: every new point of a triangle with an angle below
  // kMinAngleTargetDeg is moved by a compass search that maximises the smallest angle of its
  // star; a move is kept only if every triangle of the star stays positively oriented (exact)
  // and the star's smallest angle strictly grows. Returns the number of points moved.
  // Segment split points (slide[v] = the input segment's endpoints, {-1, -1} elsewhere) move
  // along their segment only.
  // With keep_good, a move must also keep every star triangle that has no angle below
  // kMinAngleTargetDeg so (after the refinement, whose excused triangles would otherwise pull
  // good neighbours below the target).
  std::size_t improve_min_angle(int first_free, const std::vector<std::array<int, 2>>& slide, bool keep_good = false) {
    const double target = std::cos(kMinAngleTargetDeg * std::numbers::pi / 180.0);
    std::vector<int> todo;
    for (const auto& t : T_) {
      if (!has_small_angle(t, target * target)) continue;
      for (int x : t)
        if (x >= first_free || slide[static_cast<std::size_t>(x)][0] >= 0) todo.push_back(x);
    }
    if (todo.empty()) return 0;
    std::sort(todo.begin(), todo.end());
    todo.erase(std::unique(todo.begin(), todo.end()), todo.end());
    const Incidence inc = incidence();
    // The compass directions, computed once (the same numbers as per move).
    std::array<Vec, 8> compass;
    for (int d = 0; d < 8; ++d) {
      const double ang = d * std::numbers::pi / 4.0;
      compass[static_cast<std::size_t>(d)] = Vec(std::cos(ang), std::sin(ang));
    }
    std::size_t moved = 0;
    for (int vtx : todo) {
      const auto vi = static_cast<std::size_t>(vtx);
      const int b0 = inc.start[vi], b1 = inc.start[vi + 1];
      // The star's quality: the largest cosine of its angles (smaller is better), or
      // +inf if a triangle is not positively oriented.
      int n_good = -1;  // good triangles of the star at the start (keep_good)
      // A candidate is kept only if its star beats `bound`: the evaluation stops as soon as
      // one triangle's cosine reaches it (the candidate is rejected either way). The
      // triangle that decided the last evaluation (its worst, or the one that stopped it)
      // goes first: it most often stops the next one at once. A kept candidate's star is
      // evaluated in full, and its maximum (and good count) do not depend on the order,
      // so the moves are the same bit for bit.
      int lead = b0;
      auto star = [&](double bound) {
        double worst = -1.0;
        int good = 0;
        int worst_k = lead;
        for (int i = b0; i < b1; ++i) {
          const int k = i == b0 ? lead : (i == lead ? b0 : i);
          const auto& t = T_[static_cast<std::size_t>(inc.tri[static_cast<std::size_t>(k)])];
          if (orient2d(pt(t[0]), pt(t[1]), pt(t[2])) <= 0) {
            lead = k;
            return std::numeric_limits<double>::infinity();
          }
          const double mc = max_cos(t);
          if (mc > worst) {
            worst = mc;
            worst_k = k;
          }
          if (worst >= bound) {
            lead = k;
            return worst;
          }
          good += mc <= target;
        }
        lead = worst_k;
        if (keep_good && good < n_good) return std::numeric_limits<double>::infinity();
        if (n_good < 0) n_good = good;
        return worst;
      };
      double best = star(std::numeric_limits<double>::infinity());
      double step = std::numeric_limits<double>::infinity();
      for (int k = b0; k < b1; ++k)
        for (int x : T_[static_cast<std::size_t>(inc.tri[static_cast<std::size_t>(k)])])
          if (x != vtx) step = std::min(step, (pt(x) - P_[vi]).norm());
      step *= kRelocateFirstStep;
      const Vec start_pos = P_[vi];
      const bool on_segment = slide[vi][0] >= 0;
      Vec sa = Vec::Zero(), sd = Vec::Zero();
      double t_cur = 0.0, seg_len = 1.0;
      if (on_segment) {
        sa = pt(slide[vi][0]);
        sd = pt(slide[vi][1]) - sa;
        seg_len = sd.norm();
        t_cur = (P_[vi] - sa).dot(sd) / (seg_len * seg_len);
      }
      for (int it = 0; it < kRelocateIterations && step > 0; ++it) {
        bool improved = false;
        for (int d = 0; d < (on_segment ? 2 : 8); ++d) {
          const Vec old = P_[vi];
          const Mat old_m = metric_ ? Mv_[vi] : Mat::Identity();
          double t_new = t_cur;
          if (on_segment) {
            t_new = t_cur + (d == 0 ? step : -step) / seg_len;
            move(vtx, sa + t_new * sd);
          } else {
            move(vtx, old + step * compass[static_cast<std::size_t>(d)]);
          }
          const double q = star(best);
          if (q < best) {
            best = q;
            t_cur = t_new;
            improved = true;
            mark_moved(vtx);
          } else {
            P_[vi] = old;
            if (metric_) Mv_[vi] = old_m;
          }
        }
        if (!improved) step *= 0.5;
      }
      if (P_[vi] != start_pos) ++moved;
    }
    return moved;
  }

  // Delaunay refinement of the triangles with an angle below kMinAngleTargetDeg (Ruppert
  // 1995; Shewchuk 2002, as Triangle's -q): the mesh is made constrained Delaunay by swaps,
  // the constrained pieces encroached by a vertex (in their diametral circle) are split, then,
  // worst bad triangle first, its circumcentre is inserted (Lawson: split the triangle or
  // edge that contains it, swap until Delaunay again) unless it encroaches a constrained
  // piece: then that piece is split instead, at its midpoint, or on a concentric shell (a
  // power of 2 from the apex) when one end is an input vertex with a small angle; new points
  // that encroach pieces make them split too. Triangles are excused (never split) when their
  // smallest angle is at an input vertex with an input angle below 60 deg, or when their
  // shortest edge joins two segments meeting at such an angle (Shewchuk's rule: the narrow
  // wedge near the apex). Every insertion or split keeps every triangle exactly
  // counter-clockwise (checked; a split that would not is skipped) and the inserted points
  // are capped, so the loop ends. Returns the number of points inserted. A mesh without bad
  // triangles costs one scan.
  std::size_t refine(RefineContext& rc) {
    const double c30 = std::cos(kMinAngleTargetDeg * std::numbers::pi / 180.0);
    auto is_bad = [&](int t) {
      const auto& tr = T_[static_cast<std::size_t>(t)];
      return has_small_angle(tr, c30 * c30) && !excused(tr, rc);
    };
    bool any = false;
    for (std::size_t t = 0; t < T_.size() && !any; ++t) any = is_bad(static_cast<int>(t));
    if (!any) return 0;
    delaunay_swaps();
    struct Item {
      double key;  // cosine of the smallest angle: the worst triangle first
      int t;
      std::array<int, 3> v;
      bool operator<(const Item& o) const { return key < o.key || (key == o.key && t > o.t); }
    };
    std::priority_queue<Item> queue;
    auto push = [&](int t) {
      if (is_bad(t)) queue.push({max_cos(T_[static_cast<std::size_t>(t)]), t, T_[static_cast<std::size_t>(t)]});
    };
    for (std::size_t t = 0; t < T_.size(); ++t) push(static_cast<int>(t));
    std::size_t inserted = 0;
    std::vector<int> touched;
    // Encroached pieces first (Ruppert): afterwards no piece has a vertex in its diametral
    // circle, so every circumcentre is visible from its triangle.
    std::vector<int> all(T_.size());
    for (std::size_t t = 0; t < all.size(); ++t) all[t] = static_cast<int>(t);
    split_encroached(all, rc, inserted, push);
    while (!queue.empty() && inserted < rc.max_points) {
      const Item item = queue.top();
      queue.pop();
      if (T_[static_cast<std::size_t>(item.t)] != item.v) continue;  // stale: the triangle changed
      const Vec c = circumcentre(item.v);
      if (!c.allFinite()) continue;
      const Located loc = locate(item.t, c);
      // Hidden behind a piece (only when a piece could not be split), on a vertex, or lost:
      // the triangle stays.
      if (loc.kind != Located::Inside && loc.kind != Located::OnEdge) continue;
      touched.clear();
      const int s = encroached_piece(loc, c);
      if (s >= 0) {
        if (!split_piece(s, rc, touched)) continue;
        queue.push(item);                           // retried after the split
      } else {
        P_.push_back(c);
        rc.slide->push_back({-1, -1});
        const int p = static_cast<int>(P_.size()) - 1;
        if (loc.kind == Located::OnEdge) split_edge(loc.slot, p, touched);
        else split_triangle(loc.tri, p, touched);
        legalise(p, touched);
      }
      ++inserted;
      for (int t : touched) push(t);
      split_encroached(touched, rc, inserted, push);
    }
    return inserted;
  }

  // Region marker per triangle by flood fill from the boundary sides.
  std::vector<int> regions(const std::unordered_map<std::uint64_t, int>& side_marker) const {
    std::vector<int> r(T_.size(), 0);
    if (std::all_of(side_marker.begin(), side_marker.end(), [](const auto& kv) { return kv.second == 0; })) return r;
    std::vector<bool> done(T_.size(), false);
    std::vector<int> stack;
    for (std::size_t s = 0; s < N_.size(); ++s) {
      if (!C_[s]) continue;
      const int t = static_cast<int>(s / 3);
      if (done[static_cast<std::size_t>(t)]) continue;
      auto it = side_marker.find(dkey(v(static_cast<int>(s)), v(nxt(static_cast<int>(s)))));
      if (it == side_marker.end()) continue;
      done[static_cast<std::size_t>(t)] = true;
      stack.push_back(t);
      while (!stack.empty()) {
        const int u = stack.back();
        stack.pop_back();
        r[static_cast<std::size_t>(u)] = it->second;
        for (int i = 0; i < 3; ++i) {
          const int sl = 3 * u + i;
          const int o = N_[static_cast<std::size_t>(sl)];
          if (o < 0 || C_[static_cast<std::size_t>(sl)] || done[static_cast<std::size_t>(o / 3)]) continue;
          done[static_cast<std::size_t>(o / 3)] = true;
          stack.push_back(o / 3);
        }
      }
    }
    return r;
  }

 private:
  // ---- Delaunay refinement helpers (see refine()).
  [[nodiscard]] bool excused(const std::array<int, 3>& t, const RefineContext& rc) const {
    // The vertex with the smallest angle: the one opposite the shortest edge.
    int i_min = 0;
    double l_min = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i) {
      const double l = (pt(t[static_cast<std::size_t>((i + 1) % 3)]) - pt(t[static_cast<std::size_t>((i + 2) % 3)])).squaredNorm();
      if (l < l_min) {
        l_min = l;
        i_min = i;
      }
    }
    const int apex = t[static_cast<std::size_t>(i_min)];
    if (apex < rc.n_input && rc.acute[static_cast<std::size_t>(apex)]) return true;
    const int p = t[static_cast<std::size_t>((i_min + 1) % 3)], q = t[static_cast<std::size_t>((i_min + 2) % 3)];
    const auto& sq = (*rc.slide)[static_cast<std::size_t>(q)];
    return sq[0] >= 0 && in_wedge(p, sq, rc);
  }

  // Whether the split point x lies on a segment other than e = {e0, e1} that meets e at an
  // input vertex under an angle below 60 deg (x is then in the narrow wedge of that angle).
  [[nodiscard]] bool in_wedge(int x, const std::array<int, 2>& e, const RefineContext& rc) const {
    const auto& sx = (*rc.slide)[static_cast<std::size_t>(x)];
    if (sx[0] < 0 || (sx[0] == e[0] && sx[1] == e[1]) || (sx[0] == e[1] && sx[1] == e[0])) return false;
    for (int a : sx) {
      if (a != e[0] && a != e[1]) continue;
      const Vec d1 = pt(sx[0] == a ? sx[1] : sx[0]) - pt(a);
      const Vec d2 = pt(e[0] == a ? e[1] : e[0]) - pt(a);
      if (d1.dot(d2) > 0.5 * d1.norm() * d2.norm()) return true;  // angle below 60 deg
    }
    return false;
  }

  // Whether the vertex x encroaches the piece of slot s: x in its diametral circle.
  [[nodiscard]] bool encroached_by(int s, int x) const { return encroaches(pt(v(s)), pt(v(nxt(s))), pt(x)); }

  // Whether x lies in the diametral circle of the piece uw.
  [[nodiscard]] static bool encroaches(const Vec& u, const Vec& w, const Vec& x) { return (u - x).dot(w - x) < 0.0; }

  // Splits every constrained piece of the given triangles that the opposite vertex
  // encroaches, and the pieces the splits expose, until none is left (or the cap is hit).
  // A stacked slot is re-tested when popped: splits reassign slots, but every triangle they
  // change is examined again.
  template <class Push>
  void split_encroached(const std::vector<int>& tris, RefineContext& rc, std::size_t& inserted, Push&& push) {
    std::vector<int>& stack = seg_stack_;
    stack.clear();
    auto scan = [&](const std::vector<int>& ts) {
      for (int t : ts)
        for (int k = 0; k < 3; ++k) {
          const int s = 3 * t + k;
          if (C_[static_cast<std::size_t>(s)] && encroached_by(s, v(prv(s)))) stack.push_back(s);
        }
    };
    scan(tris);
    std::vector<int> touched;
    while (!stack.empty() && inserted < rc.max_points) {
      const int s = stack.back();
      stack.pop_back();
      if (!C_[static_cast<std::size_t>(s)] || !encroached_by(s, v(prv(s)))) continue;
      touched.clear();
      if (!split_piece(s, rc, touched)) continue;
      ++inserted;
      for (int t : touched) push(t);
      scan(touched);
    }
  }

  [[nodiscard]] Vec circumcentre(const std::array<int, 3>& t) const {
    const Vec& a = pt(t[0]);
    const Vec b = pt(t[1]) - a, c = pt(t[2]) - a;
    const double d = 2.0 * (b.x() * c.y() - b.y() * c.x());
    return a + Vec(c.y() * b.squaredNorm() - b.y() * c.squaredNorm(), b.x() * c.squaredNorm() - c.x() * b.squaredNorm()) / d;
  }

  struct Located {
    enum Kind { Inside, OnEdge, OnVertex, Blocked, Lost } kind = Lost;
    int tri = -1;   // Inside, OnEdge: the triangle
    int slot = -1;  // OnEdge: the edge; Blocked: the constrained edge the walk cannot cross
  };
  // Visibility walk from triangle t towards x (exact orientations); stops at a constrained
  // edge. The start edge rotates with the step so that the walk cannot cycle.
  [[nodiscard]] Located locate(int t, const Vec& x) const {
    const std::size_t max_steps = T_.size() + 16;
    for (std::size_t step = 0; step < max_steps; ++step) {
      int zero = -1, n_zero = 0, cross = -1;
      for (int k = 0; k < 3; ++k) {
        const int i = static_cast<int>((static_cast<std::size_t>(k) + step) % 3);
        const int s = 3 * t + i;
        const int o = orient2d(pt(v(s)), pt(v(nxt(s))), x);
        if (o < 0) {
          cross = s;
          break;
        }
        if (o == 0) {
          zero = s;
          ++n_zero;
        }
      }
      if (cross < 0) {
        if (n_zero == 0) return {Located::Inside, t, -1};
        if (n_zero == 1) return {Located::OnEdge, t, zero};
        return {Located::OnVertex, t, -1};
      }
      if (C_[static_cast<std::size_t>(cross)]) return {Located::Blocked, t, cross};
      t = N_[static_cast<std::size_t>(cross)] / 3;
    }
    return {};
  }

  // A constrained edge of the cavity of x (the triangles whose circumcircle contains x,
  // reached from the located triangle without crossing a constrained edge) whose diametral
  // circle contains x; -1 if none. On a constrained edge, x encroaches that edge.
  [[nodiscard]] int encroached_piece(const Located& loc, const Vec& x) {
    if (loc.kind == Located::OnEdge && C_[static_cast<std::size_t>(loc.slot)]) return loc.slot;
    cavity_.clear();
    cavity_.push_back(loc.tri);
    if (loc.kind == Located::OnEdge) cavity_.push_back(N_[static_cast<std::size_t>(loc.slot)] / 3);
    for (std::size_t i = 0; i < cavity_.size() && i < kMaxCavity; ++i) {
      const int t = cavity_[i];
      for (int k = 0; k < 3; ++k) {
        const int s = 3 * t + k;
        const Vec& a = pt(v(s));
        const Vec& b = pt(v(nxt(s)));
        if (C_[static_cast<std::size_t>(s)]) {
          if (encroaches(a, b, x)) return s;
          continue;
        }
        const int u = N_[static_cast<std::size_t>(s)] / 3;
        if (std::find(cavity_.begin(), cavity_.end(), u) != cavity_.end()) continue;
        const auto& tu = T_[static_cast<std::size_t>(u)];
        if (front2d::incircle(pt(tu[0]), pt(tu[1]), pt(tu[2]), x) > 0) cavity_.push_back(u);
      }
    }
    return -1;
  }

  // Appends a triangle (three slots) and returns its index.
  int new_triangle(const std::array<int, 3>& t) {
    T_.push_back(t);
    N_.insert(N_.end(), 3, -1);
    C_.insert(C_.end(), 3, false);
    return static_cast<int>(T_.size()) - 1;
  }
  // Links slot s with nb (or none: -1) and sets the constraint flag of both.
  void set_slot(int s, int nb, bool constrained) {
    set_nb(s, nb);
    C_[static_cast<std::size_t>(s)] = constrained;
    if (nb >= 0) C_[static_cast<std::size_t>(nb)] = constrained;
  }

  // Splits triangle t = (a, b, c) at the interior point p into (a, b, p), (b, c, p), (c, a, p);
  // each has p last, so slot 0 is the edge opposite p.
  void split_triangle(int t, int p, std::vector<int>& touched) {
    const auto [a, b, c] = T_[static_cast<std::size_t>(t)];
    const int s0 = 3 * t;
    const int n_ab = N_[static_cast<std::size_t>(s0)], n_bc = N_[static_cast<std::size_t>(s0 + 1)], n_ca = N_[static_cast<std::size_t>(s0 + 2)];
    const bool c_ab = C_[static_cast<std::size_t>(s0)], c_bc = C_[static_cast<std::size_t>(s0 + 1)], c_ca = C_[static_cast<std::size_t>(s0 + 2)];
    T_[static_cast<std::size_t>(t)] = {a, b, p};
    const int t1 = new_triangle({b, c, p});
    const int t2 = new_triangle({c, a, p});
    set_slot(s0, n_ab, c_ab);
    set_slot(3 * t1, n_bc, c_bc);
    set_slot(3 * t2, n_ca, c_ca);
    set_slot(s0 + 1, 3 * t1 + 2, false);
    set_slot(3 * t1 + 1, 3 * t2 + 2, false);
    set_slot(3 * t2 + 1, s0 + 2, false);
    touched.insert(touched.end(), {t, t1, t2});
  }

  // Splits the edge of slot s (a -> b in t = (a, b, c), twin b -> a in (b, a, d) if any) at p,
  // which lies on or next to it: (c, a, p), (b, c, p) and (a, d, p), (d, b, p). The halves keep
  // the edge's constraint flag.
  void split_edge(int s, int p, std::vector<int>& touched) {
    const int t = s / 3, o = N_[static_cast<std::size_t>(s)];
    const int a = v(s), b = v(nxt(s)), c = v(prv(s));
    const bool con = C_[static_cast<std::size_t>(s)];
    const int n_bc = N_[static_cast<std::size_t>(nxt(s))], n_ca = N_[static_cast<std::size_t>(prv(s))];
    const bool c_bc = C_[static_cast<std::size_t>(nxt(s))], c_ca = C_[static_cast<std::size_t>(prv(s))];
    T_[static_cast<std::size_t>(t)] = {c, a, p};
    const int t1 = new_triangle({b, c, p});
    const int s0 = 3 * t;
    set_slot(s0, n_ca, c_ca);
    set_slot(3 * t1, n_bc, c_bc);
    set_slot(s0 + 2, 3 * t1 + 1, false);  // p -> c with c -> p
    set_slot(s0 + 1, -1, true);           // a -> p, twin below
    set_slot(3 * t1 + 2, -1, true);       // p -> b
    touched.insert(touched.end(), {t, t1});
    if (o < 0) return;
    const int u = o / 3;
    const int d = v(prv(o));
    const int n_ad = N_[static_cast<std::size_t>(nxt(o))], n_db = N_[static_cast<std::size_t>(prv(o))];
    const bool c_ad = C_[static_cast<std::size_t>(nxt(o))], c_db = C_[static_cast<std::size_t>(prv(o))];
    T_[static_cast<std::size_t>(u)] = {a, d, p};
    const int u1 = new_triangle({d, b, p});
    const int u0 = 3 * u;
    set_slot(u0, n_ad, c_ad);
    set_slot(3 * u1, n_db, c_db);
    set_slot(u0 + 1, 3 * u1 + 2, false);  // d -> p with p -> d
    set_slot(u0 + 2, s0 + 1, con);        // p -> a with a -> p
    set_slot(3 * u1 + 1, 3 * t1 + 2, con);  // b -> p with p -> b
    C_[static_cast<std::size_t>(s0 + 1)] = con;
    C_[static_cast<std::size_t>(3 * t1 + 2)] = con;
    touched.insert(touched.end(), {u, u1});
  }

  // Lawson swaps after inserting p: the edges opposite p in the touched triangles (slot 0 of
  // each, p last) are swapped while not Delaunay; each swap exposes two new edges opposite p.
  void legalise(int p, std::vector<int>& touched) {
    std::vector<int>& stack = legal_stack_;
    stack.clear();
    for (int t : touched) stack.push_back(3 * t);
    while (!stack.empty()) {
      const int s = stack.back();
      stack.pop_back();
      const int o = N_[static_cast<std::size_t>(s)];
      if (o < 0 || C_[static_cast<std::size_t>(s)] || v(prv(s)) != p) continue;
      const int a = v(s), b = v(nxt(s)), d = v(prv(o));
      if (!should_swap(a, b, p, d)) continue;
      if (orient2d(pt(a), pt(d), pt(p)) <= 0 || orient2d(pt(d), pt(b), pt(p)) <= 0) continue;
      flip(s);  // (a, b, p), (b, a, d) -> (p, a, d), (d, b, p)
      const int t = s / 3, u = o / 3;
      touched.push_back(u);
      stack.push_back(3 * t + 1);  // a -> d
      stack.push_back(3 * u);      // d -> b
    }
  }

  // Splits the constrained piece of slot s (midpoint, or a concentric shell around an input
  // vertex with a small angle) and updates the segment bookkeeping. False if the piece is too
  // short or a triangle would not stay exactly counter-clockwise.
  bool split_piece(int s, RefineContext& rc, std::vector<int>& touched) {
    const int u = v(s), w = v(nxt(s));
    const auto it = rc.pieces->find(ukey(u, w));
    if (it == rc.pieces->end()) return false;
    const int k = it->second;
    const Vec U = pt(u), W = pt(w);
    const double len = (W - U).norm();
    if (len < 2.0 * rc.min_length) return false;
    const bool acute_u = u < rc.n_input && rc.acute[static_cast<std::size_t>(u)];
    const bool acute_w = w < rc.n_input && rc.acute[static_cast<std::size_t>(w)];
    double f = 0.5;
    if (acute_u != acute_w) {  // the power of 2 nearest to len / 2, from the apex: in [0.35, 0.71] len
      const double r = std::exp2(std::round(std::log2(0.5 * len)));
      f = acute_u ? r / len : 1.0 - r / len;
    }
    const Vec m = U + f * (W - U);
    const int o = N_[static_cast<std::size_t>(s)];
    const Vec& Cc = pt(v(prv(s)));
    if (orient2d(U, m, Cc) <= 0 || orient2d(m, W, Cc) <= 0) return false;
    if (o >= 0) {
      const Vec& D = pt(v(prv(o)));
      if (orient2d(W, m, D) <= 0 || orient2d(m, U, D) <= 0) return false;
    }
    P_.push_back(m);
    const int p = static_cast<int>(P_.size()) - 1;
    rc.slide->push_back((*rc.segments)[static_cast<std::size_t>(k)]);
    rc.pieces->erase(it);
    (*rc.pieces)[ukey(u, p)] = k;
    (*rc.pieces)[ukey(p, w)] = k;
    auto& ch = (*rc.chains)[static_cast<std::size_t>(k)];
    const auto pos = std::find(ch.begin(), ch.end(), u);
    ch.insert(pos + 1 != ch.end() && *(pos + 1) == w ? pos + 1 : pos, p);
    for (const auto& [x, y] : {std::pair{u, w}, std::pair{w, u}})
      if (const auto sm = rc.side_marker->find(dkey(x, y)); sm != rc.side_marker->end()) {
        const int marker = sm->second;
        rc.side_marker->erase(sm);
        (*rc.side_marker)[dkey(x, p)] = marker;
        (*rc.side_marker)[dkey(p, y)] = marker;
      }
    split_edge(s, p, touched);
    legalise(p, touched);
    return true;
  }

  // Vertex -> incident triangles (CSR).
  struct Incidence {
    std::vector<int> start;
    std::vector<int> tri;
  };
  [[nodiscard]] Incidence incidence() const {
    Incidence inc;
    inc.start.assign(P_.size() + 1, 0);
    for (const auto& t : T_)
      for (int x : t) ++inc.start[static_cast<std::size_t>(x) + 1];
    for (std::size_t i = 0; i < P_.size(); ++i) inc.start[i + 1] += inc.start[i];
    inc.tri.resize(static_cast<std::size_t>(inc.start.back()));
    std::vector<int> fill(inc.start.begin(), inc.start.end() - 1);
    for (std::size_t t = 0; t < T_.size(); ++t)
      for (int x : T_[t]) inc.tri[static_cast<std::size_t>(fill[static_cast<std::size_t>(x)]++)] = static_cast<int>(t);
    return inc;
  }

  [[nodiscard]] const Vec& pt(int i) const { return P_[static_cast<std::size_t>(i)]; }
  [[nodiscard]] const Mat& mv(int i) const { return Mv_[static_cast<std::size_t>(i)]; }
  void move(int i, const Vec& x) {
    P_[static_cast<std::size_t>(i)] = x;
    if (metric_) Mv_[static_cast<std::size_t>(i)] = metric_->tensor(x);
  }
  // Stamps a kept move of i (a move that is undone leaves the vertex as it was, unstamped).
  void mark_moved(int i) {
    if (moved_at_.size() <= static_cast<std::size_t>(i)) moved_at_.resize(P_.size(), 0);
    moved_at_[static_cast<std::size_t>(i)] = ++clock_;
  }
  [[nodiscard]] std::uint64_t moved_at(int i) const {
    return static_cast<std::size_t>(i) < moved_at_.size() ? moved_at_[static_cast<std::size_t>(i)] : 0;
  }
  // should_swap(a, b, c, d) is a function of the four points and their tensors only: a slot
  // whose quad was found not to need a swap, and none of whose four vertices moved since,
  // needs no second evaluation (the swap passes after the smoothing and after each
  // relocation round meet mostly unchanged quads).
  [[nodiscard]] bool known_no_swap(int s, int a, int b, int c, int d) const {
    if (static_cast<std::size_t>(s) >= no_swap_.size()) return false;
    const NoSwap& m = no_swap_[static_cast<std::size_t>(s)];
    return m.q[0] == a && m.q[1] == b && m.q[2] == c && m.q[3] == d && moved_at(a) <= m.at && moved_at(b) <= m.at &&
           moved_at(c) <= m.at && moved_at(d) <= m.at;
  }
  void remember_no_swap(int s, int a, int b, int c, int d) {
    if (no_swap_.size() <= static_cast<std::size_t>(s)) no_swap_.resize(N_.size());
    no_swap_[static_cast<std::size_t>(s)] = {{a, b, c, d}, clock_};
  }
  [[nodiscard]] Mat tri_metric(const std::array<int, 3>& t) const { return (mv(t[0]) + mv(t[1]) + mv(t[2])) / 3.0; }

  [[nodiscard]] double quality(const std::array<int, 3>& t) const {
    if (metric_) return alpha_in_metric(pt(t[0]), pt(t[1]), pt(t[2]), tri_metric(t));
    return alpha(pt(t[0]), pt(t[1]), pt(t[2]));
  }
  // quality(t) if t is exactly counter-clockwise, else kNotOriented (below every alpha). The
  // orientation filter and alpha share their determinant.
  static constexpr double kNotOriented = -2.0;
  [[nodiscard]] double checked_quality(const std::array<int, 3>& t) const {
    const Vec &a = pt(t[0]), &b = pt(t[1]), &c = pt(t[2]);
    if (metric_) return orient2d(a, b, c) > 0 ? quality(t) : kNotOriented;
    constexpr double kEps = std::numeric_limits<double>::epsilon() / 2.0;
    constexpr double kErrBound = (3.0 + 16.0 * kEps) * kEps;  // as in front2d::orient2d
    const double left = (a.x() - c.x()) * (b.y() - c.y());
    const double right = (a.y() - c.y()) * (b.x() - c.x());
    const double det = left - right;
    if (!(det > kErrBound * (std::abs(left) + std::abs(right))) && orient2d(a, b, c) <= 0) return kNotOriented;
    const double sq = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
    return sq > 0 ? 2.0 * kSqrt3 * det / sq : 0.0;
  }
  [[nodiscard]] double max_cos(const std::array<int, 3>& t) const {
    if (metric_) return max_cos_in_metric(pt(t[0]), pt(t[1]), pt(t[2]), tri_metric(t));
    return max_cos_in_metric(pt(t[0]), pt(t[1]), pt(t[2]), Mat::Identity());
  }
  // Whether t has an angle whose cosine exceeds sqrt(cos2) (cheap: no square roots).
  [[nodiscard]] bool has_small_angle(const std::array<int, 3>& t, double cos2) const {
    const Vec& a = pt(t[0]);
    const Vec& b = pt(t[1]);
    const Vec& c = pt(t[2]);
    const Vec ab = b - a, bc = c - b, ca = a - c;
    if (metric_) {
      const Mat M = tri_metric(t);
      const Vec Mab = M * ab, Mbc = M * bc, Mca = M * ca;
      const double lab = ab.dot(Mab), lbc = bc.dot(Mbc), lca = ca.dot(Mca);
      const double da = -ca.dot(Mab), db = -ab.dot(Mbc), dc = -bc.dot(Mca);
      return (da > 0 && da * da > cos2 * lca * lab) || (db > 0 && db * db > cos2 * lab * lbc) ||
             (dc > 0 && dc * dc > cos2 * lbc * lca);
    }
    const double lab = ab.squaredNorm(), lbc = bc.squaredNorm(), lca = ca.squaredNorm();
    const double da = -ca.dot(ab), db = -ab.dot(bc), dc = -bc.dot(ca);
    return (da > 0 && da * da > cos2 * lca * lab) || (db > 0 && db * db > cos2 * lab * lbc) ||
           (dc > 0 && dc * dc > cos2 * lbc * lca);
  }
  // Delaunay criterion of the edge ab shared by (a, b, c) and (b, a, d): d strictly inside
  // the circumcircle of abc; with a metric, in the image of the quad under the Cholesky
  // factor of the mean tensor of its four vertices.
  [[nodiscard]] bool should_swap(int a, int b, int c, int d) const {
    if (!metric_) return clearly_in_circle(pt(a), pt(b), pt(c), pt(d));
    const Mat R = detail::cholesky_upper((mv(a) + mv(b) + mv(c) + mv(d)) * 0.25);
    return clearly_in_circle(R * pt(a), R * pt(b), R * pt(c), R * pt(d));
  }
  // d inside the circle of the counter-clockwise abc by more than the relative margin
  // tolerance::kIncircleRelative (so that near-cocircular quads never ping-pong). Evaluated in double
  // relative to d: its rounding error, about 1e-15 of the scale, is far below the margin.
  [[nodiscard]] static bool clearly_in_circle(const Vec& a, const Vec& b, const Vec& c, const Vec& d) {
    const Vec ad = a - d, bd = b - d, cd = c - d;
    const double det = ad.squaredNorm() * (bd.x() * cd.y() - cd.x() * bd.y()) +
                       bd.squaredNorm() * (cd.x() * ad.y() - ad.x() * cd.y()) +
                       cd.squaredNorm() * (ad.x() * bd.y() - bd.x() * ad.y());
    const double scale = std::max((a - b).squaredNorm(), (c - d).squaredNorm());
    return det > tolerance::kIncircleRelative * scale * scale;
  }
  // The smoothing target of vtx: the mean of its neighbours (each counted once per incident
  // triangle). With a metric that varies over the star, the point x minimising
  // sum_j |x - x_j|^2 in the tensors (M_v + M_j) / 2, which is the mean for a constant one.
  [[nodiscard]] Vec smoothing_target(int vtx, const Incidence& inc) const {
    const auto vi = static_cast<std::size_t>(vtx);
    const int b0 = inc.start[vi], b1 = inc.start[vi + 1];
    bool constant = true;
    Vec sum = Vec::Zero();
    for (int k = b0; k < b1; ++k)
      for (int x : T_[static_cast<std::size_t>(inc.tri[static_cast<std::size_t>(k)])])
        if (x != vtx) {
          sum += pt(x);
          if (metric_) constant = constant && mv(x) == mv(vtx);
        }
    if (constant) return sum / (2.0 * (b1 - b0));
    Mat S = Mat::Zero();
    Vec rhs = Vec::Zero();
    for (int k = b0; k < b1; ++k)
      for (int x : T_[static_cast<std::size_t>(inc.tri[static_cast<std::size_t>(k)])])
        if (x != vtx) {
          const Mat W = 0.5 * (mv(x) + mv(vtx));
          S += W;
          rhs += W * pt(x);
        }
    return S.llt().solve(rhs);
  }
  void set_nb(int s, int o) {
    N_[static_cast<std::size_t>(s)] = o;
    if (o >= 0) N_[static_cast<std::size_t>(o)] = s;
  }
  // Swaps the diagonal of slot s (edge a->b of t = (a, b, c), twin in u = (b, a, d)).
  void flip(int s) {
    const int o = N_[static_cast<std::size_t>(s)];
    const int t = s / 3, u = o / 3;
    const int a = v(s), b = v(nxt(s)), c = v(prv(s)), d = v(prv(o));
    const int n_bc = N_[static_cast<std::size_t>(nxt(s))], n_ca = N_[static_cast<std::size_t>(prv(s))];
    const int n_ad = N_[static_cast<std::size_t>(nxt(o))], n_db = N_[static_cast<std::size_t>(prv(o))];
    const bool c_bc = C_[static_cast<std::size_t>(nxt(s))], c_ca = C_[static_cast<std::size_t>(prv(s))];
    const bool c_ad = C_[static_cast<std::size_t>(nxt(o))], c_db = C_[static_cast<std::size_t>(prv(o))];
    T_[static_cast<std::size_t>(t)] = {c, a, d};
    T_[static_cast<std::size_t>(u)] = {d, b, c};
    const int t0 = 3 * t, u0 = 3 * u;
    set_nb(t0 + 0, n_ca); C_[static_cast<std::size_t>(t0)] = c_ca;
    set_nb(t0 + 1, n_ad); C_[static_cast<std::size_t>(t0 + 1)] = c_ad;
    set_nb(u0 + 0, n_db); C_[static_cast<std::size_t>(u0)] = c_db;
    set_nb(u0 + 1, n_bc); C_[static_cast<std::size_t>(u0 + 1)] = c_bc;
    set_nb(t0 + 2, u0 + 2);
    C_[static_cast<std::size_t>(t0 + 2)] = false;
    C_[static_cast<std::size_t>(u0 + 2)] = false;
  }

  std::vector<Vec>& P_;
  std::vector<std::array<int, 3>>& T_;
  const Metric* metric_;
  std::vector<Mat> Mv_;  // per vertex tensor (empty without a metric)
  std::uint64_t clock_ = 0;              // counts the moves
  std::vector<std::uint64_t> moved_at_;  // per vertex: clock_ at its last kept move (mark_moved), 0 = never moved
  struct NoSwap {
    std::array<int, 4> q{-1, -1, -1, -1};  // the quad (a, b, c, d) found not to need a swap
    std::uint64_t at = 0;                  // clock_ then
  };
  std::vector<NoSwap> no_swap_;  // per slot (delaunay_swaps)
  std::vector<int> N_;
  std::vector<bool> C_;
  std::vector<int> cavity_;       // refinement scratch
  std::vector<int> legal_stack_;  // refinement scratch
  std::vector<int> seg_stack_;    // refinement scratch
};

}  // namespace

void FrontOptions::validate() const {
  sizing.validate();
  if (!(work_budget_factor >= 1.0) || !std::isfinite(work_budget_factor))
    throw InvalidInput("FrontOptions: work_budget_factor must be >= 1");
  if (smoothing_passes < 0) throw InvalidInput("FrontOptions: smoothing_passes must be >= 0");
  if (!(hull_gap_fraction >= 0.0 && hull_gap_fraction < 1.0)) throw InvalidInput("FrontOptions: hull_gap_fraction must be in [0, 1)");
  if (!(corner_split_angle_deg > 0.0 && corner_split_angle_deg <= 180.0))
    throw InvalidInput("FrontOptions: corner_split_angle_deg must be in (0, 180]");
}

double triangle_alpha_2d(const Vec& a, const Vec& b, const Vec& c) { return alpha(a, b, c); }

double triangle_alpha_in_metric(const Vec& a, const Vec& b, const Vec& c, const Mat& M) { return alpha_in_metric(a, b, c, M); }

double triangle_min_angle_in_metric_deg(const Vec& a, const Vec& b, const Vec& c, const Mat& M) {
  return std::acos(std::clamp(max_cos_in_metric(a, b, c, M), -1.0, 1.0)) * 180.0 / std::numbers::pi;
}

Mat triangle_metric(const Metric& metric, const Vec& a, const Vec& b, const Vec& c) {
  return (metric.tensor(a) + metric.tensor(b) + metric.tensor(c)) / 3.0;
}

Mesh2d mesh_pslg(const Pslg& pslg, const FrontOptions& options) {
  options.validate();
  if (options.sizing.kind == SizingField::Kind::PerVertex && options.sizing.vertex_sizes.size() != pslg.points.size())
    throw InvalidInput("FrontOptions: per-vertex sizing needs one size per PSLG point (" +
                       std::to_string(options.sizing.vertex_sizes.size()) + " for " + std::to_string(pslg.points.size()) + ")");
  if (pslg.points.empty()) throw InvalidInput("PSLG: empty (no points)");
  Vec lo = pslg.points[0], hi = pslg.points[0];
  for (const auto& p : pslg.points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  std::optional<Sizing> sizing;  // built once the input is validated (the hull gap may need it first)
  const auto sized = [&]() -> const Sizing& {
    if (!sizing) sizing.emplace(options.sizing, pslg.points, lo, hi);
    return *sizing;
  };
  std::function<double(const Vec&)> hull_gap;
  if (options.hull_gap_fraction > 0) hull_gap = [&](const Vec& x) { return options.hull_gap_fraction * sized()(x); };
  const detail::Domain dom = detail::build_domain(pslg, options.enclose_convex_hull || pslg.segments.empty(), hull_gap);
  Stopwatch clock;
  Mesh2d mesh;
  auto& P = mesh.points;
  P = pslg.points;
  const Sizing& size = sized();
  const Metric* metric = options.metric.get();

  // Split segments.
  std::vector<std::vector<int>> chains(dom.segments.size());
  for (std::size_t k = 0; k < dom.segments.size(); ++k) {
    const int a = dom.segments[k][0], b = dom.segments[k][1];
    auto& ch = chains[k];
    ch.push_back(a);
    if (options.split_segments) {
      const Vec A = P[static_cast<std::size_t>(a)], B = P[static_cast<std::size_t>(b)];
      std::array<double, kSegmentSamples + 1> cum{};
      for (int i = 0; i < kSegmentSamples; ++i) {
        const Vec x = A + (B - A) * ((i + 0.5) / kSegmentSamples);
        cum[static_cast<std::size_t>(i + 1)] = cum[static_cast<std::size_t>(i)] + metric_length(metric, x, (B - A) / kSegmentSamples) / size(x);
      }
      const double total = cum.back();
      const int n = std::max(1, static_cast<int>(std::lround(total)));
      int i = 0;
      for (int j = 1; j < n; ++j) {
        const double target = total * j / n;
        while (i < kSegmentSamples - 1 && cum[static_cast<std::size_t>(i + 1)] < target) ++i;
        const double span = cum[static_cast<std::size_t>(i + 1)] - cum[static_cast<std::size_t>(i)];
        const double f = (i + (span > 0 ? (target - cum[static_cast<std::size_t>(i)]) / span : 0.0)) / kSegmentSamples;
        ch.push_back(static_cast<int>(P.size()));
        P.push_back(A + f * (B - A));
      }
    }
    ch.push_back(b);
  }
  const int first_free = static_cast<int>(P.size());
  std::vector<std::array<int, 2>> slide(P.size(), {-1, -1});  // split point -> its segment's endpoints
  for (std::size_t k = 0; k < dom.segments.size(); ++k)
    for (std::size_t i = 1; i + 1 < chains[k].size(); ++i) slide[static_cast<std::size_t>(chains[k][i])] = dom.segments[k];

  // Initial front, constraint edges and region markers of each side.
  std::unordered_map<std::uint64_t, int> constraints;  // constrained piece -> its domain segment
  std::unordered_map<std::uint64_t, int> side_marker;
  std::vector<std::array<int, 2>> front0;
  double area2 = 0;
  for (std::size_t k = 0; k < dom.segments.size(); ++k) {
    const auto& ch = chains[k];
    for (std::size_t i = 0; i + 1 < ch.size(); ++i) {
      const int u = ch[i], w = ch[i + 1];
      constraints[ukey(u, w)] = static_cast<int>(k);
      const Vec& U = P[static_cast<std::size_t>(u)];
      const Vec& W = P[static_cast<std::size_t>(w)];
      const Vec rel = 0.5 * (U + W) - lo;
      if (dom.side_in[k][0]) {
        front0.push_back({u, w});
        side_marker[dkey(u, w)] = dom.side_marker[k][0];
        area2 += rel.x() * (W.y() - U.y()) - rel.y() * (W.x() - U.x());
      }
      if (dom.side_in[k][1]) {
        front0.push_back({w, u});
        side_marker[dkey(w, u)] = dom.side_marker[k][1];
        area2 -= rel.x() * (W.y() - U.y()) - rel.y() * (W.x() - U.x());
      }
    }
  }
  mesh.report.domain_area = 0.5 * area2;
  mesh.report.n_dropped_points = dom.n_dropped_points;
  mesh.report.n_hull_edges_followed = dom.n_hull_edges_followed;
  mesh.report.hull_gap_area = dom.hull_gap_area;
  {
    std::unordered_set<int> nodes;
    for (const auto& e : front0) nodes.insert(e[0]);
    mesh.report.n_boundary_nodes = nodes.size();
  }
  // Expected size of the output, for the grid, the work budget and progress.
  double expected = 0;
  {
    constexpr int kSamples = 32;
    const Vec ext = hi - lo;
    if (options.sizing.kind == SizingField::Kind::Uniform) {
      // Every sample has the same size: the same term added as often, in the same order.
      const double hx = size(lo);
      const double term = 1.0 / (kSqrt3 / 4.0 * hx * hx);
      for (int k = 0; k < kSamples * kSamples; ++k) expected += term;
    } else {
      for (int j = 0; j < kSamples; ++j)
        for (int i = 0; i < kSamples; ++i) {
          const Vec x = lo + Vec((i + 0.5) * ext.x() / kSamples, (j + 0.5) * ext.y() / kSamples);
          const double hx = size(x);
          expected += 1.0 / (kSqrt3 / 4.0 * hx * hx);
        }
    }
    expected *= std::abs(mesh.report.domain_area) / (kSamples * kSamples);
  }
  double mean_edge = 0;
  for (const auto& e : front0) mean_edge += (P[static_cast<std::size_t>(e[0])] - P[static_cast<std::size_t>(e[1])]).norm();
  mean_edge /= static_cast<double>(std::max<std::size_t>(1, front0.size()));
  const double typical = std::max(mean_edge, std::sqrt(std::abs(mesh.report.domain_area) / std::max(1.0, expected)));
  const double margin = 1e-3 * (hi - lo).norm();
  const auto budget = static_cast<std::size_t>(options.work_budget_factor * (expected + 10.0 * static_cast<double>(front0.size())) + 1000.0);
  {  // the front's grid, heap and edges are released before the optimisation
    EdgeGrid grid(lo - Vec::Constant(margin), hi + Vec::Constant(margin), typical);
    AdvancingFront front(P, size, metric, std::move(grid), options.corner_split_angle_deg);
    // About `expected` triangles and half as many points: reserve so that the arrays are not
    // copied while they grow (capped, in case the estimate is far off).
    const auto hint = static_cast<std::size_t>(std::min(1.05 * expected + 16.0, 1e8));
    front.triangles().reserve(hint);
    P.reserve(P.size() + hint / 2 + 16);
    for (const auto& e : front0) front.add_boundary_edge(e[0], e[1]);
    for (int p : dom.isolated_points) front.add_isolated_point(p);
    report_progress(options.progress, "front2d: front", 0.0);
    mesh.report.n_open_edges = front.run(budget, static_cast<std::size_t>(2 * expected), options.progress, mesh.report);
    mesh.triangles = std::move(front.triangles());
  }
  mesh.report.seconds_front = clock.seconds();
  if (mesh.report.n_open_edges > 0) {
    mesh.report.status = FrontStatus::Incomplete;
    mesh.report.message = std::to_string(mesh.report.n_open_edges) + " front edges could not be closed";
  }

  clock.restart();
  report_progress(options.progress, "front2d: optimise", 0.0);
  slide.resize(P.size(), {-1, -1});  // the front's points are free
  Optimiser opt(P, mesh.triangles, constraints, first_free, metric);
  if (options.swap_edges) mesh.report.n_swaps += opt.delaunay_swaps();
  if (options.smoothing_passes > 0) {
    opt.smooth(options.smoothing_passes, first_free);
    if (options.swap_edges) mesh.report.n_swaps += opt.delaunay_swaps();
    for (int round = 0; round < kRelocateRounds; ++round) {
      if (opt.improve_min_angle(first_free, slide) == 0) break;
      if (options.swap_edges) mesh.report.n_swaps += opt.delaunay_swaps();
    }
  }
  if (options.refine_min_angle && options.split_segments && !metric) {
    RefineContext rc;
    rc.pieces = &constraints;
    rc.chains = &chains;
    rc.slide = &slide;
    rc.side_marker = &side_marker;
    rc.segments = &dom.segments;
    rc.acute = acute_vertices(pslg.points, dom.segments);
    rc.n_input = static_cast<int>(pslg.points.size());
    rc.min_length = tolerance::kRefineMinLengthRelative * (hi - lo).norm();
    rc.size = &size;
    rc.max_points = static_cast<std::size_t>(kRefineMaxPointsFactor * static_cast<double>(mesh.triangles.size())) + 1000;
    const auto relocate = [&]() {
      for (int round = 0; round < kRelocateRounds; ++round) {
        if (opt.improve_min_angle(first_free, slide, true) == 0) break;
        mesh.report.n_swaps += opt.delaunay_swaps();
      }
    };
    mesh.report.n_refinement_points = opt.refine(rc);
    if (mesh.report.n_refinement_points > 0 && options.smoothing_passes > 0) {
      // Smoothing of the refined mesh (the refinement's graded points), keeping good triangles
      // good and bad ones no worse, then the relocation.
      opt.smooth(options.smoothing_passes, first_free, &slide, true);
      mesh.report.n_swaps += opt.delaunay_swaps();
      relocate();
    }
  }
  mesh.triangle_regions = opt.regions(side_marker);
  std::vector<bool> is_hull(dom.segments.size(), true);  // the convex hull edges added (enclose_convex_hull)
  for (int k : dom.input_segment) is_hull[static_cast<std::size_t>(k)] = false;
  mesh.report.seconds_optimise = clock.seconds();
  report_progress(options.progress, "front2d: optimise", 1.0);

  // Chains of the input segments, oriented as given.
  for (std::size_t k = 0; k < pslg.segments.size(); ++k) {
    const auto& ch = chains[static_cast<std::size_t>(dom.input_segment[k])];
    mesh.segment_chains.push_back(ch);
    if (ch.front() != pslg.segments[k][0]) std::reverse(mesh.segment_chains.back().begin(), mesh.segment_chains.back().end());
  }
  for (std::size_t k = 0; k < dom.segments.size(); ++k)
    if (is_hull[k]) mesh.hull_chains.push_back(chains[k]);
  return mesh;
}

void write_triangle_files(const Mesh2d& mesh, const std::filesystem::path& stem) {
  auto node = stem;
  node += ".node";
  auto ele = stem;
  ele += ".ele";
  std::ofstream n(node);
  if (!n) throw IoError("cannot write '" + node.string() + "'");
  n.precision(17);
  n << mesh.points.size() << " 2 0 0\n";
  for (std::size_t i = 0; i < mesh.points.size(); ++i) n << i << ' ' << mesh.points[i].x() << ' ' << mesh.points[i].y() << '\n';
  std::ofstream e(ele);
  if (!e) throw IoError("cannot write '" + ele.string() + "'");
  e << mesh.triangles.size() << " 3 1\n";
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    const auto& t = mesh.triangles[i];
    e << i << ' ' << t[0] << ' ' << t[1] << ' ' << t[2] << ' ' << (i < mesh.triangle_regions.size() ? mesh.triangle_regions[i] : 0) << '\n';
  }
  if (!n || !e) throw IoError("failed writing '" + stem.string() + ".node/.ele'");
}

}  // namespace nurbsfront
