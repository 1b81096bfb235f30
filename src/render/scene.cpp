#include "src/render/scene.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_map>
#include <utility>

namespace sd::render {
namespace {

// Samples of matplotlib's viridis at t = 0, 1/8, ..., 1 (sRGB), interpolated linearly.
constexpr std::array<std::array<float, 3>, 9> kViridis{{
    {0.267f, 0.005f, 0.329f},
    {0.283f, 0.141f, 0.458f},
    {0.254f, 0.265f, 0.530f},
    {0.207f, 0.372f, 0.553f},
    {0.164f, 0.471f, 0.558f},
    {0.128f, 0.567f, 0.551f},
    {0.135f, 0.659f, 0.518f},
    {0.267f, 0.749f, 0.441f},
    {0.993f, 0.906f, 0.144f},
}};

// Distinct, saturated colours for discrete levels (a qualitative palette, Tableau-10 like).
constexpr std::array<std::array<float, 3>, 10> kLevelColours{{
    {0.122f, 0.467f, 0.706f},
    {1.000f, 0.498f, 0.055f},
    {0.173f, 0.627f, 0.173f},
    {0.839f, 0.153f, 0.157f},
    {0.580f, 0.404f, 0.741f},
    {0.549f, 0.337f, 0.294f},
    {0.890f, 0.467f, 0.761f},
    {0.498f, 0.498f, 0.498f},
    {0.737f, 0.741f, 0.133f},
    {0.090f, 0.745f, 0.812f},
}};

// Soft fabric colours for panels: distinguishable next to each other, not garish when lit.
constexpr std::array<std::array<float, 3>, 8> kPanelColours{{
    {0.36f, 0.52f, 0.74f},
    {0.86f, 0.55f, 0.38f},
    {0.48f, 0.68f, 0.46f},
    {0.80f, 0.42f, 0.50f},
    {0.62f, 0.54f, 0.78f},
    {0.85f, 0.75f, 0.42f},
    {0.40f, 0.70f, 0.72f},
    {0.66f, 0.50f, 0.42f},
}};

Eigen::Vector3f to_vector(const std::array<float, 3>& c) {
  return {c[0], c[1], c[2]};
}

std::uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) |
         static_cast<std::uint32_t>(b);
}

Eigen::MatrixX2i unique_edges(std::vector<std::pair<int, int>> edges) {
  for (auto& [a, b] : edges)
    if (a > b) std::swap(a, b);
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  Eigen::MatrixX2i out(static_cast<Eigen::Index>(edges.size()), 2);
  for (size_t i = 0; i < edges.size(); ++i)
    out.row(static_cast<Eigen::Index>(i)) << edges[i].first, edges[i].second;
  return out;
}

}  // namespace

Eigen::Vector3f colour_map(ColourMap map, double t) {
  if (map == ColourMap::kLevels) {
    const long level = std::lround(std::max(0.0, t));
    return to_vector(kLevelColours[static_cast<size_t>(level) % kLevelColours.size()]);
  }
  const double s = std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0) * (kViridis.size() - 1);
  const size_t i = std::min(static_cast<size_t>(s), kViridis.size() - 2);
  const float w = static_cast<float>(s - static_cast<double>(i));
  return (1 - w) * to_vector(kViridis[i]) + w * to_vector(kViridis[i + 1]);
}

Eigen::Vector3f panel_palette_colour(int slot) {
  if (slot < 0) throw std::invalid_argument(fmt::format("palette slot {} is negative", slot));
  return to_vector(kPanelColours[static_cast<size_t>(slot) % kPanelColours.size()]);
}

std::vector<int> panel_palette_slots(const Eigen::VectorXi& panel_ids,
                                     const Eigen::MatrixXi& faces) {
  if (faces.rows() != panel_ids.size())
    throw std::invalid_argument(
        fmt::format("{} panel ids for {} faces", panel_ids.size(), faces.rows()));
  if (panel_ids.size() == 0) return {};
  if (panel_ids.minCoeff() < 0)
    throw std::invalid_argument(fmt::format("panel id {} is negative", panel_ids.minCoeff()));
  const size_t panels = static_cast<size_t>(panel_ids.maxCoeff()) + 1;
  // Sewn neighbours: the panels on either side of each edge.
  std::unordered_map<std::uint64_t, int> edge_panel;
  std::vector<std::vector<int>> sewn(panels);
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (Eigen::Index k = 0; k < faces.cols(); ++k) {
      const int a = faces(f, k), b = faces(f, (k + 1) % faces.cols());
      const auto [it, added] = edge_panel.emplace(edge_key(a, b), panel_ids[f]);
      if (!added && it->second != panel_ids[f]) {
        sewn[static_cast<size_t>(it->second)].push_back(panel_ids[f]);
        sewn[static_cast<size_t>(panel_ids[f])].push_back(it->second);
      }
    }
  const size_t palette = kPanelColours.size();
  std::vector<int> slot(panels, -1);
  for (size_t p = 0; p < panels; ++p) {
    std::vector<char> taken(palette, 0);
    for (int q : sewn[p])
      if (slot[static_cast<size_t>(q)] >= 0)
        taken[static_cast<size_t>(slot[static_cast<size_t>(q)])] = 1;
    slot[p] = static_cast<int>(p % palette);
    for (size_t k = 0; k < palette; ++k) {
      const size_t s = (p + k) % palette;
      if (!taken[s]) {
        slot[p] = static_cast<int>(s);
        break;
      }
    }
  }
  return slot;
}

