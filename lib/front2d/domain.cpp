// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/front2d/domain.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <set>
#include <sstream>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include "nurbsfront/core/error.h"
#include "nurbsfront/front2d/predicates.h"

namespace nurbsfront::detail {
namespace {

using Vec = Eigen::Vector2d;
using front2d::orient2d;

std::string fmt(const Vec& p) {
  std::ostringstream s;
  s.precision(17);
  s << "(" << p.x() << ", " << p.y() << ")";
  return s.str();
}

bool finite(const Vec& p) { return std::isfinite(p.x()) && std::isfinite(p.y()); }

std::uint64_t undirected_key(int a, int b) {
  const auto lo = static_cast<std::uint64_t>(std::min(a, b));
  const auto hi = static_cast<std::uint64_t>(std::max(a, b));
  return (lo << 32) | hi;
}

// Whether q lies inside or on the closed polygon `poly` (winding number, exact orientations).
bool in_closed_polygon(const std::vector<Vec>& P, const std::vector<int>& poly, const Vec& q) {
  int winding = 0;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vec& u = P[static_cast<std::size_t>(poly[i])];
    const Vec& w = P[static_cast<std::size_t>(poly[(i + 1) % poly.size()])];
    if (front2d::segments_intersect(u, w, q, q)) return true;
    const int side = orient2d(u, w, q);
    if (u.y() <= q.y()) {
      if (w.y() > q.y() && side > 0) ++winding;
    } else if (w.y() <= q.y() && side < 0) {
      --winding;
    }
  }
  return winding != 0;
}

// Whether the input segments join hull vertex a to hull vertex b (along the hull edge ab)
// through points that all lie closer to the edge than gap(point), with no other input point
// in the strip between the edge and that path. Then the edge is left out and the path bounds
// the domain there; `area` gets the strip's area.
bool hull_edge_follows_input(const std::vector<Vec>& P, const std::vector<std::vector<int>>& adjacent, int a, int b,
                             const std::function<double(const Vec&)>& gap, double& area) {
  const Vec& A = P[static_cast<std::size_t>(a)];
  const Vec& B = P[static_cast<std::size_t>(b)];
  std::unordered_map<int, int> parent;  // near point -> the point it was reached from (a: -1, not reached: -2)
  parent[a] = -1;
  std::vector<int> stack = {a};
  while (!stack.empty() && !parent.count(b)) {
    const int u = stack.back();
    stack.pop_back();
    for (int w : adjacent[static_cast<std::size_t>(u)]) {
      if (parent.count(w)) continue;
      const Vec& x = P[static_cast<std::size_t>(w)];
      if (w != b && !(distance_to_segment(x, A, B) < gap(x))) continue;
      parent[w] = u;
      stack.push_back(w);
    }
  }
  if (!parent.count(b)) return false;
  std::vector<int> strip = {a};  // a, b, then the path back to a
  for (int v = b; v != a; v = parent[v]) strip.push_back(v);
  double depth = 0;
  area = 0;  // shoelace relative to A (the edge a -> b adds nothing)
  for (std::size_t i = 1; i < strip.size(); ++i) {
    const Vec p = P[static_cast<std::size_t>(strip[i])] - A;
    const Vec q = P[static_cast<std::size_t>(strip[(i + 1) % strip.size()])] - A;
    area += 0.5 * (p.x() * q.y() - p.y() * q.x());
    depth = std::max(depth, distance_to_segment(P[static_cast<std::size_t>(strip[i])], A, B));
  }
  area = std::abs(area);
  std::unordered_set<int> on_path(strip.begin(), strip.end());
  for (std::size_t i = 0; i < P.size(); ++i)
    if (!on_path.count(static_cast<int>(i)) && distance_to_segment(P[i], A, B) <= depth && in_closed_polygon(P, strip, P[i]))
      return false;
  return true;
}

// Convex hull edges (counter-clockwise), split at every point lying exactly on them. With a
// gap function, an edge that the input follows within the gap (hull_edge_follows_input) is
// left out; `removed` counts those edges and `removed_area` adds their strips' areas.
std::vector<std::array<int, 2>> hull_edges(const std::vector<Vec>& P, const std::vector<std::array<int, 2>>& input,
                                           const std::function<double(const Vec&)>& gap, std::size_t& removed,
                                           double& removed_area) {
  std::vector<int> order(P.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int i, int j) {
    return P[i].x() < P[j].x() || (P[i].x() == P[j].x() && P[i].y() < P[j].y());
  });
  std::vector<int> h(2 * order.size() + 1);
  std::size_t k = 0;
  for (int i : order) {
    while (k >= 2 && orient2d(P[h[k - 2]], P[h[k - 1]], P[i]) <= 0) --k;
    h[k++] = i;
  }
  for (std::size_t t = order.size() - 1, lower = k + 1; t-- > 0;) {
    const int i = order[t];
    while (k >= lower && orient2d(P[h[k - 2]], P[h[k - 1]], P[i]) <= 0) --k;
    h[k++] = i;
  }
  h.resize(k - 1);
  std::vector<std::vector<int>> adjacent;
  if (gap) {
    adjacent.resize(P.size());
    for (const auto& s : input) {
      adjacent[static_cast<std::size_t>(s[0])].push_back(s[1]);
      adjacent[static_cast<std::size_t>(s[1])].push_back(s[0]);
    }
  }
  std::vector<std::array<int, 2>> edges;
  for (std::size_t e = 0; e < h.size(); ++e) {
    const int a = h[e];
    const int b = h[(e + 1) % h.size()];
    double area = 0;
    const bool is_input = gap && std::find(adjacent[static_cast<std::size_t>(a)].begin(),
                                           adjacent[static_cast<std::size_t>(a)].end(), b) != adjacent[static_cast<std::size_t>(a)].end();
    if (gap && !is_input && hull_edge_follows_input(P, adjacent, a, b, gap, area)) {
      ++removed;
      removed_area += area;
      continue;
    }
    std::vector<std::pair<double, int>> on;
    const Vec d = P[b] - P[a];
    for (std::size_t i = 0; i < P.size(); ++i) {
      const int ii = static_cast<int>(i);
      if (ii == a || ii == b || orient2d(P[a], P[b], P[i]) != 0) continue;
      const double t = (P[i] - P[a]).dot(d);
      if (t > 0 && t < d.squaredNorm()) on.emplace_back(t, ii);
    }
    std::sort(on.begin(), on.end());
    int prev = a;
    for (const auto& [t, i] : on) {
      edges.push_back({prev, i});
      prev = i;
    }
    edges.push_back({prev, b});
  }
  return edges;
}

