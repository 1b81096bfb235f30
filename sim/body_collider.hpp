#pragma once
// Cloth-against-body proximity: the body triangle mesh in an FCL bounding volume hierarchy
// (RSS boxes), refitted when the body moves, answering per cloth vertex "how far from the body,
// on which side, where is the closest point and how fast is the body moving there".
//
// Inside/outside is decided with angle-weighted pseudo-normals of the closest feature (face,
// edge or vertex; Bærentzen & Aanæs 2005), so points whose closest point is an edge or a corner
// get the right sign, and points deep inside a closed body get a negative distance.
// See docs/collision.md.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <vector>

#include "meshing/tri_mesh.hpp"
#include "sim/collision_geometry.hpp"

namespace fcl {
template <typename S>
class RSS;
template <typename BV>
class BVHModel;
}  // namespace fcl

namespace sd::sim {

// A body mesh the collider cannot use (no triangles, index out of range, non-finite vertex) or a
// pose that does not match it. Derives from std::invalid_argument: the input is wrong.
class InvalidBodyMeshError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// The closest point on the body to one query point.
struct BodyProximity {
  int triangle = -1;                                      // body face index
  Eigen::Vector3d point = Eigen::Vector3d::Zero();        // on the surface, metres
  Eigen::Vector3d barycentric = Eigen::Vector3d::Zero();  // of `point` in `triangle`
  TriangleFeature feature = TriangleFeature::face;        // where in the triangle
  int feature_index = 0;                                  // edge or corner index
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();      // unit, outward push direction
  double distance = 0.0;                                  // signed, negative inside
};

// One cloth vertex that needs the solver's attention: within the thickness of the body, inside
// it, or (continuous check) passed through its surface during the step. The solver keeps the
// vertex at `point + thickness·normal` along `normal` and moves it with `body_velocity` there.
struct BodyContact {
  int vertex = -1;                                          // cloth vertex index
  int triangle = -1;                                        // body face holding `point`
  Eigen::Vector3d point = Eigen::Vector3d::Zero();          // on the body (current pose), m
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();        // unit, outward
  double distance = 0.0;                                    // (x − point)·normal; < 0 inside
  Eigen::Vector3d body_velocity = Eigen::Vector3d::Zero();  // body surface at `point`, m/s
  bool crossed = false;  // found by the continuous check: pushed back to the side it came from
};

// A body vertex poking through a cloth triangle: it lies in front of the triangle (along the
// body's outward normal) while the triangle dips into the body beneath it. Happens at sharp
// body features (box corners, shoulder tips, elbows) where every cloth vertex is outside the
// body but a triangle spans the feature; the vertex test alone cannot see it.
struct BodyPiercing {
  int body_vertex = -1;
  int cloth_triangle = -1;  // index into the triangle list given to find_piercings
  // Of the triangle's closest point to the body vertex (all ≥ 0, sum 1).
  Eigen::Vector3d barycentric = Eigen::Vector3d::Zero();
  // Unit normal of the cloth triangle, oriented to the body's outward side at the vertex: the
  // direction the triangle must move to uncover the vertex.
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();
  double height = 0.0;  // m, (body vertex − closest point)·normal; > 0: through the cloth
  Eigen::Vector3d body_velocity = Eigen::Vector3d::Zero();  // of the body vertex, m/s
};

// The cloth's triangles as find_piercings reads them: the list, and per triangle which of its
// edges lie on the cloth's open boundary (in that triangle only). The positions change every
// step, the triangles only with the topology: build this once per topology.
struct ClothTriangles {
  ClothTriangles() = default;
  ClothTriangles(std::vector<std::array<int, 3>> list);  // implicit: a plain list works too

