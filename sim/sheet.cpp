#include "sim/sheet.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <string>

namespace sd::sim {

SheetScene build_sheet(const SheetSpec& spec) {
  if (!(spec.size.allFinite() && spec.size.x() > 0.0 && spec.size.y() > 0.0))
    throw InvalidSheetError("the sheet size must be two positive lengths in metres");
  if (spec.columns < 1 || spec.rows < 1)
    throw InvalidSheetError("the sheet resolution must be at least 1 by 1 quads");
  if (!spec.centre.allFinite()) throw InvalidSheetError("the sheet centre must be finite");
  SheetScene scene;
  scene.columns = spec.columns;
  scene.rows = spec.rows;
  const int nv = (spec.rows + 1) * (spec.columns + 1);
  const bool vertical = spec.orientation == SheetOrientation::vertical;
  // In-sheet axes: "right" (+X) and "up" (towards the top edge).
  const Eigen::Vector3d right = Eigen::Vector3d::UnitX();
  const Eigen::Vector3d up =
      vertical ? Eigen::Vector3d::UnitY() : Eigen::Vector3d(-Eigen::Vector3d::UnitZ());
  scene.input.rest_positions.resize(nv, 3);
  for (int r = 0; r <= spec.rows; ++r)
    for (int c = 0; c <= spec.columns; ++c) {
      const double s = spec.size.x() * (static_cast<double>(c) / spec.columns - 0.5);
      const double t = spec.size.y() * (0.5 - static_cast<double>(r) / spec.rows);
      scene.input.rest_positions.row(scene.vertex(r, c)) = spec.centre + s * right + t * up;
    }
  const int nf = 2 * spec.rows * spec.columns;
  scene.input.triangles.resize(nf, 3);
  scene.input.warp.resize(nf, 3);
  scene.quads.resize(spec.rows * spec.columns, 4);
  int f = 0;
  for (int r = 0; r < spec.rows; ++r)
    for (int c = 0; c < spec.columns; ++c) {
      const int tl = scene.vertex(r, c), tr = scene.vertex(r, c + 1);
      const int bl = scene.vertex(r + 1, c), br = scene.vertex(r + 1, c + 1);
      scene.quads.row(r * spec.columns + c) << bl, br, tr, tl;
      // Counter-clockwise seen from +Z (vertical) or +Y (horizontal).
      if ((r + c) % 2 == 0) {
        scene.input.triangles.row(f++) << bl, br, tr;
        scene.input.triangles.row(f++) << bl, tr, tl;
      } else {
        scene.input.triangles.row(f++) << bl, br, tl;
        scene.input.triangles.row(f++) << br, tr, tl;
      }
    }
  for (int k = 0; k < nf; ++k) scene.input.warp.row(k) = up;
  scene.input.up = vertical ? up : Eigen::Vector3d::UnitY();

  for (const std::string& name : spec.pins) {
    std::vector<int> add;
    if (name == "top-left")
      add = {scene.vertex(0, 0)};
    else if (name == "top-right")
      add = {scene.vertex(0, spec.columns)};
    else if (name == "bottom-left")
      add = {scene.vertex(spec.rows, 0)};
    else if (name == "bottom-right")
      add = {scene.vertex(spec.rows, spec.columns)};
    else if (name == "top" || name == "bottom") {
      const int r = name == "top" ? 0 : spec.rows;
      for (int c = 0; c <= spec.columns; ++c) add.push_back(scene.vertex(r, c));
    } else if (name == "left" || name == "right") {
      const int c = name == "left" ? 0 : spec.columns;
      for (int r = 0; r <= spec.rows; ++r) add.push_back(scene.vertex(r, c));
    } else if (const std::size_t colon = name.find(':'); colon != std::string::npos) {
      // A clamp: "top:3" holds the top three rows of vertices (the edge and the next two).
      const std::string edge = name.substr(0, colon);
      int depth = 0;
      try {
        std::size_t used = 0;
        depth = std::stoi(name.substr(colon + 1), &used);
        if (used != name.size() - colon - 1) depth = 0;
      } catch (const std::exception&) {
        depth = 0;
      }
      const bool rows = edge == "top" || edge == "bottom";
      const int available = (rows ? spec.rows : spec.columns) + 1;
      if ((!rows && edge != "left" && edge != "right") || depth < 1 || depth > available)
        throw InvalidSheetError("pin '" + name +
                                "' is not a clamp: use top:N, bottom:N, left:N "
                                "or right:N with N from 1 to " +
                                std::to_string(available) + " lines of vertices");
      for (int k = 0; k < depth; ++k) {
        if (rows) {
          const int r = edge == "top" ? k : spec.rows - k;
          for (int c = 0; c <= spec.columns; ++c) add.push_back(scene.vertex(r, c));
        } else {
          const int c = edge == "left" ? k : spec.columns - k;
          for (int r = 0; r <= spec.rows; ++r) add.push_back(scene.vertex(r, c));
        }
      }
    } else {
      throw InvalidSheetError("unknown pin '" + name +
                              "' (use top-left, top-right, bottom-left, bottom-right, top, "
                              "bottom, left, right, or a clamp such as top:3)");
    }
    scene.pinned_vertices.insert(scene.pinned_vertices.end(), add.begin(), add.end());
  }
  std::sort(scene.pinned_vertices.begin(), scene.pinned_vertices.end());
  scene.pinned_vertices.erase(
      std::unique(scene.pinned_vertices.begin(), scene.pinned_vertices.end()),
      scene.pinned_vertices.end());
  return scene;
}

meshing::Mesh48 sheet_mesh48(const SheetScene& scene) {
  return meshing::Mesh48::from_quads(scene.input.rest_positions, scene.quads);
}

Eigen::MatrixX3d sheet_quad_warp(const SheetScene& scene) {
  // Quad q is split into triangles 2q and 2q + 1, which share its warp.
  Eigen::MatrixX3d warp(scene.quads.rows(), 3);
  for (Eigen::Index q = 0; q < warp.rows(); ++q) warp.row(q) = scene.input.warp.row(2 * q);
  return warp;
}

}  // namespace sd::sim
