#pragma once
// A triangle mesh with shared vertices, and the topological facts the rest of the pipeline asks
// about it (closed? manifold? how many pieces?).

#include <Eigen/Core>

namespace sd::meshing {

// #V by 3 positions and #F by 3 vertex indices, counter-clockwise seen from the outside.
struct TriMesh {
  Eigen::MatrixX3d vertices;
  Eigen::MatrixX3i faces;

  Eigen::Index vertex_count() const { return vertices.rows(); }
  Eigen::Index face_count() const { return faces.rows(); }
};

struct BoundingBox {
  Eigen::Vector3d min = Eigen::Vector3d::Zero();
  Eigen::Vector3d max = Eigen::Vector3d::Zero();
  Eigen::Vector3d extent() const { return max - min; }
  Eigen::Vector3d centre() const { return 0.5 * (min + max); }
};

// Axis-aligned bounds of the vertices; a zero box for an empty mesh.
BoundingBox bounding_box(const TriMesh& mesh);

struct TriMeshTopology {
  Eigen::Index boundary_edges = 0;      // edges with one incident face
  Eigen::Index non_manifold_edges = 0;  // edges with three or more incident faces
  Eigen::Index inconsistent_edges = 0;  // edges whose two faces traverse them the same way
  Eigen::Index degenerate_faces = 0;    // repeated vertex index or area below 1e-12 of bbox²
  Eigen::Index isolated_vertices = 0;   // vertices used by no face
  Eigen::Index components = 0;          // connected pieces (through shared vertices)

  bool closed() const { return boundary_edges == 0 && non_manifold_edges == 0; }
  bool edge_manifold() const { return non_manifold_edges == 0; }
  bool oriented() const { return inconsistent_edges == 0; }
};

// Counts the facts above in O(F log F). Face indices must be in range (checked, throws).
TriMeshTopology analyse_topology(const TriMesh& mesh);

// Area of each face, #F.
Eigen::VectorXd face_areas(const TriMesh& mesh);

// Area-weighted vertex normals, #V by 3, unit length (zero for unused vertices).
Eigen::MatrixX3d vertex_normals(const TriMesh& mesh);

// An icosphere: the icosahedron subdivided `subdivisions` times (20·4^s triangles), every vertex
// on the sphere of `radius` around `centre`, faces outward. One vertex sits at the top,
// centre + radius·(0, 1, 0), once subdivisions ≥ 1.
TriMesh icosphere(double radius, int subdivisions, const Eigen::Vector3d& centre);

}  // namespace sd::meshing
