#include "sim/body_collider.hpp"

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/bv/RSS.h>
#include <fcl/math/bv/utility.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "sim/parallel.hpp"

namespace sd::sim {

namespace {

std::atomic<std::uint64_t> next_collider_id{1};

// Distance from p to an RSS (rectangle swept by a sphere): zero inside. The rectangle has its
// corner at To and sides l[0], l[1] along the first two columns of `axis`.
double rss_distance(const fcl::RSS<double>& rss, const Eigen::Vector3d& p) {
  const Eigen::Vector3d q = rss.axis.transpose() * (p - rss.To);
  const double dx = q.x() - std::clamp(q.x(), 0.0, rss.l[0]);
  const double dy = q.y() - std::clamp(q.y(), 0.0, rss.l[1]);
  const double d = std::sqrt(dx * dx + dy * dy + q.z() * q.z()) - rss.r;
  return d > 0.0 ? d : 0.0;
}

void check_pose_matrix(const Eigen::MatrixX3d& vertices, Eigen::Index expected, const char* what) {
  if (vertices.rows() != expected)
    throw InvalidBodyMeshError(std::string("the body ") + what + " has " +
                               std::to_string(vertices.rows()) + " vertices but the body has " +
                               std::to_string(expected) + "; a pose must keep the topology");
  if (!vertices.allFinite())
    throw InvalidBodyMeshError(std::string("the body ") + what + " has a non-finite coordinate");
}

Eigen::Vector3d row(const Eigen::VectorXd& x, Eigen::Index vertex) {
  return x.segment<3>(3 * vertex);
}

// Cloth vertices per chunk of the contact queries at least: a search costs about a microsecond,
// so smaller chunks would cost more to schedule than they save.
constexpr int kVertexGrain = 256;

// The chunks' contacts in chunk order (= vertex order, whatever the threads did) and their
// summed counts.
std::vector<BodyContact> join_chunks(std::vector<std::vector<BodyContact>>& chunk_contacts,
                                     const std::vector<ContactQueryStats>& chunk_stats,
                                     ContactQueryStats& total) {
  std::size_t size = 0;
  for (const auto& c : chunk_contacts) size += c.size();
  std::vector<BodyContact> contacts;
  contacts.reserve(size);
  for (auto& c : chunk_contacts) contacts.insert(contacts.end(), c.begin(), c.end());
  for (const ContactQueryStats& s : chunk_stats) {
    total.vertices += s.vertices;
    total.skipped += s.skipped;
    total.bounded_searches += s.bounded_searches;
    total.full_searches += s.full_searches;
    total.sweep_samples += s.sweep_samples;
    total.crossings += s.crossings;
  }
  return contacts;
}

// visit(i, contacts, stats) for every cloth vertex i < n, in chunks on the simulator's threads;
// the contacts in vertex order and the summed counts in `total`.
template <class Visit>
std::vector<BodyContact> contacts_by_vertex(int n, ContactQueryStats& total, Visit visit) {
  std::vector<ContactQueryStats> chunk_stats(
      static_cast<std::size_t>(chunk_count(n, kVertexGrain)));
  std::vector<std::vector<BodyContact>> chunk_contacts(chunk_stats.size());
  parallel_chunks(n, kVertexGrain, [&](int chunk, int first, int last) {
    for (int i = first; i < last; ++i)
      visit(i, chunk_contacts[static_cast<std::size_t>(chunk)],
            chunk_stats[static_cast<std::size_t>(chunk)]);
  });
  return join_chunks(chunk_contacts, chunk_stats, total);
}

// m: how far past the hint's distance a search still reaches (BodyCollider::nearest). A box's
// distance is computed with rounding (the RSS frames' transforms) and may exceed the exact
// distance of a triangle inside it by that much: a search bounded at the hint's distance exactly
// cut such a box and took another triangle (the 2 cm tee's drape changed). A nanometre
// is far above the rounding and far below any distance the contacts care about.
constexpr double kHintSlack = 1e-9;

}  // namespace

// Adjacency for pseudo-normals at arbitrary pose times (CSR lists).
struct BodyCollider::Topology {
  std::vector<int> vertex_face_start;  // #V + 1
  std::vector<int> vertex_faces;       // faces around each vertex
  std::vector<int> face_edge;          // 3 per face: edge id of edge k = (k, k+1 mod 3)
  std::vector<int> edge_face_start;    // #E + 1
  std::vector<int> edge_faces;         // faces sharing each edge
};

BodyCollider::BodyCollider(const meshing::TriMesh& body) : faces_(body.faces) {
  const Eigen::Index nv = body.vertex_count();
  const Eigen::Index nf = body.face_count();
  if (nv == 0 || nf == 0) throw InvalidBodyMeshError("the body mesh has no triangles");
  if (!body.vertices.allFinite())
    throw InvalidBodyMeshError("the body mesh has a non-finite vertex coordinate");
  if (faces_.minCoeff() < 0 || faces_.maxCoeff() >= nv)
    throw InvalidBodyMeshError("the body mesh has a face whose vertex index is out of range");

  std::vector<fcl::Vector3<double>> points(static_cast<std::size_t>(nv));
  for (Eigen::Index v = 0; v < nv; ++v) points[v] = body.vertices.row(v).transpose();
  std::vector<fcl::Triangle> triangles(static_cast<std::size_t>(nf));
  for (Eigen::Index f = 0; f < nf; ++f)
    triangles[f] = fcl::Triangle(faces_(f, 0), faces_(f, 1), faces_(f, 2));
  model_ = std::make_unique<Model>();
  if (model_->beginModel(static_cast<int>(nf), static_cast<int>(nv)) != fcl::BVH_OK ||
      model_->addSubModel(points, triangles) != fcl::BVH_OK || model_->endModel() != fcl::BVH_OK)
    throw InvalidBodyMeshError("FCL could not build a hierarchy over the body mesh");

  // Adjacency.
  topology_ = std::make_unique<Topology>();
  Topology& topo = *topology_;
  topo.vertex_face_start.assign(static_cast<std::size_t>(nv) + 1, 0);
  for (Eigen::Index f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) ++topo.vertex_face_start[faces_(f, k) + 1];
  for (Eigen::Index v = 0; v < nv; ++v) topo.vertex_face_start[v + 1] += topo.vertex_face_start[v];
  topo.vertex_faces.resize(static_cast<std::size_t>(3 * nf));
  std::vector<int> fill(topo.vertex_face_start.begin(), topo.vertex_face_start.end() - 1);
  for (Eigen::Index f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) topo.vertex_faces[fill[faces_(f, k)]++] = static_cast<int>(f);

  struct HalfEdge {
    int low, high, face, local;
  };
  std::vector<HalfEdge> half_edges;
  half_edges.reserve(static_cast<std::size_t>(3 * nf));
  for (Eigen::Index f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = faces_(f, k);
      const int b = faces_(f, (k + 1) % 3);
      half_edges.push_back({std::min(a, b), std::max(a, b), static_cast<int>(f), k});
    }
  std::sort(half_edges.begin(), half_edges.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return x.low != y.low ? x.low < y.low : x.high < y.high;
  });
  topo.face_edge.assign(static_cast<std::size_t>(3 * nf), -1);
  topo.edge_face_start.push_back(0);
  for (std::size_t i = 0; i < half_edges.size();) {
    std::size_t j = i;
    const int edge = static_cast<int>(topo.edge_face_start.size()) - 1;
    while (j < half_edges.size() && half_edges[j].low == half_edges[i].low &&
           half_edges[j].high == half_edges[i].high) {
      topo.face_edge[3 * half_edges[j].face + half_edges[j].local] = edge;
      topo.edge_faces.push_back(half_edges[j].face);
      ++j;
    }
    topo.edge_face_start.push_back(static_cast<int>(topo.edge_faces.size()));
    i = j;
  }

