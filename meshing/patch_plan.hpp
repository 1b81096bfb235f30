#pragma once
// Private to meshing/patch_fill.cpp and meshing/patch_plan.cpp: the topology plan of the patch
// filler, chosen from the sides' edge counts and the boundary's shape before the geometric fill
// places it. Not part of the library's interface.

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <tuple>
#include <vector>

#include "meshing/patch_fill.hpp"
#include "meshing/quad_layout.hpp"
#include "meshing/region_partition.hpp"

namespace sd::meshing::detail {

struct Built {
  detail::QuadMeshBuilder builder;
  std::vector<std::vector<int>> sides;  // vertex ids per side, corner to corner
};

// How the boundary bends at each loop position, for judging where a vertex of valence 2 (one
// quad, with the boundary's own angle) is acceptable.
struct BoundaryShape {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // the loop is counter-clockwise about it
  std::vector<char> reflex;  // interior angle above 180°: one quad there is folded
  std::vector<char> flat;    // interior angle above kFlatDegrees (reflex included)
  bool measured = false;     // from real side points (not the count-only assumption)
  // Measured only: the turn to the left at each position about `normal`, in quarter turns.
  std::vector<double> turn;
  // Every boundary vertex within 1e-9 of the boundary's extent from the plane through the
  // first one square to `normal`: a fill without projection then lies in that plane, and a
  // quad turning the wrong way about `normal` is folded even when its neighbours turned with
  // it (measure_quality's vertex normals cannot see such a cluster).
  bool planar = false;
};

// A construction, chosen from the edge counts and the boundary's shape before any mesh is
// built (except the Yasseen candidate, which is built to be measured): strips of padding along
// some sides, then a layout of what is left.
struct Plan {
  bool yasseen = false;
  std::vector<int> strips;  // side indices, in the order they are added
  detail::PolygonLayout layout;
  // Nonempty: the left-over region is filled by this rectilinear layout (a turn per loop
  // position) instead of `layout`.
  std::vector<int> turns;
  std::string partition;
  int distortion = 0, irregular_vertices = 0;
  int folded = 0;  // boundary vertices of valence 2 where the boundary is reflex
  int flat = 0;    // boundary vertices of valence 2 where it is flat (or reflex)
  // Loop positions of the corners the strips work with: empty for the region's own corners;
  // without its reflex corners when those must not keep a single quad (a strip keeps the
  // corners it runs between at valence 2, so it can only pass a reflex corner as a side
  // vertex of valence 3).
  std::vector<int> strip_corners;

  // Never fold where another construction does not; then least distortion; then, for a
  // count-only fill, fewest irregular vertices (the corpus figures) before fewest flat
  // corners, and for a fill of real sides (`shape_first`) the other way round: a side vertex
  // of valence 2 leaves one quad with a 180° corner and the other three sharing 180°, which on
  // a long side next to short ones makes a sliver (3° for (30,4,4,4,4) on the `fill` circle).
  auto rank(bool shape_first) const {
    return std::tuple(folded, distortion, shape_first ? flat : irregular_vertices,
                      shape_first ? irregular_vertices : flat);
  }
};

// Corner i of the sides (vertex ids per side, corner to corner) is sides[i].front().
std::vector<int> corners_of(const std::vector<std::vector<int>>& sides);

// Straight sides, convex corners: what fill_region(counts) assumes.
BoundaryShape straight_sided_shape(std::span<const int> counts);

// Interior angles of the boundary loop about its Newell normal (for a panel on a curved body
// the overall normal; the sign of a turn is right as long as the surface tilts less than 90°
// from it).
// With `surface_normal` (FillGeometryOptions::surface_normal), each turn is measured about the
// surface's normal at that vertex where it is known, and the loop's overall normal elsewhere;
// with `flags_about_surface` the reflex and flat flags too (FillGeometryOptions).
BoundaryShape measured_shape(
    const std::vector<Eigen::MatrixX3d>& side_points,
    const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& surface_normal = {},
    bool flags_about_surface = false);

// The best plan for these counts on a boundary of this shape; when the Yasseen construction
// wins, `yasseen` receives it already built on `side_points`.
// Plans listed in `excluded` (same strips, strip corners and construction) are passed over.
Plan choose_plan(std::span<const int> counts, const BoundaryShape& shape,
                 const std::vector<Eigen::MatrixX3d>& side_points, std::optional<Built>& yasseen,
                 const std::vector<Plan>& excluded = {});

// The mesh of a plan on these sides (the same connectivity for any sides).
Built realize(const Plan& plan, std::span<const int> counts,
              const std::vector<Eigen::MatrixX3d>& side_points, const BoundaryShape& shape);

// The topology of a built plan: its mesh, its sides and the plan's figures.
PatchTopology to_topology(Built&& built, const Plan& plan);

}  // namespace sd::meshing::detail
