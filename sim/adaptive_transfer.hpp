#pragma once
// The cloth's state through a batch of 4-8 splits and merges (docs/adaptive.md, "State
// transfer"): masses and velocities move so that total mass and linear momentum are conserved
// exactly (meshing/mesh48_transfer.hpp), a split vertex starts at the midpoint of its diagonal
// (moved out of the body when the midpoint is inside), triangle ages, pins and where every
// vertex comes from follow; after the batch, compaction renumbers it all and says what the
// cloth model can keep.

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "meshing/mesh48.hpp"
#include "sim/cloth_model.hpp"
#include "sim/contact_response.hpp"
#include "sim/simulation.hpp"

namespace sd::sim {

// What a topology change must conserve (mass, momentum) or may change only within a bound
// (energies; see docs/adaptive.md).
struct ConservedQuantities {
  double mass = 0.0;                                   // kg
  Eigen::Vector3d momentum = Eigen::Vector3d::Zero();  // kg·m/s
  EnergyBreakdown energy;                              // J
};

// A pinned vertex: fixed where it started, or driven along a path (metres at time t).
struct PinRecord {
  int vertex = 0;
  std::function<Eigen::Vector3d(double)> path;  // empty: fixed at `fixed`
  Eigen::Vector3d fixed = Eigen::Vector3d::Zero();
};

// The state by vertex and triangle id while a batch of splits and merges is applied (ids are
// Mesh48 slots: they stay valid until compact(), rows grow as new vertices appear).
struct AdaptiveTransfer {
  Eigen::MatrixX3d x, v;
  Eigen::VectorXd m;
  std::vector<double> birth;
  std::vector<PinRecord> pins;
  std::vector<int> pin_of;           // vertex id -> index into pins, or -1
  std::vector<VertexOrigin> origin;  // vertex id -> where it comes from (ids before the batch)
  std::vector<char> touched_blocks;  // made, completed or merged in this batch
  std::vector<char> made_triangles;  // triangle ids made or removed in this batch
  double now = 0.0;
  int moved_off_body = 0;  // split vertices moved out to the contact thickness
  bool changed = false;
  bool measured = false;
  ConservedQuantities before;

  // Whether block k was made, completed or merged in this batch (one level per block per step).
  bool touched(meshing::BlockId k) const;
};

// The state of a compact mesh at the start of a batch: every vertex comes from itself.
AdaptiveTransfer begin_transfer(const meshing::Mesh48& mesh, Eigen::MatrixX3d x, Eigen::MatrixX3d v,
                                Eigen::VectorXd m, std::vector<double> birth,
                                std::vector<PinRecord> pins, double now);

// The rest-shape scale (warp, weft) of input face `source` (1 when source_ease is empty; a
// one-column source_ease is the same both ways).
Eigen::Vector2d face_ease(const Eigen::MatrixXd& source_ease, int source);

// Moves the state through one change made on `mesh` (already applied to it): mass and velocity
// at each triangle's eased density ρ·a·b, the split vertex at the midpoint of its diagonal, ages,
// origins and pins (a split between two pins is pinned at its midpoint, following them).
// root_area_scale: per level-0 triangle (Mesh48::root), its rest area over its 3D rest area (a
// pattern rest shape's, constant over the root since its rest coordinates are affine there), or
// empty: 1. Mass moves at ρ·a·b·s then, as the model lumps it from the rest areas.
void transfer_change(const meshing::BlockChange& change, const meshing::Mesh48& mesh,
                     double area_density, const Eigen::MatrixXd& source_ease,
                     AdaptiveTransfer& state,
                     const Eigen::VectorXd& root_area_scale = Eigen::VectorXd());

// Moves split vertex `e` (row of x) out to the contact thickness if the body is closer than that.
// Returns whether it moved.
bool keep_off_body(int e, Eigen::MatrixX3d& x, const ContactResponse& contact);

// False when splitting block k would put its new vertex so deep inside the body (a chord of a
// coarse block across a sharp body feature, or of a flat block) that moving it out to the
// contact thickness would stretch its children by more than a few per cent.
bool split_stays_off_body(const meshing::Mesh48& mesh, meshing::BlockId k,
                          const Eigen::MatrixX3d& x, const ContactResponse& contact);

// Renumbers the state after mesh.compact() returned `remap`, and says what the cloth model can
// keep: particles that were there before the batch, triangles no change made.
ClothModelReuse compact_transfer(const meshing::Mesh48Remap& remap, AdaptiveTransfer& state);

}  // namespace sd::sim