  // Depth of FCL's tree, to size the search stack (each level leaves at most one sibling).
  std::vector<std::pair<int, int>> walk = {{0, 1}};
  while (!walk.empty()) {
    const auto [node_id, depth] = walk.back();
    walk.pop_back();
    tree_depth_ = std::max(tree_depth_, depth);
    const fcl::BVNode<fcl::RSS<double>>& node = model_->getBV(node_id);
    if (!node.isLeaf()) {
      walk.emplace_back(node.leftChild(), depth + 1);
      walk.emplace_back(node.rightChild(), depth + 1);
    }
  }

  velocities_.assign(static_cast<std::size_t>(nv), Eigen::Vector3d::Zero());
  update_normals();
  const Eigen::Vector3d extent = box_max_ - box_min_;
  normal_epsilon_ = std::max(1e-9 * extent.norm(), 1e-15);
  id_ = next_collider_id.fetch_add(1);
}

BodyCollider::~BodyCollider() = default;
BodyCollider::BodyCollider(BodyCollider&&) noexcept = default;
BodyCollider& BodyCollider::operator=(BodyCollider&&) noexcept = default;

int BodyCollider::vertex_count() const {
  return model_->num_vertices;
}
int BodyCollider::face_count() const {
  return model_->num_tris;
}
const Eigen::MatrixX3i& BodyCollider::faces() const {
  return faces_;
}