// Rejects crossing/overlapping segments and points inside segments (sweep over x).
void check_crossings(const std::vector<Vec>& P, const std::vector<std::array<int, 2>>& S,
                     const std::vector<int>& lone_points) {
  struct Item {
    double xmin, xmax, ymin, ymax;
    int a, b;
  };
  std::vector<Item> items;
  items.reserve(S.size() + lone_points.size());
  for (const auto& s : S) {
    const Vec& p = P[s[0]];
    const Vec& q = P[s[1]];
    items.push_back({std::min(p.x(), q.x()), std::max(p.x(), q.x()), std::min(p.y(), q.y()), std::max(p.y(), q.y()), s[0], s[1]});
  }
  for (int i : lone_points) items.push_back({P[i].x(), P[i].x(), P[i].y(), P[i].y(), i, i});
  std::sort(items.begin(), items.end(), [](const Item& l, const Item& r) { return l.xmin < r.xmin; });
  for (std::size_t i = 0; i < items.size(); ++i) {
    const Item& u = items[i];
    for (std::size_t j = i + 1; j < items.size() && items[j].xmin <= u.xmax; ++j) {
      const Item& v = items[j];
      if (v.ymin > u.ymax || v.ymax < u.ymin) continue;
      const bool u_pt = u.a == u.b;
      const bool v_pt = v.a == v.b;
      if (u_pt && v_pt) continue;  // distinct points (duplicates were rejected)
      if (u_pt || v_pt) {
        const Item& s = u_pt ? v : u;
        const int q = u_pt ? u.a : v.a;
        if (front2d::segments_intersect(P[s.a], P[s.b], P[q], P[q]))
          throw InvalidInput("PSLG: point " + std::to_string(q) + " " + fmt(P[q]) + " lies on segment (" +
                             std::to_string(s.a) + ", " + std::to_string(s.b) + ")");
        continue;
      }
      int shared = -1;
      int x = -1;
      int y = -1;
      if (u.a == v.a) { shared = u.a; x = u.b; y = v.b; }
      else if (u.a == v.b) { shared = u.a; x = u.b; y = v.a; }
      else if (u.b == v.a) { shared = u.b; x = u.a; y = v.b; }
      else if (u.b == v.b) { shared = u.b; x = u.a; y = v.a; }
      bool bad = false;
      if (shared >= 0) {
        bad = orient2d(P[shared], P[x], P[y]) == 0 && (P[x] - P[shared]).dot(P[y] - P[shared]) > 0;
      } else {
        bad = front2d::segments_intersect(P[u.a], P[u.b], P[v.a], P[v.b]);
      }
      if (bad)
        throw InvalidInput("PSLG: segments (" + std::to_string(u.a) + ", " + std::to_string(u.b) + ") and (" +
                           std::to_string(v.a) + ", " + std::to_string(v.b) + ") cross or overlap");
    }
  }
}

