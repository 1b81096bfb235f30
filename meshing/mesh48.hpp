#pragma once
// The 4-8 (tri-quad) mesh of a garment and its refinement hierarchy (Velho & Zorin; Birra &
// Santos 2008; DESIGN.md "From quads to a 4-8 mesh"). Triangles are grouped in blocks that share
// a diagonal; splitting a block bisects its diagonal, merging undoes one split. See
// docs/mesh48.md for the data structure, the rules and the id scheme.

#include <Eigen/Core>
#include <array>
#include <stdexcept>
#include <string>
#include <vector>

#include "meshing/mesh48_ids.hpp"
#include "meshing/tri_mesh.hpp"

namespace sd::meshing {

struct QuadMesh;

// A mesh that cannot become a 4-8 mesh (out-of-range index, repeated corner, faces that are not
// consistently oriented, non-manifold edge or vertex, unused vertex, zero-area face).
class Mesh48InputError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// A split or merge asked of a block that cannot take it (dead block, merge of a block whose
// children are split, ...). Callers avoid it with can_split()/can_merge().
class Mesh48OperationError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// What one elementary split or merge did, named as in DESIGN.md ("Adaptive level of detail"):
// block triangles A1 = (A, B, C) and A2 = (D, C, B) share the diagonal BC; E is the midpoint of
// BC; the children are A10 = (A, E, C) ∋ C, A11 = (A, B, E) ∋ B, A20 = (D, E, B) ∋ B and
// A21 = (D, C, E) ∋ C. A boundary block has no D, A2, A20, A21 (ids invalid, areas 0).
// A split removes A1, A2 and creates E and the children; a merge does the inverse. All ids are
// valid right after the operation and stay valid until compact().
struct BlockChange {
  enum class Kind { kSplit, kMerge };
  Kind kind = Kind::kSplit;
  bool forced = false;  // a split made only so that a requested one could happen
  BlockId block;        // the block whose diagonal was split (or restored by a merge)
  int level = 0;        // that block's level; the children are one level finer
  VertexId e, b, c, a, d;
  // Rest areas (m² in the input's units squared), from the 3D rest positions.
  double area_a1 = 0, area_a2 = 0;
  double area_a10 = 0, area_a11 = 0, area_a20 = 0, area_a21 = 0;
  TriangleId a1, a2;              // parent triangles
  TriangleId a10, a11, a20, a21;  // child triangles
  // Input faces (source_face) of the parents on the two sides of the diagonal, which their
  // children share; -1 for a missing second side. Recorded when the change is made: the
  // triangle slots may be reused by the next change of a chain of forced splits.
  int source_a1 = -1, source_a2 = -1;
  // Level-0 triangles (Mesh48::root) the two parents lie in, recorded likewise; -1 for a
  // missing second side.
  int root_a1 = -1, root_a2 = -1;
};

// Flat arrays for the solver. Rows are compact: vertex row r is vertex_ids[r]; when the mesh
// is compact (is_compact()), row r is VertexId(r) and triangle row f is TriangleId(f).
struct Mesh48Arrays {
  Eigen::MatrixX3i faces;           // #F by 3 vertex rows, counter-clockwise
  Eigen::VectorXi face_block;       // #F block id values
  Eigen::VectorXi face_level;       // #F block levels (0 = the input's blocks)
  Eigen::MatrixX3d rest_positions;  // #V by 3, input units
  Eigen::VectorXi vertex_level;     // #V: 0 for input vertices, else the level of the split + 1
  // Interior edges for bending: row (i, j, k, l) means faces (i, j, k) and (j, i, l) (as cyclic
  // rotations) share the edge i-j; edge_faces holds the two face rows. #E by 4 and #E by 2.
  Eigen::MatrixX4i interior_edges;
  Eigen::MatrixX2i edge_faces;
  std::vector<VertexId> vertex_ids;      // #V
  std::vector<TriangleId> triangle_ids;  // #F
};

// Old id value -> new id value (or -1 for a slot that was free), one vector per kind.
struct Mesh48Remap {
  std::vector<int> vertices;
  std::vector<int> triangles;
  std::vector<int> blocks;
  int vertex_count = 0, triangle_count = 0, block_count = 0;  // sizes after compaction
};

// What the √3 conversion did; a swap that would fold a triangle over is not made (the block
// keeps the original edge as its diagonal, which is still a valid 4-8 block).
struct Sqrt3Stats {
  int blocks = 0;
  int boundary_blocks = 0;
  int unswapped_blocks = 0;
};

class Mesh48 {
 public:
  // Each quad (#Q by 4 indices into #V by 3 vertices, counter-clockwise) becomes one level-0
  // block of two triangles, split along the diagonal whose triangles have the larger smallest
  // angle (the shorter one on a tie). Vertex ids equal input rows; rest positions are copied.
  static Mesh48 from_quads(const Eigen::MatrixX3d& vertices, const Eigen::MatrixX4i& quads);
  static Mesh48 from_quads(const QuadMesh& mesh);