Eigen::MatrixX3d BodyCollider::vertices() const {
  Eigen::MatrixX3d result(vertex_count(), 3);
  for (int v = 0; v < vertex_count(); ++v) result.row(v) = corner(v, 1.0).transpose();
  return result;
}

Eigen::MatrixX3d BodyCollider::previous_vertices() const {
  Eigen::MatrixX3d result(vertex_count(), 3);
  for (int v = 0; v < vertex_count(); ++v) result.row(v) = corner(v, 0.0).transpose();
  return result;
}

void BodyCollider::set_pose(const Eigen::MatrixX3d& vertices, const Eigen::MatrixX3d& velocities) {
  check_pose_matrix(vertices, vertex_count(), "pose");
  if (velocities.size() != 0) check_pose_matrix(velocities, vertex_count(), "velocity");

  double motion = 0.0;
  std::vector<Eigen::Vector3d> current(static_cast<std::size_t>(vertex_count()));
  for (int v = 0; v < vertex_count(); ++v) {
    current[v] = corner(v, 1.0);
    motion = std::max(motion, (vertices.row(v).transpose() - current[v]).norm());
  }
  refit(current, vertices);
  span_from_ = 0.0;
  span_to_ = 1.0;

  for (int v = 0; v < vertex_count(); ++v)
    velocities_[v] = velocities.size() != 0 ? Eigen::Vector3d(velocities.row(v).transpose())
                                            : Eigen::Vector3d::Zero();
  last_motion_ = motion;
  total_motion_ += motion;
  update_normals();
}

void BodyCollider::refit(const std::vector<Eigen::Vector3d>& from, const Eigen::MatrixX3d& to) {
  // Refit keeps the tree; FCL fits each box around its triangles at both poses (its
  // prev_vertices and vertices), so the boxes bound every pose in between. Top-down: FCL 0.7's
  // bottom-up refit merges child RSS boxes into boxes that do not contain them (vertices metres
  // outside, measured), and the search would prune the true closest triangle.
  if (model_->beginUpdateModel() != fcl::BVH_OK)
    throw InvalidBodyMeshError("FCL refused to update the body hierarchy");
  for (int v = 0; v < vertex_count(); ++v) model_->updateVertex(to.row(v).transpose());
  // beginUpdateModel made the last fitted pose the previous one; the motion starts from `from`.
  for (int v = 0; v < vertex_count(); ++v) model_->prev_vertices[v] = from[v];
  if (model_->endUpdateModel(true, false) != fcl::BVH_OK)
    throw InvalidBodyMeshError("FCL could not refit the body hierarchy");
  ++refit_count_;
}

