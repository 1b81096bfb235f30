#pragma once
// Comparing two cloth states that live on different meshes of the same material surface (an
// adaptive run against a fixed-resolution one, a coarse run against a fine reference): positions
// of material points, found in each mesh's rest shape and interpolated in its current shape.

#include <Eigen/Core>
#include <vector>

namespace sd::sim {

// A material point found in a mesh's rest shape: the rest triangle nearest to it and the
// barycentric coordinates of the closest point on that triangle.
struct MaterialLocation {
  int face = 0;
  Eigen::Vector3d weights = Eigen::Vector3d::Zero();  // sum 1, all >= 0
};

// Each material point (#P by 3, rest frame) located in the rest triangles (rest #V by 3, faces
// #F by 3): brute force, O(P·F), done once per mesh.
std::vector<MaterialLocation> locate_material_points(const Eigen::MatrixX3d& rest,
                                                     const Eigen::MatrixX3i& faces,
                                                     const Eigen::MatrixX3d& material_points);

// The current positions (#P by 3) of located material points: their weights applied to the
// current corners (positions #V by 3).
Eigen::MatrixX3d positions_at(const std::vector<MaterialLocation>& located,
                              const Eigen::MatrixX3i& faces, const Eigen::MatrixX3d& positions);

// For each material point (#P by 3, in the rest frame of the mesh) the current position of the
// point of the rest surface closest to it: positions_at(locate_material_points(...)).
// rest #V by 3, faces #F by 3, positions #V by 3. Returns #P by 3.
Eigen::MatrixX3d positions_at_material_points(const Eigen::MatrixX3d& rest,
                                              const Eigen::MatrixX3i& faces,
                                              const Eigen::MatrixX3d& positions,
                                              const Eigen::MatrixX3d& material_points);

// Root mean square of the row-wise distances between two #P by 3 point sets, metres.
double rms_distance(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b);

}  // namespace sd::sim
