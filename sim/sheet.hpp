#pragma once
// A rectangular sheet as plain simulator input, for tests, benchmarks and sheet scenes.

#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "sim/cloth_model.hpp"

namespace sd::sim {

class InvalidSheetError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

enum class SheetOrientation {
  vertical,    // in the XY plane (facing +Z), top edge at centre.y + height/2
  horizontal,  // in the XZ plane at centre.y; "top" is the edge at −Z (far from the viewer)
};

struct SheetSpec {
  Eigen::Vector2d size{1.0, 1.0};   // m: width (X) and height (Y, or Z when horizontal)
  int columns = 16;                 // quads along the width
  int rows = 16;                    // quads along the height
  SheetOrientation orientation = SheetOrientation::vertical;
  Eigen::Vector3d centre{0.0, 1.0, 0.0};
  // Corners "top-left", "top-right", "bottom-left", "bottom-right", whole edges "top",
  // "bottom", "left", "right", or clamps "top:N" (N lines of vertices from that edge, N ≥ 1).
  std::vector<std::string> pins;
};

struct SheetScene {
  ClothInput input;                  // warp runs from the bottom edge to the top edge
  std::vector<int> pinned_vertices;  // sorted, unique
  int columns = 0;
  int rows = 0;
  // Vertex index of grid point (row r from the top, column c from the left).
  int vertex(int r, int c) const { return r * (columns + 1) + c; }
};

// Builds the (rows+1)·(columns+1) vertices and 2·rows·columns triangles (each quad split along
// alternating diagonals so the mesh has no preferred shear direction). Throws InvalidSheetError
// for a non-positive size or resolution or an unknown pin name.
SheetScene build_sheet(const SheetSpec& spec);

}  // namespace sd::sim