void BodyCollider::set_pose_on_segment(const Eigen::MatrixX3d& from, const Eigen::MatrixX3d& to,
                                       double s0, double s1, const Eigen::MatrixX3d& velocities) {
  check_pose_matrix(from, vertex_count(), "segment start");
  check_pose_matrix(to, vertex_count(), "segment end");
  if (velocities.size() != 0) check_pose_matrix(velocities, vertex_count(), "velocity");
  if (!(0.0 <= s0 && s0 <= s1 && s1 <= 1.0))
    throw std::invalid_argument("segment fractions must satisfy 0 <= s0 <= s1 <= 1");

  bool fitted = model_->prev_vertices != nullptr;
  double jump = 0.0;
  double span = 0.0;
  for (int v = 0; v < vertex_count(); ++v) {
    const Eigen::Vector3d a = from.row(v).transpose();
    const Eigen::Vector3d b = to.row(v).transpose();
    fitted = fitted && model_->prev_vertices[v] == a && model_->vertices[v] == b;
    jump = std::max(jump, (a + s0 * (b - a) - corner(v, 1.0)).norm());
    span = std::max(span, (b - a).norm());
  }
  if (!fitted) {
    std::vector<Eigen::Vector3d> start(static_cast<std::size_t>(vertex_count()));
    for (int v = 0; v < vertex_count(); ++v) start[v] = from.row(v).transpose();
    refit(start, to);
  }
  span_from_ = s0;
  span_to_ = s1;
  for (int v = 0; v < vertex_count(); ++v)
    velocities_[v] = velocities.size() != 0 ? Eigen::Vector3d(velocities.row(v).transpose())
                                            : Eigen::Vector3d::Zero();
  last_motion_ = (s1 - s0) * span;
  // A jump between the old pose and the start of this one still moves the surface: the cache's
  // bounds must include it (the sweep cannot, see the header).
  total_motion_ += jump + last_motion_;
  update_normals();
}

void BodyCollider::update_normals() {
  const int nf = face_count();
  const int nv = vertex_count();
  face_normals_.resize(static_cast<std::size_t>(nf));
  for (int f = 0; f < nf; ++f)
    face_normals_[f] = triangle_normal(corner(faces_(f, 0), 1.0), corner(faces_(f, 1), 1.0),
                                       corner(faces_(f, 2), 1.0));
  // Edge pseudo-normal: sum of the incident face normals (each weighted by π).
  const Topology& topo = *topology_;
  edge_normals_.resize(static_cast<std::size_t>(3 * nf));
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int edge = topo.face_edge[3 * f + k];
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int i = topo.edge_face_start[edge]; i < topo.edge_face_start[edge + 1]; ++i)
        sum += face_normals_[topo.edge_faces[i]];
      edge_normals_[3 * f + k] = sum;
    }
  // Vertex pseudo-normal: incident face normals weighted by the face's angle at the vertex.
  vertex_normals_.assign(static_cast<std::size_t>(nv), Eigen::Vector3d::Zero());
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int v = faces_(f, k);
      const double angle = corner_angle(corner(v, 1.0), corner(faces_(f, (k + 1) % 3), 1.0),
                                        corner(faces_(f, (k + 2) % 3), 1.0));
      vertex_normals_[v] += angle * face_normals_[f];
    }

  box_min_ = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  box_max_ = -box_min_;
  for (int v = 0; v < nv; ++v) {
    const Eigen::Vector3d x = corner(v, 1.0);
    box_min_ = box_min_.cwiseMin(x);
    box_max_ = box_max_.cwiseMax(x);
  }
}

Eigen::Vector3d BodyCollider::corner(int vertex, double t) const {
  const Eigen::Vector3d& b = model_->vertices[vertex];
  if (model_->prev_vertices == nullptr) return b;
  const double s = span_from_ + t * (span_to_ - span_from_);
  if (s >= 1.0) return b;
  const Eigen::Vector3d& a = model_->prev_vertices[vertex];
  return a + s * (b - a);
}