class Arrangement {
 public:
  Arrangement(const std::vector<Vec>& P, const std::vector<std::array<int, 2>>& S) : P_(P), S_(S) {
    // Outgoing half-edges per vertex in compressed rows (in the order a vector per vertex
    // would receive them: no allocation per vertex), then sorted around it.
    out_start_.assign(P.size() + 1, 0);
    for (const auto& sg : S) {
      ++out_start_[static_cast<std::size_t>(sg[0]) + 1];
      ++out_start_[static_cast<std::size_t>(sg[1]) + 1];
    }
    for (std::size_t v = 0; v < P.size(); ++v) out_start_[v + 1] += out_start_[v];
    out_.resize(2 * S.size());
    {
      std::vector<int> fill(out_start_.begin(), out_start_.end() - 1);
      for (std::size_t k = 0; k < S.size(); ++k) {
        out_[static_cast<std::size_t>(fill[static_cast<std::size_t>(S[k][0])]++)] = static_cast<int>(2 * k);
        out_[static_cast<std::size_t>(fill[static_cast<std::size_t>(S[k][1])]++)] = static_cast<int>(2 * k + 1);
      }
    }
    pos_.assign(2 * S.size(), 0);
    for (std::size_t v = 0; v < P.size(); ++v) {
      const auto first = out_.begin() + out_start_[v], last = out_.begin() + out_start_[v + 1];
      std::sort(first, last, [&](int h1, int h2) { return ccw_less(static_cast<int>(v), h1, h2); });
      for (auto it = first; it != last; ++it) pos_[static_cast<std::size_t>(*it)] = static_cast<int>(it - first);
    }
    // Cycles.
    cycle_.assign(2 * S.size(), -1);
    for (std::size_t h0 = 0; h0 < cycle_.size(); ++h0) {
      if (cycle_[h0] >= 0) continue;
      const int c = static_cast<int>(n_cycles_++);
      int h = static_cast<int>(h0);
      double area = 0.0;
      bool all_twins = true;
      const Vec& o = P[origin(h)];
      std::vector<int> members;
      int leftmost = origin(h);
      while (cycle_[static_cast<std::size_t>(h)] < 0) {
        cycle_[static_cast<std::size_t>(h)] = c;
        members.push_back(h);
        const Vec p = P[origin(h)] - o;
        const Vec q = P[dest(h)] - o;
        area += p.x() * q.y() - p.y() * q.x();
        const Vec& l = P[leftmost];
        const Vec& cand = P[origin(h)];
        if (cand.x() < l.x() || (cand.x() == l.x() && cand.y() < l.y())) leftmost = origin(h);
        h = next(h);
      }
      for (int m : members) all_twins = all_twins && cycle_[static_cast<std::size_t>(m ^ 1)] == c;
      outer_.push_back(!all_twins && area > 0.0);
      leftmost_.push_back(leftmost);
    }
    face_.assign(n_cycles_, kUnresolved);
    for (std::size_t c = 0; c < n_cycles_; ++c)
      if (outer_[c]) face_[c] = n_faces_++;
  }

