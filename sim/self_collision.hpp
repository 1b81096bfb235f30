#pragma once
// Detection of cloth-cloth contact (the EG 2002 cloth tutorial §3.5; Volino & Magnenat-Thalmann
// 1994 for the curvature test; Provot 1997 and Bridson et al. 2002 for the continuous tests).
//
// A bounding-volume hierarchy over the cloth's triangles (axis-aligned boxes, built by median
// splits of the triangle centroids when the mesh changes, refitted bottom-up every query) finds
// the pairs of triangles that can be near each other; the exact tests run on their elements:
//
//  * proximity: a vertex within a distance of a triangle (not one of its corners), and two edges
//    within the distance of each other (no shared vertex) whose closest points are inside both;
//  * continuous: a vertex and a triangle, or two edges, that meet (come within a tolerance)
//    while every vertex moves on a straight line from x0 to x1 over the step: the roots of the
//    coplanarity cubic, each checked for proximity; where the four points stay coplanar
//    (parallel edges, motion inside the face's plane), conservative advancement on the distance.
//
// Every element pair is owned by exactly one triangle pair (a vertex and an edge belong to the
// first triangle listed with them), so each is tested once. Elements sharing a vertex are
// adjacent and never tested.
//
// Curvature culling: a node of the tree whose triangles form one edge-connected region, whose
// normals (at both ends of the step) lie in a cone of half-angle below 90° and whose boundary
// projected along the cone's axis does not cross itself cannot touch itself: its inner tests are
// skipped. The region's boundary edges are found when the tree is built.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <vector>

namespace sd::sim {

enum class SelfPairKind : unsigned char {
  vertex_face,  // vertices = {p, a, b, c}: vertex p against triangle (a, b, c)
  edge_edge,    // vertices = {a0, a1, b0, b1}: edge a0a1 against edge b0b1
};

// A pair of cloth elements in contact or colliding. The weights make Σ_k weights[k]·x_k the
// vector from the second element's point to the first's (VF: {1, −β_a, −β_b, −β_c}; EE:
// {1 − s, s, −(1 − t), −t}), so that normal·Σ w_k x_k is their separation, positive on the side
// they are (or were, before a collision) on.
struct SelfPair {
  SelfPairKind kind = SelfPairKind::vertex_face;
  std::array<int, 4> vertices{};
  Eigen::Vector4d weights = Eigen::Vector4d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();  // unit, from the second element to the first
  double distance = 0.0;                              // m: separation at the time of the test
  double time = 0.0;  // continuous test: fraction of the step where they meet (else 0)
};

// What a query did, to report cost and culling.
struct SelfQueryStats {
  int triangles = 0;
  int culled_triangles = 0;      // triangles inside regions the curvature test declared safe
  long long node_pairs = 0;      // pairs of tree nodes whose boxes were compared
  long long triangle_pairs = 0;  // pairs of triangles whose elements were tested
  long long element_tests = 0;   // vertex-face and edge-edge tests
  int pairs_found = 0;
};

class SelfCollider {
 public:
  SelfCollider() = default;
  // The cloth's triangles (#F vertex index triples) and positions x (3n) to build the tree on.
  // Call again after every topology change (adaptive refinement renumbers the mesh).
  SelfCollider(std::vector<std::array<int, 3>> triangles, const Eigen::VectorXd& x);

  void set_culling(bool on) { culling_ = on; }
  bool culling() const { return culling_; }
  int triangle_count() const { return static_cast<int>(triangles_.size()); }
  int edge_count() const { return static_cast<int>(edges_.size()); }

  // Pairs of elements closer than `distance` (m) at positions x (3n), one per element pair.
  std::vector<SelfPair> find_proximities(const Eigen::VectorXd& x, double distance,
                                         SelfQueryStats* stats = nullptr);
  // Pairs that come within `tolerance` (m) while the cloth moves linearly from x0 to x1, with the
  // time they first do; a pair already within the tolerance at t = 0 and not approaching is not
  // a collision.
  // With `moved` (#V flags), only the pairs with at least one flagged vertex: the others are as
  // the last query found them when only those vertices changed (the fail-safe's later rounds).
  // The last query must then have been find_collisions with the same x0 and tolerance, and x1
  // differ from its x1 at flagged vertices only: the tree is refitted at the nodes holding a
  // flagged vertex alone.
  std::vector<SelfPair> find_collisions(const Eigen::VectorXd& x0, const Eigen::VectorXd& x1,
                                        double tolerance, SelfQueryStats* stats = nullptr,
                                        const std::vector<unsigned char>* moved = nullptr);
  // Pairs of triangles that intersect at x (3n) other than along the edge or vertex they share:
  // an edge of one crosses the other (orientation signs; touching counts). A cloth that starts
  // this way cannot be untangled by the continuous tests, which keep whatever it starts with.
  std::vector<std::array<int, 2>> find_intersections(const Eigen::VectorXd& x);

