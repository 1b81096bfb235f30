#include "src/app/pipeline/garment_stage.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <limits>
#include <map>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "garment/body_landmarks.hpp"
#include "garment/body_surface.hpp"
#include "garment/sketch_error.hpp"
#include "garment/sketch_inputs.hpp"
#include "garment/unused_curves.hpp"
#include "src/app/pipeline/quality_warnings.hpp"
#include "src/app/pipeline/seam_ease_warnings.hpp"

namespace sd::app {
namespace {

double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

void check_mesh48(const meshing::Mesh48& m48) {
  const std::vector<std::string> problems = m48.validate();
  if (!problems.empty()) throw std::runtime_error("4-8 mesh check failed: " + problems.front());
}

// The garment's quads cannot become the simulator's 4-8 mesh (a quad with three corners in a
// line or two on one spot: its triangles have no area). The filler's vertex numbers mean nothing
// to a designer, so the error names the panel at its JSON path, the place and the nearest
// landmark, after the quality gate's warnings (logged), which say what to change there.
[[noreturn]] void fail_on_collapsed_quad(const scene::Sketch& sketch, const garment::Body& body,
                                         const garment::Garment& g,
                                         const meshing::Mesh48InputError& error) {
  // The quad whose flattest corner triangle (area over its longest side squared) is flattest.
  Eigen::Index worst = -1;
  double flattest = std::numeric_limits<double>::infinity();
  for (Eigen::Index f = 0; f < g.mesh.face_count(); ++f)
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d a = g.mesh.vertices.row(g.mesh.faces(f, k)).transpose();
      const Eigen::Vector3d b = g.mesh.vertices.row(g.mesh.faces(f, (k + 1) % 4)).transpose();
      const Eigen::Vector3d c = g.mesh.vertices.row(g.mesh.faces(f, (k + 2) % 4)).transpose();
      const double longest =
          std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
      const double flatness = longest > 0 ? 0.5 * (b - a).cross(c - a).norm() / longest : 0.0;
      if (flatness < flattest) {
        flattest = flatness;
        worst = f;
      }
    }
  if (worst < 0) throw std::runtime_error("4-8 mesh: " + std::string(error.what()));
  const std::vector<garment::QualityWarning> warnings = quality_warnings(g, sketch, body);
  const garment::GarmentPanel& panel = g.panels[static_cast<size_t>(g.face_panel(worst))];
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (int k = 0; k < 4; ++k)
    centre += 0.25 * g.mesh.vertices.row(g.mesh.faces(worst, k)).transpose();
  std::string near;
  try {
    near = fmt::format(", near the body's {}",
                       garment::find_landmarks(body.mesh).nearest(centre).name);
  } catch (const std::runtime_error&) {
    // Not a standing figure: the place alone.
  }
  const std::string original =
      panel.mirror_copy ? panel.id.substr(0, panel.id.rfind('.')) : panel.id;
  std::string path = "/panels";
  for (const garment::PanelSpec& spec : sketch.panels)
    if (spec.id == original) path = spec.json_path;
  sketch.fail(
      path,
      fmt::format("panel '{}' has a collapsed quad at ({:.3f}, {:.3f}, {:.3f}) m{} (corners in "
                  "a line or on one spot), which the simulator cannot use; {}",
                  panel.id, centre.x(), centre.y(), centre.z(), near,
                  warnings.empty() ? "move the panel's curves there apart, or give the panel "
                                     "a different \"edge_length\""
                                   : "the mesh warnings above say what to change there"));
}

// What in the body file may be why it has no landmarks, beyond the search's own reason (trial
// 44, P3: the Collada human twice side by side in one file was inferred to stand along x, the
// pair's width, and the error said only to set "facing"): the figure-sized meshes it holds, and
// the up axis when it was inferred, with the extents that chose it. Empty when neither applies.
std::string body_file_cause(const garment::Body& body) {
  const meshing::TriMesh& mesh = body.mesh;
  // Connected pieces (triangles sharing vertices), by union-find.
  std::vector<Eigen::Index> parent(static_cast<size_t>(mesh.vertex_count()));
  std::iota(parent.begin(), parent.end(), Eigen::Index{0});
  const auto find = [&parent](Eigen::Index v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f)
    for (int k = 1; k < 3; ++k) parent[find(mesh.faces(f, k))] = find(mesh.faces(f, 0));
  // Each piece's bounding box; a figure modelled in pieces (the built-in body's head, arms and
  // legs are separate meshes) is the pieces whose boxes overlap, merged until none does.
  std::map<Eigen::Index, meshing::BoundingBox> boxes;
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d p = mesh.vertices.row(mesh.faces(f, k)).transpose();
      auto [it, added] = boxes.try_emplace(find(mesh.faces(f, k)), meshing::BoundingBox{p, p});
      it->second.min = it->second.min.cwiseMin(p);
      it->second.max = it->second.max.cwiseMax(p);
    }
  std::vector<meshing::BoundingBox> groups;
  for (const auto& [piece, box] : boxes) groups.push_back(box);
  constexpr size_t kMostPieces = 500;  // a triangle soup is no scene of figures: not grouped
  for (bool merged = groups.size() <= kMostPieces; merged;) {
    merged = false;
    for (size_t a = 0; a < groups.size() && !merged; ++a)
      for (size_t b = a + 1; b < groups.size() && !merged; ++b)
        if ((groups[a].min.array() <= groups[b].max.array()).all() &&
            (groups[b].min.array() <= groups[a].max.array()).all()) {
          groups[a].min = groups[a].min.cwiseMin(groups[b].min);
          groups[a].max = groups[a].max.cwiseMax(groups[b].max);
          groups.erase(groups.begin() + static_cast<std::ptrdiff_t>(b));
          merged = true;
        }
  }
  // A figure spans most of the body's size along its longest extent (along the height when the
  // up axis is right, along another axis when it was inferred from the pair's width); eyes,
  // teeth or a base do not. Half counts a figure however it stands.
  const double size =
      (mesh.vertices.colwise().maxCoeff() - mesh.vertices.colwise().minCoeff()).maxCoeff();
  int figures = 0;
  if (groups.size() <= kMostPieces)
    for (const meshing::BoundingBox& box : groups) figures += box.extent().maxCoeff() > 0.5 * size;
  std::vector<std::string> causes;
  if (figures > 1)
    causes.push_back(fmt::format(
        "the file holds {} separate meshes apart from each other, each at least half the "
        "body's size (more than one figure, as a scene with a second mannequin? the loader "
        "merges every mesh of the file "
        "into one body: export the one figure to dress)",
        figures));
  if (body.raw.up_inferred) {
    const Eigen::Vector3d extent = body.raw.box.extent();
    const int up = body.raw.up.axis;
    const char* names = "xyz";
    causes.push_back(fmt::format(
        "the up axis was inferred as +{} because the file is longest along {} ({:.4g} units; "
        "{:.4g} along {}, {:.4g} along {}): if the figure stands along another axis, give "
        "\"up\"",
        names[up], names[up], extent[up], extent[(up + 1) % 3], names[(up + 1) % 3],
        extent[(up + 2) % 3], names[(up + 2) % 3]));
  }
  std::string out;
  for (const std::string& cause : causes) out += (out.empty() ? "" : "; ") + cause;
  return out;
}

}  // namespace