  // √3 conversion of a consistently oriented, edge-manifold triangle mesh: vertex F_i's centre
  // becomes vertex #V + i; each input edge becomes one level-0 block (boundary edges give
  // single-triangle boundary blocks), so blocks == input edges.
  static Mesh48 from_triangles_sqrt3(const TriMesh& mesh, Sqrt3Stats* stats = nullptr);

  // --- counts and slots (ids are slot indices; dead slots are reused by later operations) ---
  int vertex_count() const { return vertex_count_; }
  int triangle_count() const { return triangle_count_; }
  int block_count() const { return block_count_; }  // leaf and split blocks
  int vertex_capacity() const { return static_cast<int>(vertices_.size()); }
  int triangle_capacity() const { return static_cast<int>(triangles_.size()); }
  int block_capacity() const { return static_cast<int>(blocks_.size()); }
  bool is_compact() const;  // no free slot of any kind
  int max_level() const;    // finest level of any live triangle

  // --- vertices ---
  bool alive(VertexId v) const;
  const Eigen::Vector3d& rest_position(VertexId v) const;
  int level(VertexId v) const;             // 0 for input vertices
  BlockId parent_block(VertexId v) const;  // the block whose split made it, or invalid
  bool on_boundary(VertexId v) const;
  int valence(VertexId v) const;  // number of incident edges

  // --- triangles: vertices (apex, b, c), counter-clockwise, b-c being the block's diagonal ---
  bool alive(TriangleId t) const;
  const std::array<VertexId, 3>& vertices(TriangleId t) const;
  TriangleId neighbor(TriangleId t, int k) const;  // across the edge opposite vertex k
  BlockId block(TriangleId t) const;
  int level(TriangleId t) const;
  // The input face the triangle lies in: its quad for from_quads; for √3, whose blocks straddle
  // an input edge, one of the edge's two faces (each triangle of a block gets one of them).
  // Lets per-face data (panel, fabric) reach every level.
  int source_face(TriangleId t) const;
  // The level-0 triangle the triangle lies in (its index in the input's triangle order: for
  // from_quads quad q gives 2q and 2q + 1). Every descendant lies in its root's plane, its
  // vertices' rest positions being midpoints of rest positions, so data given affinely on the
  // level-0 triangles (a flattened pattern's coordinates) reaches every level.
  int root(TriangleId t) const;
  int root_count() const { return static_cast<int>(root_corners_.size()); }
  // Level-0 triangle r's corners' rest positions, in its (apex, b, c) order (the order arrays()
  // gives its row while it is alive), and its input face (source_face). Let data computed on
  // the level-0 triangles (the buckling width of a cloth element) reach every level.
  const std::array<Eigen::Vector3d, 3>& root_corners(int r) const;
  int root_source(int r) const;
  double rest_area(TriangleId t) const;
  Eigen::Vector3d rest_normal(TriangleId t) const;  // unit

  // --- blocks ---
  bool alive(BlockId k) const;
  int level(BlockId k) const;
  bool is_split(BlockId k) const;
  std::array<VertexId, 2> diagonal(BlockId k) const;     // (b, c) as seen by triangles(k)[0]
  std::array<VertexId, 2> apexes(BlockId k) const;       // (A, D); D invalid for one triangle
  std::array<TriangleId, 2> triangles(BlockId k) const;  // (A1, A2) of a leaf block, else invalid
  std::array<BlockId, 2> parents(BlockId k) const;       // per side, invalid at level 0
  std::array<BlockId, 4> children(BlockId k) const;      // split blocks: (AB, AC, DC, DB) sides
  VertexId split_vertex(BlockId k) const;                // E of a split block, else invalid
  // The triangles around E of a split block, ordered like children(): (A11, A10, A21, A20) in
  // DESIGN.md's names; an entry is invalid when that child block is split (or absent). Lets the
  // simulator judge a merge (flatness, hinge rates) before making it.
  std::array<TriangleId, 4> child_triangles(BlockId k) const;
  // A leaf block with one triangle whose diagonal is shared with a coarser triangle: splitting
  // it forces the coarser block's split first.
  bool is_pending(BlockId k) const;

