#pragma once
// The error estimate of adaptive detail (docs/adaptive.md, "The estimate"): per interior edge of
// a 4-8 mesh, how far the cloth is from a smooth surface there. Two parts, the larger wins:
//   bend sag  ε = |θ − θ0|·w/8, θ the dihedral angle, θ0 its rest value, w = (A1 + A2)/|e| the
//             mean height of the two rest triangles (the distance between the mesh and a
//             circular arc through them);
//   body sag  how far the body's surface under the edge bulges out of the chord between the body
//             points under its two ends: the sag the edge will have once the cloth lies there.
// Body sags cost closest-point queries; a BodySagCache keeps each edge's last one while its ends
// and the body stay put.

#include <Eigen/Core>
#include <array>
#include <vector>

#include "meshing/mesh48.hpp"
#include "sim/body_collider.hpp"
#include "sim/cloth_model.hpp"
#include "sim/contact_response.hpp"
#include "sim/simulation.hpp"

namespace sd::sim {

// Rest geometry of every interior edge (rows of Mesh48Arrays::interior_edges): the rest dihedral
// angle θ0 (0 for a flat rest shape) and the width w = (A1 + A2)/|e|, metres.
struct EdgeRestGeometry {
  Eigen::VectorXd angle;
  Eigen::VectorXd width;
};
EdgeRestGeometry edge_rest_geometry(const meshing::Mesh48Arrays& arrays, BendRestShape bend_rest);

// Bend sag |θ − θ0|·w/8 of one hinge (element_forces' vertex order (x0, x1, x2), (x1, x0, x3), by
// vertex id of `mesh`) at dihedral angle theta, from the mesh's rest positions.
double hinge_sag(const meshing::Mesh48& mesh, BendRestShape bend_rest,
                 const std::array<int, 4>& hinge, double theta);

// Bend sag of every interior edge at positions x (3·#V, flat), metres.
Eigen::VectorXd bend_sags(const meshing::Mesh48Arrays& arrays, const EdgeRestGeometry& rest,
                          const Eigen::VectorXd& x);

// Whether interior edge `edge` has a triangle below max_level (so it can still be refined).
bool edge_refinable(const meshing::Mesh48Arrays& arrays, Eigen::Index edge, int max_level);

// m: cloth within this distance of the body gets a body sag (contact thickness + search margin).
double body_reach(const ContactSettings& contact);

// Body sag under the chord xi–xj, 0 when neither end is within `reach` of the body; at_i, at_j:
// the body points under the ends if already known.
double body_sag(const BodyCollider& body, double reach, const Eigen::Vector3d& xi,
                const Eigen::Vector3d& xj, const BodyProximity* at_i = nullptr,
                const BodyProximity* at_j = nullptr);

// The body sag each interior edge was last given, with where its ends and the body were then.
class BodySagCache {
 public:
  // Body sag of every refinable interior edge (0 for the others) at positions x, for cloth within
  // `reach` of the body (body_reach of the simulation's contact settings). An edge whose
  // ends and the body moved less than half coarsen_threshold since its sag was found keeps it;
  // so does one whose sag plus twice that motion stays below refine_threshold (it cannot decide
  // a split). The others are queried: one bounded closest point per end, one per midpoint.
  Eigen::VectorXd sags(const meshing::Mesh48Arrays& arrays, const ContactResponse& contact,
                       double reach, const Eigen::VectorXd& x, double refine_threshold,
                       double coarsen_threshold, int max_level);
  // After a topology change: keeps the memory of every edge whose two ends were joined before
  // (old_edges: the interior edges before it; origin: per new vertex, its old id).
  void carry(const Eigen::MatrixX4i& old_edges, const Eigen::MatrixX4i& new_edges,
             const std::vector<VertexOrigin>& origin);
  void clear() { memory_.clear(); }
  long long computed() const { return computed_; }  // sags found by queries
  long long reused() const { return reused_; }      // sags kept from an earlier step

 private:
  struct Memory {
    Eigen::Vector3d xi = Eigen::Vector3d::Zero(), xj = Eigen::Vector3d::Zero();
    double body_motion = 0.0;  // BodyCollider::total_motion at the time
    double sag = 0.0;
    bool valid = false;
  };
  std::vector<Memory> memory_;  // per interior edge
  long long computed_ = 0, reused_ = 0;
};

}  // namespace sd::sim
