// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/nurbs/projection.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Dense>

#include "nurbsfront/core/error.h"
#include "nurbsfront/core/tolerances.h"

namespace nurbsfront {
namespace {

// Halvings of a step before giving up on it.
constexpr int kMaxStepHalvings = 30;

// Distinct knot values inside the domain (span borders), for sampling.
std::vector<double> span_borders(const KnotVector& kv) {
  std::vector<double> b;
  for (std::size_t i = static_cast<std::size_t>(kv.degree); i <= kv.n_basis(); ++i) {
    if (b.empty() || kv.knots[i] > b.back()) b.push_back(kv.knots[i]);
  }
  return b;
}

std::vector<double> samples(const KnotVector& kv, int per_span) {
  const std::vector<double> b = span_borders(kv);
  std::vector<double> s;
  for (std::size_t k = 0; k + 1 < b.size(); ++k) {
    for (int i = 0; i < per_span; ++i) s.push_back(b[k] + (b[k + 1] - b[k]) * (i + 0.5) / per_span);
  }
  s.push_back(b.front());
  s.push_back(b.back());
  return s;
}

}  // namespace

void ProjectionOptions::validate() const {
  if (samples_per_span < 1) throw InvalidInput("ProjectionOptions: samples_per_span must be >= 1");
  if (max_iterations < 1) throw InvalidInput("ProjectionOptions: max_iterations must be >= 1");
  if (!(relative_tolerance > 0.0) || !std::isfinite(relative_tolerance)) {
    throw InvalidInput("ProjectionOptions: relative_tolerance must be positive and finite");
  }
  if (initial_guess && !initial_guess->allFinite()) throw InvalidInput("ProjectionOptions: initial guess is not finite");
}

ClosestPoint closest_point(const NurbsSurface& surface, const Eigen::Vector3d& query, const ProjectionOptions& options) {
  options.validate();
  if (!query.allFinite()) throw InvalidInput("closest_point: query point is not finite");
  const double u0 = surface.u.domain_min();
  const double u1 = surface.u.domain_max();
  const double v0 = surface.v.domain_min();
  const double v1 = surface.v.domain_max();

  Eigen::Vector3d lo = surface.control_points.front();
  Eigen::Vector3d hi = lo;
  for (const auto& p : surface.control_points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double step_tolerance = options.relative_tolerance * std::max((hi - lo).norm(), 1.0e-300);

  ClosestPoint best;

  double s = u0;
  double t = v0;
  if (options.initial_guess) {
    s = std::clamp(options.initial_guess->x(), u0, u1);
    t = std::clamp(options.initial_guess->y(), v0, v1);
  } else {
    double best_d2 = std::numeric_limits<double>::infinity();
    for (double ss : samples(surface.u, options.samples_per_span)) {
      for (double tt : samples(surface.v, options.samples_per_span)) {
        const double d2 = (surface.evaluate(ss, tt) - query).squaredNorm();
        if (d2 < best_d2) {
          best_d2 = d2;
          s = ss;
          t = tt;
        }
      }
    }
  }

  SurfaceDerivatives d = surface.derivatives(s, t);
  double f = 0.5 * (d.point - query).squaredNorm();
  best.converged = false;
  int it = 0;
  for (; it < options.max_iterations; ++it) {
    const Eigen::Vector3d r = d.point - query;
    const Eigen::Vector2d g(r.dot(d.su), r.dot(d.sv));
    Eigen::Matrix2d jtj;
    jtj << d.su.dot(d.su), d.su.dot(d.sv), d.su.dot(d.sv), d.sv.dot(d.sv);
    Eigen::Matrix2d h = jtj;
    h(0, 0) += r.dot(d.suu);
    h(0, 1) += r.dot(d.suv);
    h(1, 0) += r.dot(d.suv);
    h(1, 1) += r.dot(d.svv);
    // Active set: a parameter on its bound whose gradient pushes outwards stays there, and
    // the step is taken in the other parameter alone (projected Newton).
    const bool fix_u = (s <= u0 && g.x() > 0.0) || (s >= u1 && g.x() < 0.0);
    const bool fix_v = (t <= v0 && g.y() > 0.0) || (t >= v1 && g.y() < 0.0);
    if (fix_u && fix_v) {
      best.converged = true;  // a corner minimum
      break;
    }
    Eigen::Vector2d step = Eigen::Vector2d::Zero();
    if (fix_u || fix_v) {
      const int k = fix_u ? 1 : 0;
      const double curvature = h(k, k) > 0.0 ? h(k, k) : jtj(k, k);
      if (!(curvature > 0.0)) break;
      step[k] = -g[k] / curvature;
    } else {
      Eigen::LLT<Eigen::Matrix2d> llt(h);
      if (llt.info() == Eigen::Success) {
        step = -llt.solve(g);
      } else {
        Eigen::LLT<Eigen::Matrix2d> gn(jtj);
        if (gn.info() != Eigen::Success) break;  // degenerate point: keep what we have
        step = -gn.solve(g);
      }
    }
    if (!step.allFinite()) break;
    // Backtracking: halve until the distance decreases (clamped to the domain).
    double alpha = 1.0;
    bool moved = false;
    double ns = s;
    double nt = t;
    Eigen::Vector3d np;
    double nf = f;
    for (int k = 0; k < kMaxStepHalvings; ++k, alpha *= 0.5) {
      ns = std::clamp(s + alpha * step.x(), u0, u1);
      nt = std::clamp(t + alpha * step.y(), v0, v1);
      np = surface.evaluate(ns, nt);
      nf = 0.5 * (np - query).squaredNorm();
      if (nf <= f * (1.0 + tolerance::kDescentSlackRelative)) {
        moved = true;
        break;
      }
    }
    if (!moved) {
      best.converged = true;  // no descent possible: a (numerical) minimum
      break;
    }
    const double moved_by = (np - d.point).norm();
    s = ns;
    t = nt;
    f = nf;
    d = surface.derivatives(s, t);
    if (moved_by <= step_tolerance) {
      best.converged = true;
      ++it;
      break;
    }
  }
  best.u = s;
  best.v = t;
  best.point = d.point;
  best.distance = (d.point - query).norm();
  best.iterations = it;
  return best;
}

}  // namespace nurbsfront