Eigen::Vector3d BodyCollider::feature_normal(int triangle, TriangleFeature feature, int index,
                                             double t) const {
  if (t >= 1.0 || model_->prev_vertices == nullptr) {
    switch (feature) {
      case TriangleFeature::face:
        return face_normals_[triangle];
      case TriangleFeature::edge:
        return edge_normals_[3 * triangle + index];
      case TriangleFeature::vertex:
        return vertex_normals_[faces_(triangle, index)];
    }
  }
  // An intermediate pose of a sweep: the same pseudo-normals from interpolated corners.
  const auto normal_at = [&](int f) {
    return triangle_normal(corner(faces_(f, 0), t), corner(faces_(f, 1), t),
                           corner(faces_(f, 2), t));
  };
  const Topology& topo = *topology_;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  switch (feature) {
    case TriangleFeature::face:
      return normal_at(triangle);
    case TriangleFeature::edge: {
      const int edge = topo.face_edge[3 * triangle + index];
      for (int i = topo.edge_face_start[edge]; i < topo.edge_face_start[edge + 1]; ++i)
        sum += normal_at(topo.edge_faces[i]);
      return sum;
    }
    case TriangleFeature::vertex: {
      const int v = faces_(triangle, index);
      for (int i = topo.vertex_face_start[v]; i < topo.vertex_face_start[v + 1]; ++i) {
        const int f = topo.vertex_faces[i];
        int k = 0;
        while (faces_(f, k) != v) ++k;
        sum += corner_angle(corner(v, t), corner(faces_(f, (k + 1) % 3), t),
                            corner(faces_(f, (k + 2) % 3), t)) *
               normal_at(f);
      }
      return sum;
    }
  }
  return sum;
}

bool BodyCollider::outside_box(const Eigen::Vector3d& p) const {
  return (p.array() < box_min_.array()).any() || (p.array() > box_max_.array()).any();
}

std::optional<BodyProximity> BodyCollider::nearest(const Eigen::Vector3d& p, double t, double bound,
                                                   int hint) const {
  // Depth-first branch and bound over FCL's tree, nearer child first. The boxes bound each
  // triangle at both of the last two poses, hence at every pose in between.
  // The hint's distance d_h bounds the nearest distance d*, so starting the search at just above
  // d_h instead of `bound` only prunes subtrees whose box is farther than d_h >= d*: the
  // traversal still reaches, in the same order, the first triangle at d* it reached before (a
  // subtree is cut only at box distance >= best, and best falls to d* only once a triangle at d*
  // was found), and leaves are taken only when strictly nearer. Same triangle, same bits.
  if (hint >= 0 && hint < faces_.rows()) {
    const TriangleClosestPoint cp = closest_point_on_triangle(
        p, corner(faces_(hint, 0), t), corner(faces_(hint, 1), t), corner(faces_(hint, 2), t));
    const double d = std::sqrt(cp.squared_distance);
    if (d + kHintSlack < bound) bound = d + kHintSlack;
  }
  double best = bound;
  int best_triangle = -1;
  TriangleClosestPoint best_point;
  // One entry per level at most, plus the root: sized once per thread, no allocation per query.
  thread_local std::vector<int> stack;
  if (stack.size() < static_cast<std::size_t>(tree_depth_) + 2)
    stack.resize(static_cast<std::size_t>(tree_depth_) + 2);
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const int node_id = stack[--top];
    const fcl::BVNode<fcl::RSS<double>>& node = model_->getBV(node_id);
    if (node.isLeaf()) {
      const int f = node.primitiveId();
      const TriangleClosestPoint cp = closest_point_on_triangle(
          p, corner(faces_(f, 0), t), corner(faces_(f, 1), t), corner(faces_(f, 2), t));
      const double d = std::sqrt(cp.squared_distance);
      if (d < best) {
        best = d;
        best_triangle = f;
        best_point = cp;
      }
      continue;
    }
    int near_child = node.leftChild();
    int far_child = node.rightChild();
    double near_distance = rss_distance(model_->getBV(near_child).bv, p);
    double far_distance = rss_distance(model_->getBV(far_child).bv, p);
    if (far_distance < near_distance) {
      std::swap(near_child, far_child);
      std::swap(near_distance, far_distance);
    }
    // Far child first, so that the near one is searched next and tightens `best` early.
    if (far_distance < best) stack[top++] = far_child;
    if (near_distance < best) stack[top++] = near_child;
  }
  if (best_triangle < 0) return std::nullopt;

  BodyProximity result;
  result.triangle = best_triangle;
  result.point = best_point.point;
  result.barycentric = best_point.barycentric;
  result.feature = best_point.feature;
  result.feature_index = best_point.index;
  Eigen::Vector3d pseudo_normal =
      feature_normal(best_triangle, best_point.feature, best_point.index, t);
  if (!(pseudo_normal.squaredNorm() > 0.0))
    pseudo_normal =
        triangle_normal(corner(faces_(best_triangle, 0), t), corner(faces_(best_triangle, 1), t),
                        corner(faces_(best_triangle, 2), t));
  const Eigen::Vector3d offset = p - best_point.point;
  const double sign = offset.dot(pseudo_normal) >= 0.0 ? 1.0 : -1.0;
  result.distance = sign * best;
  // The gradient of the signed distance, p − c, is the shortest way out; on the surface itself
  // it is undefined and the feature's pseudo-normal takes over.
  if (best > normal_epsilon_)
    result.normal = sign * offset / best;
  else if (pseudo_normal.squaredNorm() > 0.0)
    result.normal = pseudo_normal.normalized();
  return result;
}

