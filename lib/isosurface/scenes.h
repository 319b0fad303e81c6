// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Built-in analytic level-set scenes (sphere, torus, trench, DRAM cell) and their sampling
//! into ScalarGrids, as signed distances (level set) or as 0/1 cell occupancy (voxels).
//!
//! Every scene has a signed distance function f (negative inside). For the sphere and the torus
//! f is the exact Euclidean signed distance. The trench and the DRAM cell are built by CSG
//! (union = min, difference = max(a, -b)) from exact box and capped-cylinder distances: the sign
//! and the zero set are exact, and |f(p)| <= dist(p, surface) everywhere (f is a 1-Lipschitz
//! lower bound of the true distance, exact outside near faces but not near concave edges).

#include <cstddef>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <Eigen/Core>

#include "nurbsfront/core/soup.h"
#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scalar_grid.h"

namespace nurbsfront {

//! A ball.
struct SphereScene {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  //!< centre. Default origin.
  double radius = 1.0;                               //!< radius (> 0). Default 1.
};

//! A ring torus around the z axis through `center`.
struct TorusScene {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  //!< centre. Default origin.
  double major_radius = 1.0;                         //!< distance of the tube's centre line from the axis. Default 1.
  double minor_radius = 0.35;                        //!< tube radius (0 < minor < major). Default 0.35.
};

//! A substrate slab [0, width] x [0, length] x [0, height] with a groove along y etched into its
//! top, centred in x; rectangular, or with a round bottom (a half-cylinder of radius
//! groove_width / 2) when `rounded`.
struct TrenchScene {
  double width = 2.0;         //!< slab size along x (> groove_width). Default 2.
  double length = 1.5;        //!< slab size along y (the groove runs along y). Default 1.5.
  double height = 1.0;        //!< slab thickness along z. Default 1.
  double groove_width = 0.6;  //!< groove width along x. Default 0.6.
  double groove_depth = 0.6;  //!< groove depth from the top (< height). Default 0.6.
  bool rounded = false;       //!< round groove bottom instead of a flat one. Default false.
};

//! A DRAM cell in micrometres, z up, in the box [0, size_x] x [0, size_y] x [0, size_z]: a
//! substrate slab; word lines as bars along y lying on it; two bit lines as bars along x lying
//! across the word lines; four cup-shaped capacitors (a cylinder shell with a bottom) in a 2 x 2
//! arrangement above the bit lines, each standing on a cylindrical contact plug that reaches down
//! through its bit line into the substrate. Everything is one connected solid.
struct DramScene {
  double size_x = 2.25;              //!< box size along x (um). Default 2.25.
  double size_y = 1.75;              //!< box size along y (um). Default 1.75.
  double size_z = 3.45;              //!< box size along z (um); the cups' rims touch the top. Default 3.45.
  double substrate_thickness = 0.5;  //!< substrate slab thickness (um). Default 0.5.
  int n_word_lines = 4;              //!< number of word lines (bars along y, evenly spaced in x). Default 4.
  double word_line_width = 0.18;     //!< word line width along x (um). Default 0.18.
  double word_line_height = 0.25;    //!< word line height (um). Default 0.25.
  double bit_line_width = 0.2;       //!< bit line width along y (um). Default 0.2.
  double bit_line_height = 0.25;     //!< bit line height (um), lying on the word lines. Default 0.25.
  double cup_bottom_z = 1.4;         //!< z of the bottom face of the cups (um). Default 1.4.
  double cup_outer_radius = 0.38;    //!< outer radius of a cup (um). Default 0.38.
  double cup_wall = 0.1;             //!< wall thickness of a cup, also its bottom thickness (um). Default 0.1.
  double plug_radius = 0.12;         //!< radius of a contact plug (um). Default 0.12.
};

//! One of the built-in scenes.
using Scene = std::variant<SphereScene, TorusScene, TrenchScene, DramScene>;

//! How a scene is turned into grid values.
enum class SampleMode {
  LevelSet,   //!< signed distance at each grid point; extract at iso 0, inside below
  Occupancy,  //!< 1 where the grid point (a cell centre) is inside, 0 outside; iso 0.5, inside above
};

//! Signed distance of p to the scene's surface (negative inside; see the file comment for exactness).
[[nodiscard]] double signed_distance(const Scene& scene, const Eigen::Vector3d& p);
//! Mean and largest of a set of distances.
struct DistanceSummary {
  double mean = 0.0;      //!< 0 when count is 0
  double max = 0.0;       //!< 0 when count is 0
  std::size_t count = 0;  //!< number of samples
  //! Both sets together (the mean weighted by the counts).
  [[nodiscard]] DistanceSummary merged(const DistanceSummary& other) const;
};

//! Distance of a triangle mesh to a scene's surface (|signed_distance| at sample points),
//! by kind of sample point.
struct SceneDistance {
  DistanceSummary vertices;   //!< at every point of the soup
  DistanceSummary centroids;  //!< at every triangle's centroid
  //! At the points of a barycentric grid of `dense_steps` steps in every triangle, its
  //! corners excluded (a 4-step grid: 12 points, 9 of them on the edges); none when
  //! dense_steps < 2.
  DistanceSummary dense;
  //! Every sample together.
  [[nodiscard]] DistanceSummary all() const { return vertices.merged(centroids).merged(dense); }
};

//! Distance of a mesh to the scene's true surface: issue 5's fidelity to the truth.
//! |signed_distance| is the Euclidean distance for the sphere and the torus and a lower bound
//! of it for the CSG scenes (see the file comment).
//! \param soup the mesh (triangle indices into its points)
//! \param dense_steps steps of the barycentric grid of SceneDistance::dense, in [0, 64]
//! \throw InvalidInput for a triangle index out of range, a bad scene or dense_steps
[[nodiscard]] SceneDistance distance_to_scene(const TriangleSoup& soup, const Scene& scene, int dense_steps = 0);

//! Tight bounding box of the scene's solid.
[[nodiscard]] BoundingBox bounding_box(const Scene& scene);
//! \throw InvalidInput for non-positive or inconsistent sizes (e.g. a groove deeper than its slab).
void validate(const Scene& scene);

//! The scene with default parameters named "sphere", "torus", "trench" or "dram".
//! \throw InvalidInput for any other name (the message lists the valid ones).
[[nodiscard]] Scene scene_by_name(std::string_view name);
//! The names accepted by scene_by_name().
[[nodiscard]] std::vector<std::string> scene_names();

//! Samples a scene on a grid with `resolution` cells along the longest side of its bounding box
//! (cubic cells) plus a margin of kSceneMarginCells cells on each side, so the surface is closed
//! inside the grid. Runs on several threads (by z slices); the result does not depend on their number.
//! \param scene the scene (validated)
//! \param resolution cells along the longest box side, in [4, 2048]
//! \param mode level set (signed distance) or occupancy (0/1)
//! \throw InvalidInput for a bad scene or resolution
[[nodiscard]] ScalarGrid sample_scene(const Scene& scene, int resolution, SampleMode mode = SampleMode::LevelSet);

//! Grid cells added around the scene's box on each side by sample_scene().
inline constexpr int kSceneMarginCells = 3;

//! Marching-cubes options matching a sample mode (iso 0 and inside below for LevelSet, iso 0.5
//! and inside above for Occupancy; no padding).
[[nodiscard]] MarchingCubesOptions scene_marching_cubes_options(SampleMode mode);

}  // namespace nurbsfront
