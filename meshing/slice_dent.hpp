#pragma once
// How far a draped garment dents inward between supports: cloth that spans the legs (a skirt)
// has horizontal slices that are close to convex, cloth pulled into the crotch has a slice with
// a deep notch. The measure: cut the mesh with horizontal planes, and in each slice take the
// deepest distance of a cut point from the slice's convex hull (in the XZ plane).

#include <Eigen/Core>

#include "meshing/tri_mesh.hpp"

namespace sd::meshing {

struct SliceDent {
  double depth = 0.0;                               // m, deepest over the slices
  double height = 0.0;                              // m, y of the slice where it is deepest
  Eigen::Vector3d where = Eigen::Vector3d::Zero();  // the deepest cut point
  int slices = 0;                                   // slices that cut the mesh
};

// Slices at `count` heights evenly from `from` to `to`, given as fractions of the mesh's height
// above its lowest vertex (Y up). A slice that cuts fewer than 3 points counts as depth 0.
SliceDent slice_dent(const TriMesh& mesh, double from = 0.1, double to = 0.6, int count = 51);

// The deepest distance of points (#P by 2) from the boundary of their convex hull, 0 for
// fewer than 3 points; `deepest` (optional) receives the row of the deepest point.
double hull_dent(const Eigen::MatrixX2d& points, Eigen::Index* deepest = nullptr);

}  // namespace sd::meshing