std::optional<BodyProximity> BodyCollider::closest_point(const Eigen::Vector3d& p,
                                                         double max_distance) const {
  return nearest(p, 1.0, max_distance);
}

double BodyCollider::signed_distance(const Eigen::Vector3d& p) const {
  const std::optional<BodyProximity> hit = nearest(p, 1.0, std::numeric_limits<double>::infinity());
  return hit ? hit->distance : std::numeric_limits<double>::quiet_NaN();  // only for a NaN point
}

Eigen::Vector3d BodyCollider::surface_velocity(int triangle,
                                               const Eigen::Vector3d& barycentric) const {
  return barycentric[0] * velocities_[faces_(triangle, 0)] +
         barycentric[1] * velocities_[faces_(triangle, 1)] +
         barycentric[2] * velocities_[faces_(triangle, 2)];
}

BodyContact BodyCollider::make_contact(int vertex, const BodyProximity& proximity) const {
  BodyContact contact;
  contact.vertex = vertex;
  contact.triangle = proximity.triangle;
  contact.point = proximity.point;
  contact.normal = proximity.normal;
  contact.distance = proximity.distance;
  contact.body_velocity = surface_velocity(proximity.triangle, proximity.barycentric);
  return contact;
}

void BodyCollider::prepare_cache(ContactCache* cache, int vertex_count) const {
  if (cache == nullptr) return;
  if (cache->vertex_count() != vertex_count || cache->collider_id_ != id_) {
    cache->entries_.assign(static_cast<std::size_t>(vertex_count), ContactCache::Entry{});
    cache->collider_id_ = id_;
  }
}

void BodyCollider::classify_current(int vertex, const Eigen::Vector3d& p, bool known_outside,
                                    double clearance_lower_bound, const ContactQuery& query,
                                    bool use_margin, ContactCache::Entry* entry,
                                    std::vector<BodyContact>& contacts,
                                    ContactQueryStats& stats) const {
  using State = ContactCache::State;
  if (known_outside && clearance_lower_bound >= query.thickness) {
    ++stats.skipped;
    return;
  }
  const double bound = query.thickness + (use_margin ? query.search_margin : 0.0);
  const int hint = entry != nullptr ? entry->triangle : -1;
  std::optional<BodyProximity> found = nearest(p, 1.0, bound, hint);
  ++stats.bounded_searches;
  if (!found && !known_outside && !outside_box(p)) {
    // Nothing within reach: far outside, or deep inside. Only a full search tells.
    found = nearest(p, 1.0, std::numeric_limits<double>::infinity(), hint);
    ++stats.full_searches;
  }
  if (found) {
    if (found->distance < query.thickness) contacts.push_back(make_contact(vertex, *found));
    if (entry != nullptr)
      *entry = {p, std::abs(found->distance), total_motion_,
                found->distance >= 0.0 ? State::outside : State::inside, found->triangle};
  } else if (entry != nullptr) {
    *entry = {p, bound, total_motion_, State::outside};
  }
}

