#pragma once
// Unfolding the quads of a filled panel that lies on a curved surface. The quad filler relaxes
// in 3D and projects onto the body's offset surface after each sweep; where a panel turns
// sharply over a curved part of the body (a shoulder tip, the crotch) that can leave quads
// folded over. Here each free vertex of a folded quad is moved, one at a time, to the best of a
// few candidate places (the mean of the parallelogram completions of its quads, the mean of its
// neighbours, and halfway to each), lifted onto the surface, judged by the worst corner of its
// quads measured against the surface normal (not the mesh's own normals, which a fold flips).

#include <Eigen/Core>
#include <functional>
#include <span>

#include "meshing/quad_mesh.hpp"

namespace sd::garment {

struct UntangleResult {
  int folded_before = 0;  // quads with a corner below zero, against the surface normal
  int folded_after = 0;
  int moves = 0;  // accepted vertex moves
};

// `fixed` (#V flags, nonzero = fixed) marks the boundary; `project` maps a point onto the
// surface (may be empty: then candidates are used as they are); `normal` gives the unit
// outward surface normal near a point. At most `sweeps` passes over the folded quads.
UntangleResult untangle_on_surface(
    meshing::QuadMesh& mesh, std::span<const char> fixed,
    const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& project,
    const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& normal, int sweeps = 50);

}  // namespace sd::garment
