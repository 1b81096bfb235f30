#include "sim/adaptive_transfer.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <initializer_list>
#include <limits>
#include <optional>
#include <string>
#include <utility>

#include "meshing/mesh48_transfer.hpp"

namespace sd::sim {
namespace {

using meshing::BlockChange;
using meshing::BlockId;
using meshing::TriangleId;
using meshing::VertexId;

// How far a split vertex at `e` (on the diagonal b–c) may be lifted off the body. Lifting E by δ
// changes each child triangle (E, apex, b or c) by δ against its height from E, the distance
// from E to the opposite side: a lift square to the cloth stretches it by sqrt(1 + (δ/h)²) − 1,
// 4.4 % at 0.3 × the smallest height (the usual case: the body's normal is near the cloth's),
// a lift along it by up to δ/h, 30 %. A flat parent (an apex near the diagonal) has small
// heights: lifted without this bound, a t-shirt split under the arm was moved 14 mm off the body
// and its children stretched by 340 %.
double safe_lift(const Eigen::Vector3d& e, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                 std::initializer_list<const Eigen::Vector3d*> apexes) {
  constexpr double kMaxLiftPerHeight = 0.3;
  const auto height = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
    const Eigen::Vector3d side = q - p;
    const double length = side.norm();
    return length > 0.0 ? side.cross(e - p).norm() / length : 0.0;
  };
  double shortest = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d* apex : apexes)
    if (apex != nullptr) shortest = std::min({shortest, height(*apex, b), height(*apex, c)});
  return kMaxLiftPerHeight * shortest;
}

}  // namespace

bool AdaptiveTransfer::touched(BlockId k) const {
  const auto i = static_cast<std::size_t>(k.value());
  return i < touched_blocks.size() && touched_blocks[i] != 0;
}

AdaptiveTransfer begin_transfer(const meshing::Mesh48& mesh, Eigen::MatrixX3d x, Eigen::MatrixX3d v,
                                Eigen::VectorXd m, std::vector<double> birth,
                                std::vector<PinRecord> pins, double now) {
  AdaptiveTransfer state;
  state.x = std::move(x);
  state.v = std::move(v);
  state.m = std::move(m);
  state.birth = std::move(birth);
  state.pins = std::move(pins);
  state.pin_of.assign(static_cast<std::size_t>(mesh.vertex_capacity()), -1);
  for (std::size_t k = 0; k < state.pins.size(); ++k)
    state.pin_of[static_cast<std::size_t>(state.pins[k].vertex)] = static_cast<int>(k);
  state.origin.resize(static_cast<std::size_t>(mesh.vertex_capacity()));
  for (int i = 0; i < mesh.vertex_capacity(); ++i)
    state.origin[static_cast<std::size_t>(i)] = {i, i};
  state.now = now;
  return state;
}

Eigen::Vector2d face_ease(const Eigen::MatrixXd& source_ease, int source) {
  if (source_ease.size() == 0) return Eigen::Vector2d::Ones();
  if (source < 0 || source >= source_ease.rows())
    throw InvalidClothError("the ease must be given for every input face (" +
                            std::to_string(source_ease.rows()) + " given, face " +
                            std::to_string(source) + " needed)");
  const double a = source_ease(source, 0);
  return {a, source_ease.cols() > 1 ? source_ease(source, 1) : a};
}

