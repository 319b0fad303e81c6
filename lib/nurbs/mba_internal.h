// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Internal to the nurbs module: the least-squares polish's lattice products (mba.cpp), declared
// here so that tests can check them against the pass-by-pass products (not installed API).

#include <cstddef>
#include <vector>

namespace nurbsfront::mba_detail {

//! out += mu D^T D x + eps x for a coefficient lattice of nx x ny (row-major, nx, ny >= 4), D
//! the thin-plate second differences (xx and yy of three neighbours, the mixed one of a 2 x 2
//! block weighted by 2); returns the dot product of x and the new out (summed in index order).
//! Each element of out takes its terms in the order of the pass-by-pass product (all xx
//! terms, then yy, then mixed, then eps; the same expressions), so the result is that
//! product's bit for bit, in one pass over the lattice. `scratch` is resized as needed.
double add_thin_plate_product(const std::vector<double>& x, std::size_t nx, std::size_t ny, double mu, double eps,
                              std::vector<double>& out, std::vector<double>& scratch);

}  // namespace nurbsfront::mba_detail
