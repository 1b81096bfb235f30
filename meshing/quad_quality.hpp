#pragma once
// Distortion (valence deviation) and shape quality of a filled quad patch.

#include <span>

#include "meshing/quad_mesh.hpp"

namespace sd::meshing {

struct QuadQuality {
  // Σ |valence − regular| over all vertices: regular is 4 inside, 3 on a side, 2 at a corner.
  int distortion = 0;
  int irregular_vertices = 0;  // vertices whose valence is not the regular one
  double min_angle_deg = 0;    // smallest / largest corner angle over all quads
  double max_angle_deg = 0;
  double max_aspect_ratio = 0;      // over quads: longest edge / shortest edge
  double scaled_jacobian_min = 0;   // over all quad corners; 1 for a square, ≤ 0 when inverted
  double scaled_jacobian_mean = 0;  // mean over quads of each quad's minimum corner value
  int inverted_quads = 0;           // quads with a corner whose scaled Jacobian is < 0
};

// Valence figures only (cheap, no geometry): distortion and irregular_vertices.
// corner_vertices are the region's corners (regular valence 2); other boundary vertices are
// side vertices (regular 3).
QuadQuality measure_valence(const QuadMesh& mesh, std::span<const int> corner_vertices);

// All figures. The scaled Jacobian at a corner is ((e1 × e2) · n) / (|e1| |e2|), with n the
// quad's reference normal: the sum of its vertices' normals (each the sum of the corner cross
// products around the vertex), so a folded quad shows up as negative even on a curved patch.
QuadQuality measure_quality(const QuadMesh& mesh, std::span<const int> corner_vertices);

// The mean length of quad `face`'s four sides: its size, as the fill and the quality gate compare
// it with the edge length asked for.
double mean_side(const QuadMesh& mesh, Eigen::Index face);

}  // namespace sd::meshing