meshing::Mesh48 garment_mesh48(const scene::Sketch& sketch, const garment::Body& body,
                               const garment::Garment& g) {
  meshing::Mesh48 m48 = [&] {
    try {
      return meshing::Mesh48::from_quads(g.mesh);
    } catch (const meshing::Mesh48InputError& e) {
      fail_on_collapsed_quad(sketch, body, g, e);
    }
  }();
  check_mesh48(m48);
  return m48;
}

MeshedGarment mesh_garment(const scene::Sketch& sketch) {
  const auto body_start = std::chrono::steady_clock::now();
  garment::Body body = garment::load_sketch_body(sketch);
  const garment::BodySurface surface(body.mesh);
  const double body_ms = ms_since(body_start);
  const auto mesh_start = std::chrono::steady_clock::now();
  garment::Garment g = [&] {
    try {
      return garment::build_garment(sketch, surface);
    } catch (const garment::SketchError& e) {
      // On a body that is not a standing figure (trial 35: assimp's duck given as the body) the
      // curves fail in ways that say nothing of the cause: say it first.
      std::string why;
      try {
        (void)garment::find_landmarks(body.mesh);
      } catch (const std::runtime_error& landmarks) {
        why = landmarks.what();
      }
      if (why.empty()) throw;
      // Upside down (trial 44, P18: `info` said "give "up": "-z"", this error did not): the
      // file is the right one, read the wrong way up.
      if (const std::string upside = garment::upside_down_advice(body); !upside.empty())
        sketch.fail(e.json_path(),
                    fmt::format("the body '{}' has no landmarks ({}); {}. With it as read, {}",
                                sketch.body.mesh, why, upside, e.sentence()));
      const std::string cause = body_file_cause(body);
      sketch.fail(
          e.json_path(),
          fmt::format("the body '{}' has no landmarks ({}){}, so it is not a standing "
                      "human figure: is it the right body file? With it, {}",
                      sketch.body.mesh, why, cause.empty() ? "" : "; " + cause, e.sentence()));
    }
  }();
  const double meshing_ms = ms_since(mesh_start);
  for (const std::string& warning : seam_ease_warnings(sketch, g)) spdlog::warn("{}", warning);
  for (const std::string& warning : garment::unused_curve_warnings(sketch, g))
    spdlog::warn("{}", warning);
  for (const std::string& warning : garment::half_mirrored_warnings(sketch, g))
    spdlog::warn("{}", warning);

  std::vector<std::string> groups;
  std::vector<int> panel_group(g.panels.size());
  for (size_t p = 0; p < g.panels.size(); ++p) {
    auto it = std::find(groups.begin(), groups.end(), g.panels[p].group);
    if (it == groups.end()) it = groups.insert(groups.end(), g.panels[p].group);
    panel_group[p] = static_cast<int>(it - groups.begin());
  }
  meshing::Mesh48 m48 = garment_mesh48(sketch, body, g);
  return {std::move(body), std::move(g), std::move(groups), std::move(panel_group),
          std::move(m48),  body_ms,      meshing_ms};
}

ImportedGarment import_garment(const scene::Sketch& sketch) {
  long file_faces = 0;
  meshing::TriMesh triangles = garment::load_garment_mesh(sketch, &file_faces);
  meshing::Sqrt3Stats stats;
  meshing::Mesh48 m48 = [&] {
    try {
      return meshing::Mesh48::from_triangles_sqrt3(triangles, &stats);
    } catch (const meshing::Mesh48InputError& e) {
      sketch.fail("/garment_mesh",
                  fmt::format("the garment mesh cannot become a 4-8 mesh: {}", e.what()));
    }
  }();
  check_mesh48(m48);
  return {std::move(triangles), file_faces, std::move(m48), stats};
}

}  // namespace sd::app