  [[nodiscard]] int origin(int h) const { return S_[static_cast<std::size_t>(h >> 1)][static_cast<std::size_t>(h & 1)]; }
  [[nodiscard]] int dest(int h) const { return S_[static_cast<std::size_t>(h >> 1)][static_cast<std::size_t>(1 - (h & 1))]; }
  [[nodiscard]] int n_faces() const { return n_faces_; }

  //! Face of the half-edge's left side; -1 for the unbounded face.
  int face_of_halfedge(int h) { return face_of_cycle(cycle_[static_cast<std::size_t>(h)]); }

  //! Face containing the point; -1 outside.
  int locate(const Vec& q, int skip_vertex = -1) {
    const int h = ray_hit(q, skip_vertex);
    return h < 0 ? -1 : face_of_halfedge(h);
  }

 private:
  static constexpr int kUnresolved = -2;

  int next(int h) const {
    const auto v = static_cast<std::size_t>(dest(h));
    const int i = pos_[static_cast<std::size_t>(h ^ 1)];
    const int n = out_start_[v + 1] - out_start_[v];
    return out_[static_cast<std::size_t>(out_start_[v] + (i - 1 + n) % n)];
  }

  bool ccw_less(int v, int h1, int h2) const {
    auto half = [&](int h) {
      const Vec& c = P_[v];
      const Vec& d = P_[dest(h)];
      return (d.y() > c.y() || (d.y() == c.y() && d.x() > c.x())) ? 0 : 1;
    };
    const int s1 = half(h1);
    const int s2 = half(h2);
    if (s1 != s2) return s1 < s2;
    return orient2d(P_[v], P_[dest(h1)], P_[dest(h2)]) > 0;
  }

  int face_of_cycle(int c) {
    auto& f = face_[static_cast<std::size_t>(c)];
    if (f != kUnresolved) return f;
    const int h = ray_hit(P_[leftmost_[static_cast<std::size_t>(c)]], leftmost_[static_cast<std::size_t>(c)]);
    f = h < 0 ? -1 : face_of_cycle(cycle_[static_cast<std::size_t>(h)]);
    return f;
  }