std::vector<BodyContact> BodyCollider::find_contacts(const Eigen::VectorXd& x,
                                                     const ContactQuery& query, ContactCache* cache,
                                                     ContactQueryStats* stats) const {
  if (x.size() % 3 != 0)
    throw std::invalid_argument("cloth positions must hold 3 coordinates per vertex");
  if (!x.allFinite())
    throw std::invalid_argument("a cloth position is not finite (the simulation diverged?)");
  if (!(query.thickness >= 0.0) || !(query.search_margin >= 0.0))
    throw std::invalid_argument("the collision thickness and search margin must be >= 0");
  const int n = static_cast<int>(x.size() / 3);
  prepare_cache(cache, n);
  ContactQueryStats totals;
  std::vector<BodyContact> found = contacts_by_vertex(
      n, totals, [&](int i, std::vector<BodyContact>& contacts, ContactQueryStats& local) {
        const Eigen::Vector3d p = row(x, i);
        ++local.vertices;
        ContactCache::Entry* entry = cache != nullptr ? &cache->entries_[i] : nullptr;
        bool known_outside = false;
        double lower_bound = 0.0;
        if (entry != nullptr && entry->state == ContactCache::State::outside) {
          lower_bound = entry->clearance - (p - entry->position).norm() -
                        std::abs(total_motion_ - entry->stamp);
          known_outside = lower_bound > 0.0;
        }
        classify_current(i, p, known_outside, lower_bound, query, cache != nullptr, entry, contacts,
                         local);
      });
  totals.contacts = static_cast<int>(found.size());
  if (stats != nullptr) *stats = totals;
  return found;
}

