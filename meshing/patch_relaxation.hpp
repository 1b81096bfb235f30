#pragma once
// Smoothing the interior of a filled patch without folding it.

#include <Eigen/Core>
#include <array>
#include <functional>
#include <span>
#include <vector>

#include "meshing/quad_mesh.hpp"

namespace sd::meshing {

// Jacobi Laplacian sweeps over the vertices not marked fixed (#V flags, nonzero = fixed): each
// vertex moves to the mean of its edge neighbours. First all sweeps run unguarded and every
// quad is checked once at the end; if some quad's smallest scaled Jacobian (measured against
// reference normals from the starting positions) ended below min(its starting value, 0.05),
// the sweeps run again guarded: the vertices of a quad that would fall below min(its current
// value, 0.05) keep their place for that sweep. So the relaxation never folds a quad it did
// not receive folded, and can only unfold. `project`, when
// set, maps each moved vertex onto the target surface. Stops early once no vertex moves more
// than 1e-3 of the mean edge length in a sweep.
void relax_interior(QuadMesh& mesh, std::span<const char> fixed, int sweeps,
                    const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& project = {});

namespace detail {

// Where the reference normals that tell a quad's front from its back come from: the starting
// positions (vertex normals averaged over 4 rings), or the positions after the unguarded sweeps.
// The start misleads when Coons blocks overlap in a cluster too large for the averaging (a
// layout next to a reflex corner): the whole cluster counts as unfolded, and the guard keeps it
// folded; the sweeps untangle most such clusters. Taken for every fill, the sweeps' normals
// changed 483 of the notched test fills (docs/meshing.md), 179 of them to smaller angles, so
// the start is the default and fill_region turns to the sweeps' normals only when every plan
// it tried keeps inverted quads.
enum class ReferenceNormals { kStart, kAfterSweeps };

// The same on a mesh being built (QuadMeshBuilder's arrays): #V positions, relaxed in place,
// and #Q counter-clockwise quads; saves copying them into a QuadMesh and back.
void relax_interior(std::vector<Eigen::Vector3d>& positions,
                    std::span<const std::array<int, 4>> quads, std::span<const char> fixed,
                    int sweeps,
                    const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& project = {},
                    ReferenceNormals reference = ReferenceNormals::kStart);

}  // namespace detail

}  // namespace sd::meshing