  // Nearest segment hit by the ray from q towards -x; returns the half-edge whose left face
  // contains q. A hit exactly at a vertex z is resolved by the angular sector at z that
  // contains the direction +x (the left face of z's last outgoing half-edge in CCW order).
  int ray_hit(const Vec& q, int skip_vertex) const {
    double best_x = -std::numeric_limits<double>::infinity();
    int best = -1;         // segment hit in its interior
    int best_vertex = -1;  // or vertex hit
    auto consider_vertex = [&](int z) {
      const Vec& p = P_[static_cast<std::size_t>(z)];
      if (z == skip_vertex || p.y() != q.y() || p.x() >= q.x() || p.x() <= best_x) return;
      best_x = p.x();
      best = -1;
      best_vertex = z;
    };
    for (std::size_t k = 0; k < S_.size(); ++k) {
      const int ia = S_[k][0];
      const int ib = S_[k][1];
      consider_vertex(ia);
      consider_vertex(ib);
      if (ia == skip_vertex || ib == skip_vertex) continue;
      const Vec& s = P_[static_cast<std::size_t>(ia)];
      const Vec& t = P_[static_cast<std::size_t>(ib)];
      if (!((s.y() < q.y() && t.y() > q.y()) || (s.y() > q.y() && t.y() < q.y()))) continue;
      const double x = s.x() + (q.y() - s.y()) * (t.x() - s.x()) / (t.y() - s.y());
      if (x >= q.x() || x <= best_x) continue;
      best_x = x;
      best = static_cast<int>(2 * k);
      best_vertex = -1;
    }
    if (best_vertex >= 0) return out_[static_cast<std::size_t>(out_start_[static_cast<std::size_t>(best_vertex) + 1] - 1)];
    if (best < 0) return -1;
    const auto& seg = S_[static_cast<std::size_t>(best >> 1)];
    return orient2d(P_[static_cast<std::size_t>(seg[0])], P_[static_cast<std::size_t>(seg[1])], q) >= 0 ? best : best + 1;
  }

  const std::vector<Vec>& P_;
  const std::vector<std::array<int, 2>>& S_;
  std::vector<int> out_start_;  // per vertex: its first entry in out_ (one more entry at the end)
  std::vector<int> out_;        // outgoing half-edges, sorted counter-clockwise around each vertex
  std::vector<int> pos_;
  std::vector<int> cycle_;
  std::vector<bool> outer_;
  std::vector<int> leftmost_;
  std::vector<int> face_;
  std::size_t n_cycles_ = 0;
  int n_faces_ = 0;
};

}  // namespace

