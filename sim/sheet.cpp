#include "sim/sheet.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <map>
#include <numbers>
#include <optional>
#include <string>
#include <utility>

namespace sd::sim {

namespace {

// The disc's quads in its own plane (s, t), counter-clockwise, with shared vertices merged.
struct DiscBuilder {
  std::vector<Eigen::Vector2d> points;
  std::map<std::pair<long long, long long>, int> index;  // key: position in 1e-9 m units
  std::vector<Eigen::Vector4i> quads;
  std::vector<int> parity;  // (i + j) mod 2 of each quad: alternating diagonals, checkerboard

  int vertex(const Eigen::Vector2d& p) {
    const std::pair<long long, long long> key{std::llround(p.x() * 1e9), std::llround(p.y() * 1e9)};
    const auto [it, inserted] = index.emplace(key, static_cast<int>(points.size()));
    if (inserted) points.push_back(p);
    return it->second;
  }
  // A structured patch of along × across quads from point(i, j): (i, j), (i+1, j), (i+1, j+1),
  // (i, j+1) is counter-clockwise, or clockwise (`flip`: i runs counter-clockwise round the
  // centre and j outwards) and then reversed.
  template <class Point>
  void patch(int along, int across, bool flip, Point point) {
    std::vector<int> ids((along + 1) * (across + 1));
    for (int j = 0; j <= across; ++j)
      for (int i = 0; i <= along; ++i) ids[j * (along + 1) + i] = vertex(point(i, j));
    for (int j = 0; j < across; ++j)
      for (int i = 0; i < along; ++i) {
        const int q0 = ids[j * (along + 1) + i], q1 = ids[j * (along + 1) + i + 1];
        const int q2 = ids[(j + 1) * (along + 1) + i + 1], q3 = ids[(j + 1) * (along + 1) + i];
        if (flip)
          quads.emplace_back(q0, q3, q2, q1);
        else
          quads.emplace_back(q0, q1, q2, q3);
        parity.push_back((i + j) % 2);
      }
  }
};

// Disc of radius R with cells about h wide: the annulus from the clamp radius r0 (half the
// radius without a clamp) to the rim in L rings of S sectors, S = 4M so that the core's square
// of M × M cells and its four curved blocks meet the annulus's inner ring vertex for vertex.
DiscBuilder build_disc(const SheetSpec& spec, double clamp) {
  const double radius = 0.5 * spec.size.x();
  const double h = spec.size.x() / spec.columns;
  const double r0 = clamp > 0.0 && clamp < radius ? clamp : 0.5 * radius;
  const double pi = std::numbers::pi;
  // Sectors sized to h at the annulus's mid radius: cells are 0.6-1.6 h wide across it.
  const int m = std::max(2, static_cast<int>(std::lround(2 * pi * 0.5 * (r0 + radius) / h / 4)));
  const int sectors = 4 * m;
  const int rings = std::max(1, static_cast<int>(std::lround((radius - r0) / h)));
  DiscBuilder b;
  const auto polar = [](double r, double angle) {
    return Eigen::Vector2d(r * std::cos(angle), r * std::sin(angle));
  };
  // Annulus: i along the sectors (counter-clockwise), j outwards.
  b.patch(sectors, rings, true, [&](int i, int j) {
    return polar(r0 + (radius - r0) * j / rings, pi / 4 + 2 * pi * (i % sectors) / sectors);
  });
  // Core square of half-side a, and a block between each of its sides and the circle r0.
  const double a = 0.5 * r0;
  b.patch(m, m, false,
          [&](int i, int j) { return Eigen::Vector2d(-a + 2 * a * i / m, -a + 2 * a * j / m); });
  const int layers = std::max(1, static_cast<int>(std::lround((r0 - a) / h)));
  for (int side = 0; side < 4; ++side) {
    const double start = pi / 4 + side * pi / 2;  // the side's first corner, counter-clockwise
    const Eigen::Vector2d c0 = polar(a * std::numbers::sqrt2, start);
    const Eigen::Vector2d c1 = polar(a * std::numbers::sqrt2, start + pi / 2);
    b.patch(m, layers, true, [&](int i, int j) {
      const Eigen::Vector2d inner = c0 + (c1 - c0) * i / m;
      const Eigen::Vector2d outer = polar(r0, start + pi / 2 * i / m);
      return Eigen::Vector2d(inner + (outer - inner) * j / layers);
    });
  }
  return b;
}

}  // namespace

SheetScene build_sheet(const SheetSpec& spec) {
  if (!(spec.size.allFinite() && spec.size.x() > 0.0 && spec.size.y() > 0.0))
    throw InvalidSheetError("the sheet size must be two positive lengths in metres");
  if (spec.columns < 1 || spec.rows < 1)
    throw InvalidSheetError("the sheet resolution must be at least 1 by 1 quads");
  if (!spec.centre.allFinite()) throw InvalidSheetError("the sheet centre must be finite");
  const bool vertical = spec.orientation == SheetOrientation::vertical;
  // In-sheet axes: "right" (+X) and "up" (towards the top edge).
  const Eigen::Vector3d right = Eigen::Vector3d::UnitX();
  const Eigen::Vector3d up =
      vertical ? Eigen::Vector3d::UnitY() : Eigen::Vector3d(-Eigen::Vector3d::UnitZ());
  const bool disc = spec.shape == SheetShape::disc;
  double clamp = 0.0;  // the largest "centre:R" radius
  for (const std::string& name : spec.pins)
    if (const std::optional<double> r = centre_clamp_radius(name)) clamp = std::max(clamp, *r);
  SheetScene scene;
  if (disc) {
    if (spec.size.y() != spec.size.x() || spec.rows != spec.columns)
      throw InvalidSheetError(
          "a disc's size is [diameter, diameter] and its resolution [cells, cells] across it");
    if (spec.columns < 4) throw InvalidSheetError("a disc needs at least 4 cells across it");
    const DiscBuilder built = build_disc(spec, clamp);
    const std::vector<Eigen::Vector2d>& points = built.points;
    const std::vector<Eigen::Vector4i>& quads = built.quads;
    scene.input.rest_positions.resize(static_cast<Eigen::Index>(points.size()), 3);
    for (size_t i = 0; i < points.size(); ++i)
      scene.input.rest_positions.row(static_cast<Eigen::Index>(i)) =
          spec.centre + points[i].x() * right + points[i].y() * up;
    const Eigen::Index nq = static_cast<Eigen::Index>(quads.size());
    scene.quads.resize(nq, 4);
    scene.input.triangles.resize(2 * nq, 3);
    for (Eigen::Index q = 0; q < nq; ++q) {
      const Eigen::Vector4i& v = quads[static_cast<size_t>(q)];
      scene.quads.row(q) = v.transpose();
      // Alternating diagonals, as on the rectangle (quad q: triangles 2q and 2q + 1).
      if (built.parity[static_cast<size_t>(q)] == 0) {
        scene.input.triangles.row(2 * q) << v(0), v(1), v(2);
        scene.input.triangles.row(2 * q + 1) << v(0), v(2), v(3);
      } else {
        scene.input.triangles.row(2 * q) << v(0), v(1), v(3);
        scene.input.triangles.row(2 * q + 1) << v(1), v(2), v(3);
      }
    }
    scene.input.warp.resize(2 * nq, 3);
    for (Eigen::Index k = 0; k < 2 * nq; ++k) scene.input.warp.row(k) = up;
    scene.input.up = vertical ? up : Eigen::Vector3d::UnitY();
  } else {
    scene.columns = spec.columns;
    scene.rows = spec.rows;
    const int nv = (spec.rows + 1) * (spec.columns + 1);
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
  }

  for (const std::string& name : spec.pins) {
    std::vector<int> add;
    if (const std::optional<double> held = centre_clamp_radius(name)) {
      // Every vertex within r of the centre, measured in the sheet's plane (a ring of the disc
      // lies at r exactly; 1 um tolerance for its rounding).
      for (Eigen::Index v = 0; v < scene.input.rest_positions.rows(); ++v)
        if ((scene.input.rest_positions.row(v).transpose() - spec.centre).norm() <= *held + 1e-6)
          add.push_back(static_cast<int>(v));
      if (add.empty())
        throw InvalidSheetError("pin '" + name + "' holds no vertex: the radius is too small");
    } else if (disc) {
      throw InvalidSheetError("unknown pin '" + name +
                              "' for a disc: a disc is held by a clamp at its centre (centre:R, "
                              "R in metres)");
    } else if (const std::optional<CornerClamp> bite = corner_clamp(name)) {
      // Every vertex within R of the corner (the corner itself always; 1 um tolerance, as the
      // centre clamp's, for a grid point lying at R).
      const int r = bite->corner.starts_with("top") ? 0 : spec.rows;
      const int c = bite->corner.ends_with("left") ? 0 : spec.columns;
      const Eigen::Vector3d corner = scene.input.rest_positions.row(scene.vertex(r, c));
      for (Eigen::Index v = 0; v < scene.input.rest_positions.rows(); ++v)
        if ((scene.input.rest_positions.row(v).transpose() - corner).norm() <= bite->radius + 1e-6)
          add.push_back(static_cast<int>(v));
    } else if (name == "top-left")
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
                              "bottom, left, right, a clamp such as top:3, or a corner clamp "
                              "such as top-left:0.02)");
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
