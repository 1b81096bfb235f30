#pragma once
// Building a quad mesh block by block: a coarse layout of 4-sided blocks whose opposite sides
// have equal edge counts, each block refined into a grid. Internal to the patch filler.
//
// Every vertex the blocks add in the middle of a block side or inside a block is regular
// (valence 3 on the region's boundary, 4 inside), so a layout's distortion is decided by its
// block corners alone.

#include <Eigen/Core>
#include <array>
#include <span>
#include <vector>

#include "meshing/quad_mesh.hpp"

namespace sd::meshing::detail {

class QuadMeshBuilder {
 public:
  // A vertex at a position (2D parameter layouts use z = 0).
  int add_vertex(const Eigen::Vector3d& position);

  // A straight chain of `edges` edges from vertex `from` to vertex `to`: returns the
  // edges + 1 vertex indices, creating the edges − 1 in between.
  std::vector<int> add_chain(int from, int to, int edges);

  // Records the edges of a path of existing vertices (a region's side), so valences() sees
  // them before any face uses them.
  void add_path(std::span<const int> vertices);

  // A grid block from its four sides, counter-clockwise: bottom (a edges, corner 0 → 1), right
  // (b edges, 1 → 2), top (a edges, 2 → 3), left (b edges, 3 → 0); consecutive sides share
  // their end vertex. Interior vertices go where bilinear Coons interpolation of the sides puts
  // them. Faces are counter-clockwise when the sides are.
  void add_grid(std::span<const int> bottom, std::span<const int> right, std::span<const int> top,
                std::span<const int> left);

  // One quad, counter-clockwise, of existing vertices.
  void add_quad(const std::array<int, 4>& quad) { faces_.push_back(quad); }

  const Eigen::Vector3d& position(int v) const { return positions_[static_cast<size_t>(v)]; }
  // All positions (#V), for moving vertices once the layout is complete (relaxation); build()
  // takes them as they are then.
  std::vector<Eigen::Vector3d>& positions() { return positions_; }
  // The quads so far (#Q), counter-clockwise.
  std::span<const std::array<int, 4>> faces() const { return faces_; }
  int vertex_count() const { return static_cast<int>(positions_.size()); }
  int face_count() const { return static_cast<int>(faces_.size()); }

  // Number of distinct edges at each vertex among the faces and chains added so far.
  std::vector<int> valences() const;

  // The mesh so far.
  QuadMesh build() const;

 private:
  std::vector<Eigen::Vector3d> positions_;
  std::vector<std::array<int, 4>> faces_;
  std::vector<std::array<int, 2>> chain_edges_;  // edges of chains, faces or not
};

}  // namespace sd::meshing::detail
