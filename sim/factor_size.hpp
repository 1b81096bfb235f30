#pragma once
// The size of the Cholesky factor CHOLMOD makes of a cloth's 3n×3n system, known from the
// symbolic analysis alone, before any number is factorised: a drape that cannot fit the machine
// is refused before it allocates the factor (docs/cli.md, "Limits").

#include <Eigen/Core>

#include "sim/cloth_model.hpp"

namespace sd::sim {

struct FactorSize {
  double nonzeros = 0;  // entries of L (lower triangle with the diagonal), CHOLMOD's Common->lnz
  double flops = 0;     // floating-point operations of one numeric factorisation, Common->fl
  // Bytes the numeric factorisation allocates: L's values and row indices (supernodal: Lx and
  // Ls, zeros of relaxed supernodes included) and its largest update block (maxcsize doubles).
  double bytes = 0;
};

// The factor of the system of a cloth with these triangles (#F×3 vertex indices into
// `vertex_count` vertices): the symbolic analysis of its vertex graph (vertices sharing a
// triangle, and the two far corners of each edge's two triangles, as the bending hinges couple
// them: the block pattern of ClothModel), each vertex's three rows kept together as
// CholmodSolver orders them, expanded to the 3n scalar rows: every off-diagonal vertex entry of
// L is a 3×3 block, every diagonal one a lower triangle of 6. Cost: AMD and the analysis on the
// n-vertex graph (about a ninth of the scalar pattern), no values. Throws std::bad_alloc when
// CHOLMOD runs out of memory.
//
// That is the pattern of the hinge bending (BendModel::hinges). The quadratic bending couples
// every pair of vertices in a vertex's stencil (its one-ring and the nearest points of its
// two-ring), a pattern this graph does not hold and which would cost dozens of pairs per vertex
// to list; for it the prediction is scaled by kQuadraticBendingFactorScale, an upper bound
// measured on sheets and tubes (the solver's analysis was 1.8–2.5× the hinge pattern's bytes,
// 2.5–5.2× its flops, on sheets of 16×12 to 100×75 quads and tubes of 24×12 to 96×48;
// tests/sim/factor_size_test.cpp).
FactorSize predict_factor_size(const Eigen::MatrixX3i& triangles, int vertex_count,
                               BendModel bend_model = BendModel::hinges);

// The same for the model build_cloth_model(input, fabric, options) makes, which with
// options.diamond_membrane also couples every two of each diamond's 13 vertices (the centre, its
// corners and their neighbours, sim/diamond_membrane.hpp): the diamonds are found as the model
// finds them (make_diamonds on the rest positions) and their pairs added to the vertex graph, so
// the prediction is again the solver's analysis for the hinges (a diamond holds up to four rings
// apart: without its pairs the prediction was 0.47-0.58 of the nonzeros). With the quadratic
// bending it stays the bound below (2.27 times the analysis's bytes with the diamonds on a 40×30
// sheet, where the triangles' graph alone gave 0.92). Costs make_diamonds, linear in the mesh.
FactorSize predict_factor_size(const ClothInput& input, const ClothModelOptions& options);

inline constexpr double kQuadraticBendingFactorScale = 3.0;

}  // namespace sd::sim
