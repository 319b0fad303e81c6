// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! The first fundamental form of a height field as a front2d Metric: the 2D front then
//! measures 3D lengths of steps in the plane (DESIGN.md, Pitfalls: I + grad f grad f^T).

#include "nurbsfront/front2d/sizing.h"
#include "nurbsfront/nurbs/height_field.h"

namespace nurbsfront {

//! Metric tensor I + grad f grad f^T of z = f(x, y); refers to the field (keep it alive).
class HeightFieldMetric final : public Metric {
 public:
  explicit HeightFieldMetric(const BicubicHeightField& field) : field_(&field) {}
  [[nodiscard]] Eigen::Matrix2d tensor(const Eigen::Vector2d& x) const override { return field_->metric(x.x(), x.y()); }

 private:
  const BicubicHeightField* field_;
};

}  // namespace nurbsfront