std::vector<BodyContact> BodyCollider::find_contacts_swept(const Eigen::VectorXd& x0,
                                                           const Eigen::VectorXd& x1,
                                                           const ContactQuery& query,
                                                           ContactCache* cache,
                                                           ContactQueryStats* stats) const {
  if (x0.size() != x1.size() || x1.size() % 3 != 0)
    throw std::invalid_argument(
        "start and end cloth positions must have the same size, 3 coordinates per vertex");
  if (!x0.allFinite() || !x1.allFinite())
    throw std::invalid_argument("a cloth position is not finite (the simulation diverged?)");
  if (!(query.thickness >= 0.0) || !(query.search_margin >= 0.0) ||
      !(query.max_substep_motion > 0.0) || query.max_substeps < 1)
    throw std::invalid_argument(
        "the collision thickness and margin must be >= 0, the sub-step motion > 0 and the "
        "sub-step count >= 1");
  using State = ContactCache::State;
  const double infinity = std::numeric_limits<double>::infinity();
  const int n = static_cast<int>(x1.size() / 3);
  prepare_cache(cache, n);
  const double stamp_before = total_motion_ - last_motion_;  // cache stamp of the previous pose
  ContactQueryStats totals;
  std::vector<BodyContact> found = contacts_by_vertex(
      n, totals, [&](int i, std::vector<BodyContact>& contacts, ContactQueryStats& local) {
        const Eigen::Vector3d p0 = row(x0, i);
        const Eigen::Vector3d p1 = row(x1, i);
        ++local.vertices;
        ContactCache::Entry* entry = cache != nullptr ? &cache->entries_[i] : nullptr;
        // Bound on how fast the vertex-to-body distance can change over the step (per unit of t).
        const double relative_motion = (p1 - p0).norm() + last_motion_;

        // 1. The start of the path: outside, and with what clearance?
        bool outside_at_start = false;
        bool sign_known = false;
        double clearance = 0.0;
        if (entry != nullptr && entry->state == State::outside) {
          const double lower_bound = entry->clearance - (p0 - entry->position).norm() -
                                     std::abs(stamp_before - entry->stamp);
          if (lower_bound > 0.0) {
            outside_at_start = sign_known = true;
            clearance = lower_bound;
          }
        }
        if (!sign_known && relative_motion > 0.0) {
          const std::optional<BodyProximity> start =
              nearest(p0, 0.0, relative_motion, entry != nullptr ? entry->triangle : -1);
          ++local.bounded_searches;
          if (start) {
            sign_known = true;
            outside_at_start = start->distance >= 0.0;
            clearance = std::abs(start->distance);
          }
          // Nothing within reach: the surface cannot meet the path this step, whichever side.
        }

        // 2. Walk the path while a crossing is possible: samples at t = k/K, skipping samples the
        //    clearance of the last one already rules out.
        bool known_outside_at_end = false;
        double end_lower_bound = 0.0;
        std::optional<BodyProximity> entry_point;
        if (sign_known && outside_at_start) {
          if (clearance > relative_motion) {
            known_outside_at_end = true;
            end_lower_bound = clearance - relative_motion;
          } else {
            const int samples =
                std::clamp(static_cast<int>(std::ceil(relative_motion / query.max_substep_motion)),
                           1, query.max_substeps);
            double t_last = 0.0;
            double clearance_last = clearance;
            bool clear_to_end = false;
            for (int k = 1; k <= samples; ++k) {
              const double t = static_cast<double>(k) / samples;
              if (clearance_last - relative_motion * (t - t_last) > 0.0) continue;
              // Deep enough to catch a point that crossed since the last clear sample, far enough
              // to clear the rest of the step when nothing is found.
              const double bound =
                  std::max(relative_motion / samples, relative_motion * (1.0 - t)) +
                  query.thickness;
              const std::optional<BodyProximity> sample =
                  nearest(p0 + t * (p1 - p0), t, bound, entry != nullptr ? entry->triangle : -1);
              ++local.sweep_samples;
              if (!sample) {
                clear_to_end = true;
                end_lower_bound = bound - relative_motion * (1.0 - t);
                break;
              }
              if (sample->distance < 0.0) {
                entry_point = sample;
                break;
              }
              clearance_last = sample->distance;
              t_last = t;
            }
            if (!entry_point) {
              known_outside_at_end = true;
              if (!clear_to_end)
                end_lower_bound = std::max(0.0, clearance_last - relative_motion * (1.0 - t_last));
            }
          }
        }

        // 3. A vertex that went in: carry the entry point to the current pose and decide whether
        //    it is still behind the surface it entered.
        if (entry_point) {
          const Eigen::Vector3d& w = entry_point->barycentric;
          const int f = entry_point->triangle;
          const Eigen::Vector3d point = w[0] * corner(faces_(f, 0), 1.0) +
                                        w[1] * corner(faces_(f, 1), 1.0) +
                                        w[2] * corner(faces_(f, 2), 1.0);
          Eigen::Vector3d normal =
              feature_normal(f, entry_point->feature, entry_point->feature_index, 1.0);
          if (!(normal.squaredNorm() > 0.0)) normal = face_normals_[f];
          normal.normalize();
          const double behind = (p1 - point).dot(normal);
          const BodyProximity end = *nearest(p1, 1.0, infinity, entry_point->triangle);
          ++local.full_searches;
          // Came back out on the entry side, or ended inside with the nearest surface facing the
          // way it came in: the ordinary contact is right. Otherwise it tunnelled.
          const bool tunnelled =
              behind < 0.0 && (end.distance >= 0.0 || end.normal.dot(normal) < 0.0);
          if (tunnelled) {
            BodyContact contact;
            contact.vertex = i;
            contact.triangle = f;
            contact.point = point;
            contact.normal = normal;
            contact.distance = behind;
            contact.body_velocity = surface_velocity(f, w);
            contact.crossed = true;
            contacts.push_back(contact);
            ++local.crossings;
            if (entry != nullptr) *entry = ContactCache::Entry{};
          } else {
            if (end.distance < query.thickness) contacts.push_back(make_contact(i, end));
            if (entry != nullptr)
              *entry = {p1, std::abs(end.distance), total_motion_,
                        end.distance >= 0.0 ? State::outside : State::inside, end.triangle};
          }
          return;
        }

        // 4. Everything else: the discrete test at the end of the step.
        classify_current(i, p1, known_outside_at_end, end_lower_bound, query, cache != nullptr,
                         entry, contacts, local);
      });
  totals.contacts = static_cast<int>(found.size());
  if (stats != nullptr) *stats = totals;
  return found;
}

}  // namespace sd::sim