 private:
  struct Node {
    Eigen::AlignedBox3d box;
    Eigen::Vector3d axis = Eigen::Vector3d::Zero();  // normal cone: unit axis, half-angle
    double half_angle = 3.2;
    int left = -1;  // children (both or none)
    int right = -1;
    int begin = 0;  // range of order_ (the node's triangles)
    int end = 0;
    bool connected = false;     // its triangles form one edge-connected region
    std::vector<int> boundary;  // edges with one triangle in the node (when connected)
  };
  // Builds the subtree over order_[begin, end) at nodes_[index] (preorder, presized).
  void build(int index, int begin, int end, const Eigen::VectorXd& x, int depth);
  // Boxes (inflated by `inflate`, m) and normal cones of the step x0 → x1, bottom-up. With
  // `dirty_only`, only the nodes flagged in dirty_ (the others are as the last refit left them).
  void refit(const Eigen::VectorXd& x0, const Eigen::VectorXd& x1, double inflate,
             bool dirty_only = false);
  bool region_is_safe(const Node& node, const Eigen::VectorXd& x0, const Eigen::VectorXd& x1);
  // Where a split traversal stopped: self_test(a) or pair_test(a, b) to run below it, or a
  // pair of triangles (a, b) met above the split.
  struct WalkPiece {
    enum class Kind { self, pair, triangles } kind = Kind::self;
    int a = 0, b = -1;
  };
  // The traversal. With `pieces`, it stops at kWalkSplitDepth and lists there, in its order, the
  // calls it would make below (the leaves it meets above the split go to `leaf` as before).
  template <class LeafTest>
  void self_test(int node, const Eigen::VectorXd& x0, const Eigen::VectorXd& x1, LeafTest& leaf,
                 SelfQueryStats& stats, int depth = 0, std::vector<WalkPiece>* pieces = nullptr);
  template <class LeafTest>
  void pair_test(int a, int b, LeafTest& leaf, SelfQueryStats& stats, int depth = 0,
                 std::vector<WalkPiece>* pieces = nullptr);
  // The element tests of one triangle pair: each vertex against the other triangle and each
  // edge against the other's edges, each element taken at its owner triangle only, so a pair
  // shared by neighbouring triangles is tested once.
  template <class VertexFace, class EdgeEdge>
  void for_each_owned_element_pair(int ta, int tb, VertexFace&& vertex_face,
                                   EdgeEdge&& edge_edge) const {
    for (int k = 0; k < 3; ++k) {
      const int va = triangles_[ta][k], vb = triangles_[tb][k];
      if (vertex_owner_[va] == ta) vertex_face(va, tb);
      if (vertex_owner_[vb] == tb) vertex_face(vb, ta);
    }
    for (int i = 0; i < 3; ++i) {
      const int e = triangle_edges_[ta][i];
      if (edge_owner_[e] != ta) continue;
      for (int j = 0; j < 3; ++j) {
        const int g = triangle_edges_[tb][j];
        if (edge_owner_[g] == tb) edge_edge(e, g);
      }
    }
  }
  // What self_test(0, ...) reaches, in its order: the triangle pairs (appended to `leaves`)
  // and the counts. The top levels are walked here; the pieces below them (subtrees and node
  // pairs) run on the threads and are joined in traversal order.
  void collect_leaves(const Eigen::VectorXd& x0, const Eigen::VectorXd& x1,
                      std::vector<std::array<int, 2>>& leaves, SelfQueryStats& stats);

  std::vector<std::array<int, 3>> triangles_;
  std::vector<std::array<int, 2>> edges_;
  std::vector<std::array<int, 3>> triangle_edges_;  // edge k joins corners k and k+1
  std::vector<std::array<int, 2>> edge_triangles_;  // −1 on the boundary
  std::vector<int> vertex_owner_;                   // first triangle of each vertex, −1: none
  std::vector<int> edge_owner_;
  std::vector<int> order_;     // triangles in tree order
  std::vector<int> position_;  // inverse of order_
  std::vector<Node> nodes_;    // preorder: children after their parent
  // A query restricted to moved vertices: per node, whether one of its triangles has one; empty
  // for a full query.
  std::vector<unsigned char> dirty_;
  bool culling_ = true;
};

// Continuous tests of one element pair over a step (positions at t = 0 and t = 1); nothing when
// they do not come within `tolerance`. Exposed for tests.
bool vertex_face_collision(const std::array<Eigen::Vector3d, 4>& x0,
                           const std::array<Eigen::Vector3d, 4>& x1, double tolerance,
                           SelfPair& hit);
bool edge_edge_collision(const std::array<Eigen::Vector3d, 4>& x0,
                         const std::array<Eigen::Vector3d, 4>& x1, double tolerance, SelfPair& hit);

}  // namespace sd::sim