Eigen::MatrixX3f panel_colours(const Eigen::VectorXi& panel_ids, const Eigen::MatrixXi& faces) {
  const std::vector<int> slot = panel_palette_slots(panel_ids, faces);
  Eigen::MatrixX3f out(panel_ids.size(), 3);
  for (Eigen::Index f = 0; f < panel_ids.size(); ++f)
    out.row(f) = panel_palette_colour(slot[static_cast<size_t>(panel_ids[f])]).transpose();
  return out;
}

Eigen::MatrixX3f panel_colours(const Eigen::VectorXi& panel_ids) {
  Eigen::MatrixX3f out(panel_ids.size(), 3);
  for (Eigen::Index f = 0; f < panel_ids.size(); ++f) {
    if (panel_ids[f] < 0)
      throw std::invalid_argument(
          fmt::format("panel id {} of face {} is negative", panel_ids[f], f));
    out.row(f) = to_vector(kPanelColours[static_cast<size_t>(panel_ids[f]) % kPanelColours.size()])
                     .transpose();
  }
  return out;
}

Eigen::MatrixX2i triangle_edges(const meshing::TriMesh& mesh) {
  std::vector<std::pair<int, int>> edges;
  edges.reserve(static_cast<size_t>(mesh.face_count()) * 3);
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f)
    for (int k = 0; k < 3; ++k) edges.emplace_back(mesh.faces(f, k), mesh.faces(f, (k + 1) % 3));
  return unique_edges(std::move(edges));
}

Eigen::MatrixX2i quad_edges(const Eigen::MatrixX4i& quads) {
  std::vector<std::pair<int, int>> edges;
  edges.reserve(static_cast<size_t>(quads.rows()) * 4);
  for (Eigen::Index q = 0; q < quads.rows(); ++q)
    for (int k = 0; k < 4; ++k) edges.emplace_back(quads(q, k), quads(q, (k + 1) % 4));
  return unique_edges(std::move(edges));
}

Eigen::MatrixX3i triangulate_quads(const Eigen::MatrixX4i& quads) {
  Eigen::MatrixX3i faces(2 * quads.rows(), 3);
  for (Eigen::Index q = 0; q < quads.rows(); ++q) {
    faces.row(2 * q) << quads(q, 0), quads(q, 1), quads(q, 2);
    faces.row(2 * q + 1) << quads(q, 0), quads(q, 2), quads(q, 3);
  }
  return faces;
}

Eigen::VectorXd edge_values_from_faces(const meshing::TriMesh& mesh, const Eigen::MatrixX2i& edges,
                                       const Eigen::VectorXd& face_values) {
  if (face_values.size() != mesh.face_count())
    throw std::invalid_argument(fmt::format("{} face values for a mesh of {} triangles",
                                            face_values.size(), mesh.face_count()));
  std::unordered_map<std::uint64_t, double> largest;
  largest.reserve(static_cast<size_t>(mesh.face_count()) * 3);
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f)
    for (int k = 0; k < 3; ++k) {
      const auto [it, inserted] = largest.try_emplace(
          edge_key(mesh.faces(f, k), mesh.faces(f, (k + 1) % 3)), face_values[f]);
      if (!inserted) it->second = std::max(it->second, face_values[f]);
    }
  Eigen::VectorXd out(edges.rows());
  for (Eigen::Index e = 0; e < edges.rows(); ++e) {
    const auto it = largest.find(edge_key(edges(e, 0), edges(e, 1)));
    out[e] = it == largest.end() ? std::numeric_limits<double>::quiet_NaN() : it->second;
  }
  return out;
}

meshing::BoundingBox scene_bounds(const Scene& scene) {
  meshing::BoundingBox box;
  bool first = true;
  for (const SceneMesh& m : scene.meshes) {
    if (m.mesh.vertex_count() == 0) continue;
    const meshing::BoundingBox b = meshing::bounding_box(m.mesh);
    box.min = first ? b.min : box.min.cwiseMin(b.min);
    box.max = first ? b.max : box.max.cwiseMax(b.max);
    first = false;
  }
  return box;
}

void validate_scene(const Scene& scene) {
  for (size_t i = 0; i < scene.meshes.size(); ++i) {
    const SceneMesh& m = scene.meshes[i];
    const Eigen::Index nv = m.mesh.vertex_count(), nf = m.mesh.face_count();
    const auto fail = [i](const std::string& what) {
      throw std::invalid_argument(fmt::format("scene mesh {}: {}", i, what));
    };
    if (!m.mesh.vertices.allFinite()) fail("has NaN or infinite vertex coordinates");
    if (nf > 0 && (m.mesh.faces.minCoeff() < 0 || m.mesh.faces.maxCoeff() >= nv))
      fail("a face index is out of range");
    if (m.face_colours.rows() != 0 && m.face_colours.rows() != nf)
      fail(fmt::format("{} face colours for {} triangles", m.face_colours.rows(), nf));
    if (!m.wireframe) continue;
    const Wireframe& w = *m.wireframe;
    if (w.edges.rows() > 0 && (w.edges.minCoeff() < 0 || w.edges.maxCoeff() >= nv))
      fail("a wireframe edge index is out of range");
    if (w.edge_values.size() != 0 && w.face_values.size() != 0)
      fail("wireframe has both edge and face values; give one");
    if (w.edge_values.size() != 0 && w.edge_values.size() != w.edges.rows())
      fail(fmt::format("{} edge values for {} edges", w.edge_values.size(), w.edges.rows()));
    if (w.face_values.size() != 0 && w.face_values.size() != nf)
      fail(fmt::format("{} face values for {} triangles", w.face_values.size(), nf));
    if (!(w.width_px > 0)) fail("wireframe width must be positive");
  }
}

}  // namespace sd::render
