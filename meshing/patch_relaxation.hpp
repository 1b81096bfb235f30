#pragma once
// Smoothing the interior of a filled patch without folding it.

#include <Eigen/Core>
#include <functional>
#include <span>

#include "meshing/quad_mesh.hpp"

namespace sd::meshing {

// Jacobi Laplacian sweeps over the vertices not marked fixed (#V flags, nonzero = fixed): each
// vertex moves to the mean of its edge neighbours, except the vertices of a quad whose smallest
// scaled Jacobian would fall below min(its current value, 0.05) (measured against reference
// normals from the starting positions), which keep their place for that sweep; so the
// relaxation never folds a quad it did not receive folded, and can only unfold. `project`, when
// set, maps each moved vertex onto the target surface. Stops early once no vertex moves more
// than 1e-3 of the mean edge length in a sweep.
void relax_interior(QuadMesh& mesh, std::span<const char> fixed, int sweeps,
                    const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& project = {});

}  // namespace sd::meshing
