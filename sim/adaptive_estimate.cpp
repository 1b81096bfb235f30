#include "sim/adaptive_estimate.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <optional>
#include <unordered_map>
#include <utility>

#include "sim/element_forces.hpp"
#include "sim/parallel.hpp"

namespace sd::sim {
namespace {

// θ − θ0 wrapped into (−π, π].
double angle_difference(double theta, double rest) {
  return std::remainder(theta - rest, 2.0 * std::numbers::pi);
}

Eigen::Vector3d row3(const Eigen::VectorXd& flat, int i) {
  return flat.segment<3>(3 * i);
}

}  // namespace

EdgeRestGeometry edge_rest_geometry(const meshing::Mesh48Arrays& arrays, BendRestShape bend_rest) {
  const Eigen::MatrixX4i& edges = arrays.interior_edges;
  const Eigen::MatrixX3d& rest = arrays.rest_positions;
  EdgeRestGeometry out;
  out.angle.resize(edges.rows());
  out.width.resize(edges.rows());
  for (Eigen::Index r = 0; r < edges.rows(); ++r) {
    const Eigen::Vector3d p0 = rest.row(edges(r, 0)), p1 = rest.row(edges(r, 1));
    const Eigen::Vector3d p2 = rest.row(edges(r, 2)), p3 = rest.row(edges(r, 3));
    out.angle(r) = bend_rest == BendRestShape::designed ? dihedral_angle(p0, p1, p2, p3) : 0.0;
    const double areas = 0.5 * ((p1 - p0).cross(p2 - p0).norm() + (p3 - p0).cross(p1 - p0).norm());
    out.width(r) = areas / (p1 - p0).norm();
  }
  return out;
}

double hinge_sag(const meshing::Mesh48& mesh, BendRestShape bend_rest,
                 const std::array<int, 4>& hinge, double theta) {
  std::array<Eigen::Vector3d, 4> p;
  for (int m = 0; m < 4; ++m) p[m] = mesh.rest_position(meshing::VertexId(hinge[m]));
  const double rest =
      bend_rest == BendRestShape::designed ? dihedral_angle(p[0], p[1], p[2], p[3]) : 0.0;
  const double areas =
      0.5 * ((p[1] - p[0]).cross(p[2] - p[0]).norm() + (p[3] - p[0]).cross(p[1] - p[0]).norm());
  return std::abs(angle_difference(theta, rest)) * areas / (p[1] - p[0]).norm() / 8.0;
}

Eigen::VectorXd bend_sags(const meshing::Mesh48Arrays& arrays, const EdgeRestGeometry& rest,
                          const Eigen::VectorXd& x) {
  const Eigen::MatrixX4i& edges = arrays.interior_edges;
  Eigen::VectorXd errors(edges.rows());
  for (Eigen::Index r = 0; r < edges.rows(); ++r) {
    const double theta = dihedral_angle(row3(x, edges(r, 0)), row3(x, edges(r, 1)),
                                        row3(x, edges(r, 2)), row3(x, edges(r, 3)));
    errors(r) = std::abs(angle_difference(theta, rest.angle(r))) * rest.width(r) / 8.0;
  }
  return errors;
}

bool edge_refinable(const meshing::Mesh48Arrays& arrays, Eigen::Index edge, int max_level) {
  return arrays.face_level(arrays.edge_faces(edge, 0)) < max_level ||
         arrays.face_level(arrays.edge_faces(edge, 1)) < max_level;
}

double body_reach(const ContactSettings& contact) {
  return contact.thickness + contact.search_margin;
}

double body_sag(const BodyCollider& body, double reach, const Eigen::Vector3d& xi,
                const Eigen::Vector3d& xj, const BodyProximity* at_i, const BodyProximity* at_j) {
  // Body points under the ends not given; beyond reach of both, no sag. The other end and the
  // midpoint are at most the edge's length farther than the near end.
  std::optional<BodyProximity> near_i, near_j;
  if (at_i == nullptr && at_j == nullptr) {
    near_i = body.closest_point(xi, reach);
    near_j = body.closest_point(xj, reach);
    if (!near_i && !near_j) return 0.0;
  }
  const double bound = reach + (xi - xj).norm();
  if (at_i == nullptr && !near_i) near_i = body.closest_point(xi, bound);
  if (at_j == nullptr && !near_j) near_j = body.closest_point(xj, bound);
  if (at_i == nullptr) at_i = near_i ? &*near_i : nullptr;
  if (at_j == nullptr) at_j = near_j ? &*near_j : nullptr;
  const std::optional<BodyProximity> middle = body.closest_point(0.5 * (xi + xj), bound);
  if (at_i == nullptr || at_j == nullptr || !middle) return 0.0;
  return std::max(0.0, (middle->point - 0.5 * (at_i->point + at_j->point)).dot(middle->normal));
}

// Vertices or edges per chunk at least in BodySagCache::sags: most need no query (a comparison),
// a stale one up to three closest-point searches of a few microseconds.
constexpr int kSagGrain = 512;

Eigen::VectorXd BodySagCache::sags(const meshing::Mesh48Arrays& arrays,
                                   const ContactResponse& contact, double reach,
                                   const Eigen::VectorXd& x, double refine_threshold,
                                   double coarsen_threshold, int max_level) {
  const Eigen::MatrixX4i& edges = arrays.interior_edges;
  Eigen::VectorXd sags = Eigen::VectorXd::Zero(edges.rows());
  // Three closest-point queries per edge are most of adaptivity's cost on a body, and the sag
  // under an edge depends only on where its two ends are: an edge whose ends (and the body)
  // moved less than `settle` since its sag was found keeps it. A body point then moved as
  // little, so the kept sag is off by about 2·settle, the coarsen threshold. A sag that stays
  // below the refine threshold by more than twice the motion is kept too (below).
  const double settle = 0.5 * coarsen_threshold;
  const double body_motion = contact.collider().total_motion();
  memory_.resize(static_cast<std::size_t>(edges.rows()));
  // Only edges that can still be refined need their sag (a block at the finest level cannot
  // split; merges ask body_sag themselves), only the stale ones a new one, and only their
  // vertices a body point.
  const int n = static_cast<int>(x.size() / 3);
  std::vector<unsigned char> stale(static_cast<std::size_t>(edges.rows()), 0);
  std::vector<unsigned char> needed(static_cast<std::size_t>(n), 0);
  for (Eigen::Index r = 0; r < edges.rows(); ++r) {
    if (!edge_refinable(arrays, r, max_level)) continue;
    const Memory& memory = memory_[static_cast<std::size_t>(r)];
    const int i = edges(r, 0), j = edges(r, 1);
    if (memory.valid) {
      const double moved =
          std::max({(row3(x, i) - memory.xi).norm(), (row3(x, j) - memory.xj).norm(),
                    body_motion - memory.body_motion});
      // Near enough to where it was found, or so far below the refine threshold that the motion
      // cannot lift it over (the three body points move as little as what they lie under, so
      // the sag changes by at most twice the motion): such a sag cannot decide a split, and the
      // splits and their order are those a fresh one would give.
      if (moved < settle || memory.sag + 2.0 * moved < refine_threshold) {
        sags(r) = memory.sag;
        ++reused_;
        continue;
      }
    }
    ++computed_;
    stale[static_cast<std::size_t>(r)] = 1;
    needed[static_cast<std::size_t>(i)] = 1;
    needed[static_cast<std::size_t>(j)] = 1;
  }
  // The body point under each of those vertices within reach (bounded queries: most of a
  // garment is not, and FCL prunes by the bound).
  // Both loops on the simulator's threads: each item writes only its own entry, so the result
  // is the same on any thread count.
  std::vector<std::optional<BodyProximity>> under(static_cast<std::size_t>(n));
  parallel_chunks(n, kSagGrain, [&](int, int first, int last) {
    for (int i = first; i < last; ++i)
      if (needed[static_cast<std::size_t>(i)])
        under[static_cast<std::size_t>(i)] = contact.collider().closest_point(row3(x, i), reach);
  });
  parallel_chunks(static_cast<int>(edges.rows()), kSagGrain, [&](int, int first, int last) {
    for (int r = first; r < last; ++r) {
      if (!stale[static_cast<std::size_t>(r)]) continue;
      const int i = edges(r, 0), j = edges(r, 1);
      const std::optional<BodyProximity>& at_i = under[static_cast<std::size_t>(i)];
      const std::optional<BodyProximity>& at_j = under[static_cast<std::size_t>(j)];
      if (at_i || at_j)
        sags(r) = body_sag(contact.collider(), reach, row3(x, i), row3(x, j),
                           at_i ? &*at_i : nullptr, at_j ? &*at_j : nullptr);
      memory_[static_cast<std::size_t>(r)] = {row3(x, i), row3(x, j), body_motion, sags(r), true};
    }
  });
  return sags;
}

void BodySagCache::carry(const Eigen::MatrixX4i& old_edges, const Eigen::MatrixX4i& new_edges,
                         const std::vector<VertexOrigin>& origin) {
  // An edge between two particles that were joined before the change is the same chord, so its
  // body sag is the same; every other edge starts without one.
  const auto key = [](int a, int b) {
    return (static_cast<std::uint64_t>(std::min(a, b)) << 32) |
           static_cast<std::uint32_t>(std::max(a, b));
  };
  std::unordered_map<std::uint64_t, Eigen::Index> before;  // old row of each remembered edge
  for (Eigen::Index r = 0; r < old_edges.rows(); ++r)
    if (static_cast<std::size_t>(r) < memory_.size() && memory_[static_cast<std::size_t>(r)].valid)
      before.emplace(key(old_edges(r, 0), old_edges(r, 1)), r);
  std::vector<Memory> after(static_cast<std::size_t>(new_edges.rows()));
  for (Eigen::Index r = 0; r < new_edges.rows() && !before.empty(); ++r) {
    const VertexOrigin& i = origin[static_cast<std::size_t>(new_edges(r, 0))];
    const VertexOrigin& j = origin[static_cast<std::size_t>(new_edges(r, 1))];
    if (i.a < 0 || i.a != i.b || j.a < 0 || j.a != j.b) continue;  // a new vertex
    const auto found = before.find(key(i.a, j.a));
    if (found == before.end()) continue;
    Memory memory = memory_[static_cast<std::size_t>(found->second)];
    if (old_edges(found->second, 0) != i.a) std::swap(memory.xi, memory.xj);  // ends reversed
    after[static_cast<std::size_t>(r)] = memory;
  }
  memory_ = std::move(after);
}

}  // namespace sd::sim
