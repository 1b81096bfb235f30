#pragma once
// A rectangular sheet as plain simulator input, for tests, benchmarks and sheet scenes.

#include <Eigen/Core>
#include <cmath>
#include <exception>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "meshing/mesh48.hpp"
#include "sim/cloth_model.hpp"

namespace sd::sim {

class InvalidSheetError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// A rectangle of rows × columns square-ish quads, or a disc (the Cusick drape test's specimen).
enum class SheetShape { rectangle, disc };

enum class SheetOrientation {
  vertical,    // in the XY plane (facing +Z), top edge at centre.y + height/2
  horizontal,  // in the XZ plane at centre.y; "top" is the edge at −Z (far from the viewer)
};

struct SheetSpec {
  Eigen::Vector2d size{1.0, 1.0};  // m: width (X) and height (Y, or Z when horizontal)
  int columns = 16;                // quads along the width
  int rows = 16;                   // quads along the height
  SheetOrientation orientation = SheetOrientation::vertical;
  Eigen::Vector3d centre{0.0, 1.0, 0.0};
  // A disc of diameter size.x() (size.y() must equal it) with cells about size.x() / columns
  // wide (docs/fabrics.md, "Cusick drape"); `rows` must equal `columns`.
  SheetShape shape = SheetShape::rectangle;
  // Corners "top-left", "top-right", "bottom-left", "bottom-right", whole edges "top",
  // "bottom", "left", "right", or clamps "top:N" (N lines of vertices from that edge, N ≥ 1);
  // "centre:R" holds every vertex within R metres of the centre (a disc clamped between two
  // discs of radius R; on a disc sheet a ring of vertices lies exactly at R). A disc takes only
  // "centre:R". A corner with a radius, "top-left:R", holds every vertex within R metres of
  // that corner (a clip's bite; corner_clamp).
  std::vector<std::string> pins;
};

struct SheetScene {
  ClothInput input;                  // warp runs from the bottom edge to the top edge
  std::vector<int> pinned_vertices;  // sorted, unique
  // rows·columns by 4: the grid's quads (bottom-left, bottom-right, top-right, top-left: counter-
  // clockwise seen from the sheet's normal side), row by row from the top; the input of the
  // sheet's 4-8 mesh (Mesh48::from_quads, which picks each quad's diagonal itself).
  Eigen::MatrixX4i quads;
  int columns = 0;  // 0 for a disc (its quads are not a grid)
  int rows = 0;
  // Vertex index of grid point (row r from the top, column c from the left).
  int vertex(int r, int c) const { return r * (columns + 1) + c; }
};

// Builds a rectangle or a disc. A rectangle: the (rows+1)·(columns+1) vertices and 2·rows·columns
// triangles (each quad split along alternating diagonals so the mesh has no preferred shear
// direction). Throws InvalidSheetError for a non-positive size or resolution or an unknown pin
// name. A disc: an annulus of quads in rings and sectors from the clamp radius (or half the radius)
// to the rim, whose polar layout has no preferred direction for folds, around a core of five blocks
// (a square and four quads curved to the core's circle); each quad is split along alternating
// diagonals.
SheetScene build_sheet(const SheetSpec& spec);

// The sheet as a 4-8 mesh: its quads through Mesh48::from_quads (vertex ids = grid ids; each
// quad's diagonal is the 4-8 rule's, not the alternating one of the sheet's own triangles).
meshing::Mesh48 sheet_mesh48(const SheetScene& scene);
// #Q by 3: the warp of each quad (its triangles'), for AdaptiveMaterial::source_warp.
Eigen::MatrixX3d sheet_quad_warp(const SheetScene& scene);

// R of a pin "centre:R" (metres: a clamp holding every vertex within R of the centre), nullopt
// for other pin names; throws InvalidSheetError for a radius that is not a positive number.
// (Inline: the sketch reader, built on its own for the fuzzer, calls it too.)
// The radius after a clamp pin's colon (m), 0 when it is not a whole finite number.
inline double clamp_radius_text(const std::string& number) {
  double radius = 0.0;
  try {
    std::size_t used = 0;
    radius = std::stod(number, &used);
    if (used != number.size()) radius = 0.0;
  } catch (const std::exception&) {
    radius = 0.0;
  }
  return std::isfinite(radius) ? radius : 0.0;
}

inline std::optional<double> centre_clamp_radius(const std::string& name) {
  if (!name.starts_with("centre:")) return std::nullopt;
  const double radius = clamp_radius_text(name.substr(7));
  if (!(radius > 0.0))
    throw InvalidSheetError("pin '" + name +
                            "' must give a positive radius in metres (centre:0.09)");
  return radius;
}

// A corner clamp "top-left:R" ("top-right:R", "bottom-left:R", "bottom-right:R"): every vertex
// within R metres of that corner is held, like the jaws of a clip biting a quarter disc of
// cloth; a pin of a single corner vertex is a point load, whose strain grows as 1/r towards it
// (docs/benchmarks.md, "Sixth round"), a clamp spreads the load over its edge.
struct CornerClamp {
  std::string corner;   // "top-left", "top-right", "bottom-left" or "bottom-right"
  double radius = 0.0;  // m
};

// The corner clamp a pin names, nullopt for other pin names (a bare corner is a point pin);
// throws InvalidSheetError for a radius that is not a positive number. (Inline, as
// centre_clamp_radius.)
inline std::optional<CornerClamp> corner_clamp(const std::string& name) {
  const std::size_t colon = name.find(':');
  if (colon == std::string::npos) return std::nullopt;
  const std::string corner = name.substr(0, colon);
  if (corner != "top-left" && corner != "top-right" && corner != "bottom-left" &&
      corner != "bottom-right")
    return std::nullopt;
  const double radius = clamp_radius_text(name.substr(colon + 1));
  if (!(radius > 0.0))
    throw InvalidSheetError("pin '" + name + "' must give a positive radius in metres (" + corner +
                            ":0.02)");
  return CornerClamp{corner, radius};
}

}  // namespace sd::sim