  std::vector<std::array<int, 3>> triangles;
  std::vector<std::uint8_t> open_edges;  // per triangle, bit k: edge k (corners k, k+1) is open
  // The triangles around each vertex (compressed rows: vertex v's are
  // vertex_triangles[vertex_offsets[v] .. vertex_offsets[v + 1]]), for the side of the cloth at
  // a corner or an edge (BodyCollider::find_piercings).
  std::vector<int> vertex_offsets;
  std::vector<int> vertex_triangles;
};

struct PiercingQueryStats {
  int body_vertices = 0;  // body vertices inside the cloth's bounding box (looked up)
  int pairs = 0;          // vertex-triangle pairs tested
  int inside_checks = 0;  // signed-distance searches to confirm the triangle dips into the body
  int piercings = 0;
  std::int64_t grid_entries = 0;  // (cell, triangle) entries of the broad-phase grid
};

struct ContactQuery {
  double thickness = 0.005;  // m: vertices closer than this (signed) become contacts
  // m: with a cache, searches reach this much further than the thickness, so that a vertex found
  // clear by more than the thickness can be skipped for a few steps without any search.
  double search_margin = 0.02;
  // Continuous check: the largest relative cloth-body motion (m) between two samples of a
  // vertex's path. Must stay below half the thinnest body part (fingers, ~2 cm): a vertex is
  // caught at most this deep, where its nearest surface is still the one it came through.
  double max_substep_motion = 0.005;
  int max_substeps = 64;  // cap on samples per vertex and step
};

// What a query did, for diagnostics and benchmarks.
struct ContactQueryStats {
  int vertices = 0;          // cloth vertices looked at
  int skipped = 0;           // cleared by the cache without a search
  int bounded_searches = 0;  // BVH searches limited to thickness (+ margin)
  int full_searches = 0;     // unbounded searches (sign of a point far from the surface)
  int sweep_samples = 0;     // continuous check: points sampled along paths
  int crossings = 0;         // continuous check: vertices that passed through the surface
  int contacts = 0;          // contacts returned
};

// Per-cloth-vertex memory between queries: where the vertex was, whether it was outside, and a
// lower bound of its distance to the body then. The unsigned distance is 1-Lipschitz in the
// point and changes by at most the body's largest vertex displacement, so a vertex that has
// moved less than its clearance minus the thickness needs no search. Reset (or let the size
// change do it) whenever the cloth's vertices are renumbered.
class ContactCache {
 public:
  void reset() { entries_.clear(); }
  int vertex_count() const { return static_cast<int>(entries_.size()); }

 private:
  friend class BodyCollider;
  enum class State : unsigned char { unknown, outside, inside };
  struct Entry {
    Eigen::Vector3d position = Eigen::Vector3d::Zero();  // where the vertex was evaluated
    double clearance = 0.0;  // lower bound of the unsigned distance to the body there, m
    double stamp = 0.0;      // the collider's cumulative motion at the evaluated pose, m
    State state = State::unknown;
    int triangle = -1;  // the body triangle nearest to it then (a hint for the next search)
  };
  std::vector<Entry> entries_;
  std::uint64_t collider_id_ = 0;
};

class BodyCollider {
 public:
  // Builds the hierarchy over `body` (metres, counter-clockwise seen from outside, closed for a
  // meaningful inside). Throws InvalidBodyMeshError on an unusable mesh.
  explicit BodyCollider(const meshing::TriMesh& body);
  ~BodyCollider();
  BodyCollider(BodyCollider&&) noexcept;
  BodyCollider& operator=(BodyCollider&&) noexcept;
  BodyCollider(const BodyCollider&) = delete;
  BodyCollider& operator=(const BodyCollider&) = delete;

  int vertex_count() const;
  int face_count() const;
  const Eigen::MatrixX3i& faces() const;
  // Current pose, #V by 3 (copy).
  Eigen::MatrixX3d vertices() const;
  // Pose before the last set_pose (the current one if never moved), #V by 3 (copy).
  Eigen::MatrixX3d previous_vertices() const;

  // Moves the body to a new pose with the same topology (#V by 3 positions, and #V by 3
  // velocities in m/s or an empty matrix for zero). Refits the FCL hierarchy rather than
  // rebuilding it; its boxes then bound the motion from the previous pose to this one, which is
  // what the continuous check sweeps. Call once per cloth step.
  void set_pose(const Eigen::MatrixX3d& vertices, const Eigen::MatrixX3d& velocities = {});

