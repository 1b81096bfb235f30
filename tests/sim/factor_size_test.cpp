#include "sim/factor_size.hpp"

#include <gtest/gtest.h>

#include "sim/cholmod_solver.hpp"
#include "sim/cloth_model.hpp"
#include "sim/constraint_filter.hpp"
#include "sim/fabric.hpp"
#include "sim/sheet.hpp"

namespace sd::sim {
namespace {

// What CholmodSolver's own analysis of a cloth's 3n×3n system reports, on the model's pattern
// (values: the identity on the diagonal, so the numeric factorisation succeeds; the analysis
// reads only the pattern).
FactorSize analysed_by_solver(const ClothInput& input, const ClothModelOptions& options) {
  const ClothModel model = build_cloth_model(input, fabric_preset("cotton"), options);
  SparseMatrixR a = model.pattern.zero_matrix;
  for (int i = 0; i < model.vertex_count; ++i)
    for (int k = 0; k < 3; ++k) a.coeffRef(3 * i + k, 3 * i + k) = 1.0;
  CholmodSolver solver;
  EXPECT_TRUE(solver.factorize(a, ConstraintFilter(model.vertex_count)));
  return solver.analysed_size();
}

// Both membranes, stated rather than left to the defaults (the diamonds with the ghost points, as
// the cantilever and Cusick tests set them).
ClothModelOptions model_options(BendModel bend_model, bool diamonds) {
  ClothModelOptions options;
  options.bend_model = bend_model;
  options.diamond_membrane = diamonds;
  options.clamp_ghost_points = diamonds;
  return options;
}

// The prediction from the vertex graph is the solver's analysis of the scalar system of the hinge
// bending (the sketch default), with or without the diamonds: the same entries of L exactly (the
// same AMD ordering of the same vertex graph, each vertex a 3×3 block), flops and bytes close
// (CHOLMOD relaxes supernodes by column counts, which differ between the vertex and the scalar
// analysis).
void expect_prediction_matches(const ClothInput& input, bool diamonds) {
  SCOPED_TRACE(diamonds ? "diamond membrane" : "plain membrane");
  const ClothModelOptions options = model_options(BendModel::hinges, diamonds);
  const FactorSize predicted = predict_factor_size(input, options);
  const FactorSize analysed = analysed_by_solver(input, options);
  ASSERT_GT(analysed.nonzeros, 0.0);
  EXPECT_DOUBLE_EQ(predicted.nonzeros, analysed.nonzeros);
  EXPECT_NEAR(predicted.flops / analysed.flops, 1.0, 0.1);
  // Over, never much under: the check refuses on it.
  EXPECT_GE(predicted.bytes / analysed.bytes, 0.95);
  EXPECT_LE(predicted.bytes / analysed.bytes, 1.5);
  if (!diamonds) {  // the triangles alone are the same graph
    const FactorSize from_triangles =
        predict_factor_size(input.triangles, static_cast<int>(input.rest_positions.rows()));
    EXPECT_EQ(from_triangles.nonzeros, predicted.nonzeros);
    EXPECT_EQ(from_triangles.bytes, predicted.bytes);
  }
}

SheetScene sheet_of(int columns, int rows) {
  SheetSpec spec;
  spec.columns = columns;
  spec.rows = rows;
  return build_sheet(spec);
}

// With the quadratic bending the prediction is a bound: never under the solver's analysis, and
// not more than twice it (2.5 times with the diamonds, whose pairs overlap the quadratic bends'
// stencils, which the bound's scale does not know: measured 2.27 on this sheet; without their
// pairs the prediction was 0.92 of the analysis).
TEST(FactorSize, QuadraticBendingIsBoundedFromAbove) {
  const ClothInput input = sheet_of(40, 30).input;
  for (const bool diamonds : {false, true}) {
    SCOPED_TRACE(diamonds ? "diamond membrane" : "plain membrane");
    const ClothModelOptions options = model_options(BendModel::quadratic, diamonds);
    const FactorSize predicted = predict_factor_size(input, options);
    const FactorSize analysed = analysed_by_solver(input, options);
    EXPECT_GE(predicted.bytes, analysed.bytes);
    EXPECT_LE(predicted.bytes, (diamonds ? 2.5 : 2.0) * analysed.bytes);
    EXPECT_GE(predicted.nonzeros, analysed.nonzeros);
  }
}

TEST(FactorSize, PredictionOfASheetIsTheSolversAnalysis) {
  const ClothInput input = sheet_of(40, 30).input;
  for (const bool diamonds : {false, true}) expect_prediction_matches(input, diamonds);
}

// The diamonds' pairs are most of the fill: without them the prediction of a sheet's factor is
// about half the solver's (0.47-0.58 of L's entries, measured in session 41).
TEST(FactorSize, DiamondsAreCounted) {
  const ClothInput input = sheet_of(40, 30).input;
  const ClothModelOptions options = model_options(BendModel::hinges, true);
  const FactorSize with = predict_factor_size(input, options);
  const FactorSize without =
      predict_factor_size(input.triangles, static_cast<int>(input.rest_positions.rows()));
  EXPECT_GT(with.nonzeros, 1.5 * without.nonzeros);
  EXPECT_DOUBLE_EQ(with.nonzeros, analysed_by_solver(input, options).nonzeros);
}

TEST(FactorSize, PredictionOfAClosedMeshIsTheSolversAnalysis) {
  // A tube: a sheet whose left and right columns are one (every edge has two triangles but
  // the top and bottom rims).
  SheetSpec spec;
  spec.columns = 24;
  spec.rows = 12;
  ClothInput input = build_sheet(spec).input;
  const int width = spec.columns + 1;
  for (Eigen::Index f = 0; f < input.triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int v = input.triangles(f, k);
      if (v % width == spec.columns) input.triangles(f, k) = v - spec.columns;  // last → first
    }
  // Drop the unused last column: renumber vertices r·width + c to r·columns + c.
  Eigen::MatrixX3d positions(static_cast<Eigen::Index>(spec.rows + 1) * spec.columns, 3);
  for (int r = 0; r <= spec.rows; ++r)
    for (int c = 0; c < spec.columns; ++c)
      positions.row(r * spec.columns + c) = input.rest_positions.row(r * width + c);
  for (Eigen::Index f = 0; f < input.triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int v = input.triangles(f, k);
      input.triangles(f, k) = (v / width) * spec.columns + v % width;
    }
  input.rest_positions = positions;
  for (const bool diamonds : {false, true}) expect_prediction_matches(input, diamonds);
}

TEST(FactorSize, GrowsFasterThanTheVertexCount) {
  // Nested-dissection-like fill of a grid: L grows like n log n, so 4× the vertices give more
  // than 4× the entries.
  SheetSpec spec;
  spec.columns = spec.rows = 32;
  const SheetScene small = build_sheet(spec);
  spec.columns = spec.rows = 64;
  const SheetScene large = build_sheet(spec);
  const FactorSize s = predict_factor_size(small.input.triangles, 33 * 33);
  const FactorSize l = predict_factor_size(large.input.triangles, 65 * 65);
  EXPECT_GT(l.nonzeros / s.nonzeros, (65.0 * 65.0) / (33.0 * 33.0));
  EXPECT_GT(l.flops / s.flops, 4.0);
  EXPECT_EQ(predict_factor_size(Eigen::MatrixX3i(0, 3), 0).bytes, 0.0);
}

}  // namespace
}  // namespace sd::sim
