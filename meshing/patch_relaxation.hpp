#pragma once
// Smoothing the interior of a filled patch without folding it.

#include <Eigen/Core>
#include <functional>
#include <span>

#include "meshing/quad_mesh.hpp"

namespace sd::meshing {

// Gauss–Seidel Laplacian sweeps over the vertices not marked fixed (#V flags, nonzero = fixed): each vertex
// moves toward the mean of its edge neighbours, but a move is rejected when it would push the
// smallest scaled Jacobian of the vertex's quads below min(current, 0.05), measured against
// the vertex normals at the start of the sweep; so the relaxation never folds a quad it did not
// receive folded, and can only unfold. `project`, when set, maps each moved vertex back onto
// the target surface after the move. Stops early once no vertex moves more than 1e-3 of the
// mean edge length in a sweep.
void relax_interior(QuadMesh& mesh, std::span<const char> fixed, int sweeps,
                    const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& project = {});

}  // namespace sd::meshing