  // The same for a body moving along a straight segment of its motion (two keyframes of a pose
  // sequence): during this step it went from lerp(from, to, s0) to lerp(from, to, s1),
  // 0 <= s0 <= s1 <= 1. The hierarchy is refitted only when the segment changes, so the many
  // steps between two keyframes cost no refit; its boxes then bound the whole segment. The
  // previous pose should be where the body was (a jump is allowed but not swept).
  void set_pose_on_segment(const Eigen::MatrixX3d& from, const Eigen::MatrixX3d& to, double s0,
                           double s1, const Eigen::MatrixX3d& velocities = {});

  // Largest vertex displacement of the last step (m): a bound on how far any surface point
  // moved in it.
  double last_motion() const { return last_motion_; }
  // The sum of last_motion over every pose so far (m): no surface point moved farther between
  // two moments than the difference of this at them (0 for a body that never moved).
  double total_motion() const { return total_motion_; }
  // FCL refits so far (diagnostics).
  int refit_count() const { return refit_count_; }

  // Body vertices of the current pose that poke through the cloth: x is 3n cloth positions,
  // `triangles` the cloth's triangles. The height of a body vertex over a triangle is measured
  // from the triangle's closest point (the projection when it falls inside the triangle; on an
  // edge for a vertex pushed through a ridge where two triangles fold over it) along the
  // triangle's normal oriented to the body's outside. Reported: heights in (min_height,
  // max_height) (m; min_height 0: through the cloth; −thickness: also closer than the
  // thickness, then only with the projection inside the triangle) within max_height of the
  // triangle; a height above `unchecked_height` only when that closest point lies inside the
  // body (a cloth triangle beyond a body part, such as the far side of a sleeve, or beside it
  // is not pierced). Smaller heights are taken as they are: no body part is that thin, and at a
  // sharp tip under tilted cloth the closest point can lie just outside the body. Broad phase: a
  // uniform grid over the cloth triangles' boxes grown by max_height, built per call (the cloth
  // changes every step; cells the size of the longest cloth edge). Sorted by body vertex; at most
  // one (the highest) per body vertex, or with `every_triangle` each triangle in the band (a vertex
  // under a cloth edge is under both its triangles). The height of one body vertex over one cloth
  // triangle, as find_piercings measures it, with none of its filters (the band, the open edges,
  // the inside check): for a pair the caller already follows. Nothing for a degenerate triangle or
  // one edge-on to the body there. With `cloth`, a closest point on a corner or an edge measures
  // the height along the cloth's pseudo-normal there, as find_piercings does with
  // `pseudo_normal_sides` (else: over the triangle's plane; the simulator's springs use the
  // plane, its count of body vertices through the cloth the pseudo-normal).
  std::optional<BodyPiercing> piercing_of_pair(const Eigen::VectorXd& x,
                                               const std::array<int, 3>& triangle,
                                               int triangle_index, int body_vertex,
                                               const ClothTriangles* cloth = nullptr) const;

  std::vector<BodyPiercing> find_piercings(const Eigen::VectorXd& x, const ClothTriangles& cloth,
                                           double min_height, double max_height,
                                           double unchecked_height = 0.0,
                                           PiercingQueryStats* stats = nullptr,
                                           bool every_triangle = false,
                                           bool pseudo_normal_sides = false) const;

  // Closest point of the current pose within `max_distance` of p (unbounded by default), with
  // the signed distance and outward normal; nothing when the surface is farther than that.
  std::optional<BodyProximity> closest_point(
      const Eigen::Vector3d& p,
      double max_distance = std::numeric_limits<double>::infinity()) const;
  // Signed distance of p to the current pose (negative inside), m.
  double signed_distance(const Eigen::Vector3d& p) const;
  // Velocity of the body surface at barycentric point `barycentric` of `triangle`, m/s.
  Eigen::Vector3d surface_velocity(int triangle, const Eigen::Vector3d& barycentric) const;

