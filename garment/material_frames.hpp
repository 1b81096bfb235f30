#pragma once
// Material (warp/weft) frames of the garment and the rest shape of its triangles. Warp is the
// direction in each face closest to the body's vertical (+Y), weft is perpendicular to it in the
// face (DESIGN.md "Cloth model"); rest coordinates are the designed 3D shape expressed in that
// frame, optionally scaled by an ease factor.

#include <Eigen/Core>

#include "meshing/quad_mesh.hpp"
#include "meshing/tri_mesh.hpp"

namespace sd::garment {

struct MaterialFrames {
  Eigen::MatrixX3d warp;    // #Q by 3 unit vectors in the face's tangent plane
  Eigen::MatrixX3d weft;    // #Q by 3, normal × warp
  Eigen::MatrixX3d normal;  // #Q by 3 unit face normals (from the diagonals)
};

// One frame per quad. A face lying flat (normal within 1e-6 of ±Y, no vertical direction in
// it) takes the projection of +Z instead (the mannequin's forward direction).
MaterialFrames material_frames(const meshing::QuadMesh& mesh);

// One frame per quad, with the warp of each quad from its panel's grain (GarmentPanel::grain_axis
// projected into the quad, then turned by grain_turn_deg about the normal). A quad whose plane
// holds no direction of the axis (normal within 1e-6 of it) falls back to the rule above.
struct Garment;
MaterialFrames material_frames(const Garment& garment);

// Rest (material) coordinates of each triangle: #T by 6 rows (u0 v0 u1 v1 u2 v2) in metres,
// u along warp and v along weft of the quad the triangle came from (`triangle_quad`, #T), with
// the first corner at the origin, scaled by `quad_ease` (#Q, 1 = as designed). Lengths and
// angles of each triangle are preserved up to the ease factor.
Eigen::MatrixXd triangle_rest_coordinates(const meshing::TriMesh& triangles,
                                          const Eigen::VectorXi& triangle_quad,
                                          const MaterialFrames& frames,
                                          const Eigen::VectorXd& quad_ease);

}  // namespace sd::garment