  std::vector<TriangleId> live_triangles() const;
  std::vector<BlockId> leaf_blocks() const;       // every block split() accepts
  std::vector<BlockId> mergeable_blocks() const;  // every block merge() accepts

  // --- operations ---
  bool can_split(BlockId k) const;  // a live leaf block
  // Bisects k's diagonal, first splitting (recursively) the coarser blocks that must go first
  // so that adjacent levels stay within one. Returns every split in the order made; the last
  // one is k's (forced == false).
  std::vector<BlockChange> split(BlockId k);
  // Splits the edge u-v of the current mesh: if it is not a block diagonal, the blocks on its
  // sides are split first until it is one.
  std::vector<BlockChange> split_edge(VertexId u, VertexId v);

  // A split block can be merged when none of its (2 or 4) children is split, i.e. its split
  // vertex has valence 4 (3 on the boundary) and no finer block depends on it.
  bool can_merge(BlockId k) const;
  BlockChange merge(BlockId k);

  // --- export and ids ---
  Mesh48Arrays arrays() const;
  // Renumbers live vertices, triangles and blocks to 0..n-1 keeping their order; afterwards
  // is_compact() and arrays() rows equal ids. Ids held from before must be passed through the
  // returned remap.
  Mesh48Remap compact();

  // Every broken invariant, in words (empty when valid): slot bookkeeping, conformity
  // (matching neighbours, no hanging vertex), level rule, block structure, parent/child links,
  // exact-halves rest geometry, orientation relative to the input, total rest area.
  std::vector<std::string> validate() const;

  double total_rest_area() const;  // sum over live triangles

 private:
  friend struct Mesh48TestAccess;  // tests corrupt a mesh on purpose to check validate()

  struct Vertex {
    Eigen::Vector3d rest = Eigen::Vector3d::Zero();
    BlockId parent;
    TriangleId triangle;  // any live incident triangle
    int level = 0;
    bool on_boundary = false;
    bool alive = false;
  };
  struct Triangle {
    std::array<VertexId, 3> v;      // apex, b, c
    std::array<TriangleId, 3> adj;  // adj[k] across the edge opposite v[k]; adj[0] across b-c
    BlockId block;
    int level = 0;
    int root = -1;  // index of the level-0 triangle it lies in (for the orientation check)
    bool alive = false;
  };
  struct Block {
    std::array<VertexId, 2> diagonal;  // (b, c) seen from side 0
    std::array<VertexId, 2> apex;      // side 0, side 1 (invalid when the side is absent)
    std::array<TriangleId, 2> tri;     // live triangles of a leaf block
    std::array<BlockId, 2> parent;
    std::array<BlockId, 4> child;
    VertexId split;
    int level = 0;
    bool alive = false;
  };

  Mesh48() = default;
  // Builds from level-0 triangles given as (apex, b, c); triangles sharing b-c pair into blocks.
  static Mesh48 build(std::vector<Eigen::Vector3d> rest,
                      const std::vector<std::array<int, 3>>& triangles);

  VertexId new_vertex();
  TriangleId new_triangle();
  BlockId new_block();
  void free_vertex(VertexId v);
  void free_triangle(TriangleId t);
  void free_block(BlockId k);

  void split_recursive(BlockId k, bool forced, std::vector<BlockChange>& changes);
  BlockChange split_complete(BlockId k, bool forced);
  void replace_neighbor(TriangleId t, TriangleId new_neighbor);
  void attach_child(BlockId parent, int child_index, TriangleId child);
  TriangleId find_triangle_with_edge(VertexId u, VertexId v, int* local_edge) const;
  template <class Visit>
  void for_each_triangle_around(VertexId v, Visit visit) const;

  const Vertex& vertex_at(VertexId v) const;
  const Triangle& triangle_at(TriangleId t) const;
  const Block& block_at(BlockId k) const;

  std::vector<Vertex> vertices_;
  std::vector<Triangle> triangles_;
  std::vector<Block> blocks_;
  std::vector<int> free_vertices_, free_triangles_, free_blocks_;  // LIFO
  int vertex_count_ = 0, triangle_count_ = 0, block_count_ = 0;

  // Input facts kept for validate(): level-0 triangle unit normals and areas, total rest area,
  // total boundary length.
  std::vector<Eigen::Vector3d> root_normals_;
  std::vector<double> root_areas_;
  std::vector<int> root_source_;                              // input face of each level-0 triangle
  std::vector<std::array<Eigen::Vector3d, 3>> root_corners_;  // (apex, b, c) rest positions
  double input_area_ = 0;
  double input_boundary_length_ = 0;
};

}  // namespace sd::meshing