  // Contacts of cloth positions `x` (3n, xyz per vertex) with the current pose: every vertex
  // closer than query.thickness, including vertices deep inside. Sorted by vertex. `cache`
  // (optional) skips vertices that cannot have come near since the last query.
  std::vector<BodyContact> find_contacts(const Eigen::VectorXd& x, const ContactQuery& query,
                                         ContactCache* cache = nullptr,
                                         ContactQueryStats* stats = nullptr) const;

  // The same at the end of a step, plus the continuous check: the cloth moved from `x0` (at the
  // previous pose) to `x1` (at the current pose) while the body moved between its last two
  // poses. A vertex whose path passed through the surface gets a contact with crossed = true on
  // the side it came from (entry point carried to the current pose), even if it ended outside
  // on the far side of a thin part. Paths are sampled so that the relative motion between
  // samples stays below query.max_substep_motion.
  std::vector<BodyContact> find_contacts_swept(const Eigen::VectorXd& x0, const Eigen::VectorXd& x1,
                                               const ContactQuery& query,
                                               ContactCache* cache = nullptr,
                                               ContactQueryStats* stats = nullptr) const;

 private:
  struct Topology;
  using Model = fcl::BVHModel<fcl::RSS<double>>;

  // Closest point at pose time t ∈ [0, 1] (0 = previous pose, 1 = current), searching only
  // within `bound`; nothing if the surface is farther. `hint`: a body triangle likely near p
  // (the one found for the same cloth vertex last step, or -1): its distance bounds the search,
  // which then prunes most of the tree and returns the same result (see the definition).
  std::optional<BodyProximity> nearest(const Eigen::Vector3d& p, double t, double bound,
                                       int hint = -1) const;
  // Body vertex at time t ∈ [0, 1] of the current step (0 = previous pose, 1 = current).
  Eigen::Vector3d corner(int vertex, double t) const;
  // FCL refit with prev_vertices = from and vertices = to (#V each).
  void refit(const std::vector<Eigen::Vector3d>& from, const Eigen::MatrixX3d& to);
  Eigen::Vector3d feature_normal(int triangle, TriangleFeature feature, int index, double t) const;
  void update_normals();
  bool outside_box(const Eigen::Vector3d& p) const;
  BodyContact make_contact(int vertex, const BodyProximity& proximity) const;
  // The discrete test at the current pose for one vertex, given what is already known about it.
  void classify_current(int vertex, const Eigen::Vector3d& p, bool known_outside,
                        double clearance_lower_bound, const ContactQuery& query, bool use_margin,
                        ContactCache::Entry* entry, std::vector<BodyContact>& contacts,
                        ContactQueryStats& stats) const;
  void prepare_cache(ContactCache* cache, int vertex_count) const;

  std::unique_ptr<Model> model_;
  std::unique_ptr<Topology> topology_;
  Eigen::MatrixX3i faces_;
  std::vector<Eigen::Vector3d> velocities_;
  // Pseudo-normals of the current pose: per face, per face edge (3 per face), per vertex.
  std::vector<Eigen::Vector3d> face_normals_;
  std::vector<Eigen::Vector3d> edge_normals_;
  std::vector<Eigen::Vector3d> vertex_normals_;
  Eigen::Vector3d box_min_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d box_max_ = Eigen::Vector3d::Zero();
  double normal_epsilon_ = 0.0;  // m: below this offset the feature normal replaces p − c
  int tree_depth_ = 0;           // levels of FCL's tree (search stack size)
  // The step spans [span_from_, span_to_] of the motion FCL's boxes bound (its prev_vertices
  // at 0, vertices at 1).
  double span_from_ = 0.0;
  double span_to_ = 1.0;
  int refit_count_ = 0;
  double last_motion_ = 0.0;
  double total_motion_ = 0.0;  // sum of last_motion over all set_pose calls (cache stamps)
  std::uint64_t id_ = 0;
};

}  // namespace sd::sim