Domain build_domain(const Pslg& pslg, bool enclose_convex_hull, const std::function<double(const Vec&)>& hull_gap) {
  const auto& P = pslg.points;
  if (P.empty()) throw InvalidInput("PSLG: empty (no points)");
  for (std::size_t i = 0; i < P.size(); ++i)
    if (!finite(P[i])) throw InvalidInput("PSLG: point " + std::to_string(i) + " is not finite (NaN or inf)");
  for (const auto& h : pslg.holes)
    if (!finite(h)) throw InvalidInput("PSLG: a hole point is not finite (NaN or inf)");
  for (const auto& r : pslg.regions)
    if (!finite(r.point)) throw InvalidInput("PSLG: a region point is not finite (NaN or inf)");
  if (P.size() > static_cast<std::size_t>(std::numeric_limits<int>::max() / 4))
    throw InvalidInput("PSLG: too many points");
  {
    std::vector<int> order(P.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int i, int j) {
      return P[i].x() < P[j].x() || (P[i].x() == P[j].x() && P[i].y() < P[j].y());
    });
    for (std::size_t i = 1; i < order.size(); ++i)
      if (P[order[i]] == P[order[i - 1]])
        throw InvalidInput("PSLG: duplicate points " + std::to_string(std::min(order[i], order[i - 1])) + " and " +
                           std::to_string(std::max(order[i], order[i - 1])) + " at " + fmt(P[order[i]]));
  }
  bool has_area = false;
  for (std::size_t i = 2; i < P.size() && !has_area; ++i) has_area = orient2d(P[0], P[1], P[i]) != 0;
  if (!has_area) throw InvalidInput("PSLG: all points are collinear (fewer than 3 in general position): no area to mesh");

  Domain d;
  std::unordered_map<std::uint64_t, int> seen;
  const int n = static_cast<int>(P.size());
  for (std::size_t k = 0; k < pslg.segments.size(); ++k) {
    const auto& s = pslg.segments[k];
    if (s[0] < 0 || s[0] >= n || s[1] < 0 || s[1] >= n)
      throw InvalidInput("PSLG: segment " + std::to_string(k) + " has a point index out of range");
    if (s[0] == s[1]) throw InvalidInput("PSLG: segment " + std::to_string(k) + " joins a point to itself");
    auto [it, inserted] = seen.try_emplace(undirected_key(s[0], s[1]), static_cast<int>(d.segments.size()));
    if (inserted) d.segments.push_back(s);
    d.input_segment.push_back(it->second);
  }
  {
    std::vector<bool> on_input(P.size(), false);
    for (const auto& s : d.segments) on_input[static_cast<std::size_t>(s[0])] = on_input[static_cast<std::size_t>(s[1])] = true;
    std::vector<int> off_input;
    for (std::size_t i = 0; i < P.size(); ++i)
      if (!on_input[i]) off_input.push_back(static_cast<int>(i));
    // Hull edges cannot cross the input: only the input needs checking.
    check_crossings(P, d.segments, off_input);
  }
  if (enclose_convex_hull) {
    for (const auto& e : hull_edges(P, d.segments, hull_gap, d.n_hull_edges_followed, d.hull_gap_area))
      if (seen.try_emplace(undirected_key(e[0], e[1]), static_cast<int>(d.segments.size())).second) d.segments.push_back(e);
  }
  std::vector<bool> on_segment(P.size(), false);
  for (const auto& s : d.segments) on_segment[static_cast<std::size_t>(s[0])] = on_segment[static_cast<std::size_t>(s[1])] = true;
  std::vector<int> lone;
  for (std::size_t i = 0; i < P.size(); ++i)
    if (!on_segment[i]) lone.push_back(static_cast<int>(i));
  if (d.segments.empty()) throw InvalidInput("PSLG: no segments (and enclose_convex_hull is off): no domain");

  Arrangement arr(P, d.segments);
  std::vector<bool> is_hole(static_cast<std::size_t>(arr.n_faces()), false);
  for (const auto& h : pslg.holes) {
    const int f = arr.locate(h);
    if (f < 0) throw InvalidInput("PSLG: hole point " + fmt(h) + " is outside the domain");
    is_hole[static_cast<std::size_t>(f)] = true;
  }
  std::vector<int> marker(static_cast<std::size_t>(arr.n_faces()), 0);
  for (const auto& r : pslg.regions) {
    const int f = arr.locate(r.point);
    if (f < 0) throw InvalidInput("PSLG: region point " + fmt(r.point) + " is outside the domain");
    marker[static_cast<std::size_t>(f)] = r.marker;
  }
  auto in_domain = [&](int f) { return f >= 0 && !is_hole[static_cast<std::size_t>(f)]; };
  bool any = false;
  for (std::size_t k = 0; k < d.segments.size(); ++k) {
    const int f0 = arr.face_of_halfedge(static_cast<int>(2 * k));
    const int f1 = arr.face_of_halfedge(static_cast<int>(2 * k + 1));
    d.side_in.push_back({in_domain(f0), in_domain(f1)});
    d.side_marker.push_back({f0 >= 0 ? marker[static_cast<std::size_t>(f0)] : 0, f1 >= 0 ? marker[static_cast<std::size_t>(f1)] : 0});
    any = any || in_domain(f0) || in_domain(f1);
  }
  // Hull edges left out can leave no bounded face (an open polyline within the gap of its
  // whole hull): then the exact hull is the domain, however thin.
  if (!any && d.n_hull_edges_followed > 0) return build_domain(pslg, enclose_convex_hull, {});
  if (!any) throw InvalidInput("PSLG: the domain is empty (no bounded face, or every face is a hole)");
  for (int i : lone) {
    if (in_domain(arr.locate(P[static_cast<std::size_t>(i)])))
      d.isolated_points.push_back(i);
    else
      ++d.n_dropped_points;
  }
  return d;
}

}  // namespace nurbsfront::detail