void transfer_change(const BlockChange& change, const meshing::Mesh48& mesh, double area_density,
                     const Eigen::MatrixXd& source_ease, AdaptiveTransfer& state,
                     const Eigen::VectorXd& root_area_scale) {
  state.changed = true;
  // Mass moves at each triangle's eased density ρ·a·b. The ease comes from the input faces the
  // change recorded: by the time a forced split of a chain is applied, its child slots may
  // hold the triangles of the next split.
  const double rho = area_density;
  const Eigen::Vector2d e1 = face_ease(source_ease, change.source_a1);
  const Eigen::Vector2d e2 =
      change.source_a2 >= 0 ? face_ease(source_ease, change.source_a2) : Eigen::Vector2d::Ones();
  const auto area_scale = [&root_area_scale](int root) {
    if (root_area_scale.size() == 0 || root < 0) return 1.0;
    if (root >= root_area_scale.size())
      throw InvalidClothError("the rest-area scale must be given for every level-0 triangle (" +
                              std::to_string(root_area_scale.size()) + " given, triangle " +
                              std::to_string(root) + " needed)");
    return root_area_scale(root);
  };
  const double s1 = area_scale(change.root_a1), s2 = area_scale(change.root_a2);
  meshing::transfer_mass_and_velocity(change, {rho * e1(0) * e1(1) * s1, rho * e2(0) * e2(1) * s2},
                                      state.m, state.v);
  const auto grow = [](auto& vector, int size, auto fill) {
    if (static_cast<int>(vector.size()) < size) vector.resize(static_cast<std::size_t>(size), fill);
  };
  grow(state.birth, mesh.triangle_capacity(), 0.0);
  grow(state.touched_blocks, mesh.block_capacity(), char{0});
  grow(state.made_triangles, mesh.triangle_capacity(), char{0});
  // Parents and children both: a removed slot may be reused by a later change of the batch.
  for (TriangleId t : {change.a1, change.a2, change.a10, change.a11, change.a20, change.a21})
    if (t.valid()) state.made_triangles[static_cast<std::size_t>(t.value())] = 1;
  grow(state.pin_of, mesh.vertex_capacity(), -1);
  grow(state.origin, mesh.vertex_capacity(), VertexOrigin{});
  state.touched_blocks[static_cast<std::size_t>(change.block.value())] = 1;
  const auto pin_index = [&](VertexId v) {
    return state.pin_of[static_cast<std::size_t>(v.value())];
  };

  if (change.kind == BlockChange::Kind::kSplit) {
    // E at the midpoint of BC in world space, as in rest space: each child keeps its parent's
    // deformation gradient, so stretch, shear and the centre of mass are unchanged.
    meshing::place_split_vertex(change, state.x);
    // E comes from the edge BC if both are particles from before the batch.
    const VertexOrigin& from_b = state.origin[static_cast<std::size_t>(change.b.value())];
    const VertexOrigin& from_c = state.origin[static_cast<std::size_t>(change.c.value())];
    state.origin[static_cast<std::size_t>(change.e.value())] =
        from_b.a >= 0 && from_b.a == from_b.b && from_c.a >= 0 && from_c.a == from_c.b
            ? VertexOrigin{from_b.a, from_c.a}
            : VertexOrigin{};
    for (TriangleId t : {change.a10, change.a11, change.a20, change.a21}) {
      if (!t.valid()) continue;
      state.birth[static_cast<std::size_t>(t.value())] = state.now;
      state.touched_blocks[static_cast<std::size_t>(mesh.block(t).value())] = 1;
    }
    state.pin_of[static_cast<std::size_t>(change.e.value())] = -1;
    // A split edge between two pinned vertices (a pinned border) is pinned at its midpoint,
    // following the two pins' paths.
    const int pb = pin_index(change.b), pc = pin_index(change.c);
    if (pb >= 0 && pc >= 0) {
      const PinRecord b = state.pins[static_cast<std::size_t>(pb)];
      const PinRecord c = state.pins[static_cast<std::size_t>(pc)];
      PinRecord e;
      e.vertex = change.e.value();
      e.fixed = 0.5 * (b.fixed + c.fixed);
      if (b.path || c.path)
        e.path = [b, c](double t) {
          const Eigen::Vector3d xb = b.path ? b.path(t) : b.fixed;
          const Eigen::Vector3d xc = c.path ? c.path(t) : c.fixed;
          return Eigen::Vector3d(0.5 * (xb + xc));
        };
      state.pin_of[static_cast<std::size_t>(e.vertex)] = static_cast<int>(state.pins.size());
      state.pins.push_back(std::move(e));
    }
  } else {
    state.origin[static_cast<std::size_t>(change.e.value())] = VertexOrigin{};  // gone
    for (TriangleId t : {change.a1, change.a2})
      if (t.valid()) state.birth[static_cast<std::size_t>(t.value())] = state.now;
    if (const int pe = pin_index(change.e); pe >= 0) {
      state.pins.erase(state.pins.begin() + pe);
      std::fill(state.pin_of.begin(), state.pin_of.end(), -1);
      for (std::size_t k = 0; k < state.pins.size(); ++k)
        state.pin_of[static_cast<std::size_t>(state.pins[k].vertex)] = static_cast<int>(k);
    }
  }
}

