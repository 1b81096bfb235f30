#pragma once
// A quad mesh with shared vertices and the structural checks every fill must pass.

#include <Eigen/Core>
#include <string>
#include <vector>

namespace sd::meshing {

// #V by 3 positions and #Q by 4 vertex indices, counter-clockwise seen from the front/outside.
struct QuadMesh {
  Eigen::MatrixX3d vertices;
  Eigen::MatrixX4i faces;

  Eigen::Index vertex_count() const { return vertices.rows(); }
  Eigen::Index face_count() const { return faces.rows(); }
};

// What validate() found wrong; empty when the mesh is fine.
struct MeshCheck {
  std::vector<std::string> problems;
  bool ok() const { return problems.empty(); }
};

// Checks that every face is a quad of 4 distinct in-range vertices, every edge has one or two
// faces, faces sharing an edge traverse it in opposite directions, the boundary is one simple
// loop, every vertex is used, and no face has (near) zero area (below 1e-12 of bbox diagonal²;
// a mesh whose positions are all equal, e.g. before geometry is assigned, skips that check).
MeshCheck validate(const QuadMesh& mesh);

// Number of edges at each vertex, #V.
Eigen::VectorXi vertex_valences(const QuadMesh& mesh);

// The boundary loop as vertex indices in the faces' orientation (counter-clockwise for a
// front-facing disk). Empty for a closed mesh; throws std::invalid_argument when the boundary
// is not a single simple loop.
std::vector<int> boundary_loop(const QuadMesh& mesh);

// Wavefront OBJ text (1-based "f a b c d" lines).
std::string to_obj(const QuadMesh& mesh);

}  // namespace sd::meshing
