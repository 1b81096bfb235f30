#pragma once
// A panel's interior spanned by its boundary curves, then kept out of the body. Cloth cut to a
// panel's outline and sewn along it hangs across hollows (between the legs, under the bust);
// the body pushes it out where it would be inside but never pulls it in. The spanned surface is
// the discrete harmonic one over the panel's quad mesh (each interior vertex at the mean of its
// edge neighbours, boundary fixed): a membrane whose shape the boundary alone decides. The body
// is an obstacle: vertices inside its offset surface are moved onto it and held there, and the
// rest of the membrane is solved again, until no vertex is inside (an active-set solve of the
// obstacle problem in which contacts are only added).

#include <Eigen/Core>
#include <array>
#include <functional>
#include <optional>
#include <span>

#include "meshing/quad_mesh.hpp"

namespace sd::garment {

// Where a point inside the obstacle goes: its closest point on the offset surface; empty when
// the point is outside (or on) it.
using PushOut = std::function<std::optional<Eigen::Vector3d>(const Eigen::Vector3d&)>;
// The same with the spanned surface's unit normal at the point (its quads' diagonal cross
// products summed at the vertex): a push along it keeps neighbours apart where the nearest
// point of a crease would gather them.
using PushAlong =
    std::function<std::optional<Eigen::Vector3d>(const Eigen::Vector3d&, const Eigen::Vector3d&)>;

struct SpannedSurface {
  int rounds = 0;       // harmonic solves after the first (each after a batch of new contacts)
  int contacts = 0;     // vertices held on the offset surface at the end
  bool settled = true;  // false: the round limit was reached with vertices still inside
};

// Moves the vertices not marked in `fixed` (#V flags, nonzero = fixed) to the discrete harmonic
// surface spanned by the fixed ones (uniform edge weights; each connected part of the free
// vertices must touch a fixed one). Throws std::invalid_argument otherwise.
void span_harmonic(meshing::QuadMesh& mesh, std::span<const char> fixed);

// Points of quad `f` where the cloth between its corners is tested against the obstacle: the
// centre, the edge midpoints and the centroids of the four triangles the 4-8 mesh splits it into
// at its centre. A quad whose corners all lie on the offset surface can still cut through a
// bulge of the body between them (a new user's wide shorts: the inner thigh 6 mm inside the
// front leg, every vertex outside).
std::array<Eigen::Vector3d, 9> quad_samples(const meshing::QuadMesh& mesh, Eigen::Index f);

// span_harmonic, then the obstacle: at most `max_rounds` rounds of pushing every free vertex
// that `push_out` moves and solving the others again with those held. Once no vertex is inside,
// a quad with a sample (quad_samples) inside has its free corners moved by that sample's push
// (the deepest one's; a translation of the corners moves the sample by the same) and held, and
// the rest solved again, until no sample is inside either.
// `weights` (#V, or empty for 1 each): each vertex's weight in its neighbours' means, as
// mean_weights (surface_relaxation.hpp) gives them: a ring of quads round an irregular vertex
// then keeps the size of the next ring, where uniform weights shrink it round a vertex of
// valence 3.
SpannedSurface span_over_obstacle(meshing::QuadMesh& mesh, std::span<const char> fixed,
                                  const PushOut& push_out, int max_rounds = 30,
                                  std::span<const double> weights = {});
// The same, each round's pushes given the spanned surface's normals at the vertices (taken after
// that round's harmonic solve, before any push). With `release`, once a round pushes nothing,
// every held vertex whose neighbours' mean `push_along` leaves where it is (outside the obstacle)
// is let go and the rest solved again, until a round neither pushes nor lets go: the membrane
// touches the body only where the body holds it up (an obstacle problem's contact set), not
// wherever it was once pushed.
SpannedSurface span_over_obstacle(meshing::QuadMesh& mesh, std::span<const char> fixed,
                                  const PushAlong& push_along, bool release, int max_rounds = 30,
                                  std::span<const double> weights = {});

}  // namespace sd::garment