bool keep_off_body(int e, Eigen::MatrixX3d& x, const ContactResponse& contact) {
  const double thickness = contact.settings().thickness;
  const Eigen::Vector3d p = x.row(e).transpose();
  // Unbounded: a chord across a sharp edge can put E deeper inside than the thickness.
  const std::optional<BodyProximity> near = contact.collider().closest_point(p);
  if (!near || near->distance >= thickness) return false;
  // Splits whose lift would stretch the children are declined before (split_stays_off_body), so
  // the whole lift is taken: what remains deeper than the safe lift comes from forced splits,
  // and leaving it inside for the start repair to push out failed worse (the t-shirt at L2:
  // 430 m/s within 5 steps).
  const double lift = thickness - near->distance;
  x.row(e) += (lift * near->normal).transpose();
  return true;
}

bool split_stays_off_body(const meshing::Mesh48& mesh, BlockId k, const Eigen::MatrixX3d& x,
                          const ContactResponse& contact) {
  const auto position = [&](VertexId v) -> Eigen::Vector3d { return x.row(v.value()); };
  const auto [b, c] = mesh.diagonal(k);
  const Eigen::Vector3d xb = position(b), xc = position(c);
  const Eigen::Vector3d middle = 0.5 * (xb + xc);
  const std::optional<BodyProximity> near = contact.collider().closest_point(middle);
  if (!near) return true;
  const double lift = contact.settings().thickness - near->distance;
  if (lift <= 0.0) return true;
  const auto [a, d] = mesh.apexes(k);
  const Eigen::Vector3d xa = position(a);
  const Eigen::Vector3d xd = d.valid() ? position(d) : Eigen::Vector3d::Zero();
  return lift <= safe_lift(middle, xb, xc, {&xa, d.valid() ? &xd : nullptr});
}

ClothModelReuse compact_transfer(const meshing::Mesh48Remap& remap, AdaptiveTransfer& state) {
  state.x = meshing::remap_rows(state.x, remap.vertices, remap.vertex_count);
  state.v = meshing::remap_rows(state.v, remap.vertices, remap.vertex_count);
  state.m = meshing::remap_rows(state.m, remap.vertices, remap.vertex_count);
  std::vector<double> birth(static_cast<std::size_t>(remap.triangle_count), 0.0);
  for (std::size_t t = 0; t < remap.triangles.size() && t < state.birth.size(); ++t)
    if (remap.triangles[t] >= 0)
      birth[static_cast<std::size_t>(remap.triangles[t])] = state.birth[t];
  state.birth = std::move(birth);
  for (PinRecord& pin : state.pins)
    pin.vertex = remap.vertices[static_cast<std::size_t>(pin.vertex)];
  std::vector<VertexOrigin> origin(static_cast<std::size_t>(remap.vertex_count));
  for (std::size_t slot = 0; slot < remap.vertices.size() && slot < state.origin.size(); ++slot)
    if (remap.vertices[slot] >= 0)
      origin[static_cast<std::size_t>(remap.vertices[slot])] = state.origin[slot];
  state.origin = std::move(origin);
  // What the model can keep: particles that were there before, triangles no change made.
  ClothModelReuse reuse;
  reuse.previous_vertex.resize(static_cast<std::size_t>(remap.vertex_count));
  for (std::size_t i = 0; i < reuse.previous_vertex.size(); ++i) {
    const VertexOrigin& from = state.origin[i];
    reuse.previous_vertex[i] = from.a >= 0 && from.a == from.b ? from.a : -1;
  }
  reuse.previous_triangle.resize(static_cast<std::size_t>(remap.triangle_count));
  for (std::size_t t = 0; t < remap.triangles.size(); ++t)
    if (const int row = remap.triangles[t]; row >= 0)
      reuse.previous_triangle[static_cast<std::size_t>(row)] =
          t < state.made_triangles.size() && state.made_triangles[t] ? -1 : static_cast<int>(t);
  return reuse;
}

}  // namespace sd::sim
