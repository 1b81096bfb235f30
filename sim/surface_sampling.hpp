#pragma once
// Comparing two cloth states that live on different meshes of the same material surface (an
// adaptive run against a fixed-resolution one, a coarse run against a fine reference): positions
// of material points, found in each mesh's rest shape and interpolated in its current shape.

#include <Eigen/Core>

namespace sd::sim {

// For each material point (#P by 3, in the rest frame of the mesh) the current position of the
// point of the rest surface closest to it: the rest triangle nearest to the point (brute force,
// O(P·F)), barycentric coordinates of the closest point on it, applied to the current corners.
// rest #V by 3, faces #F by 3, positions #V by 3. Returns #P by 3.
Eigen::MatrixX3d positions_at_material_points(const Eigen::MatrixX3d& rest,
                                              const Eigen::MatrixX3i& faces,
                                              const Eigen::MatrixX3d& positions,
                                              const Eigen::MatrixX3d& material_points);

// Root mean square of the row-wise distances between two #P by 3 point sets, metres.
double rms_distance(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b);

}  // namespace sd::sim
