#include "meshing/mesh48_transfer.hpp"

#include <gtest/gtest.h>

#include <random>

#include "tests/meshing/mesh48_fixtures.hpp"

namespace sd::meshing {
namespace {

using testing::icosphere;
using testing::quad_grid;

// Lumped masses Σ ρ_t A_t / 3 over the live triangles, indexed by vertex id value.
Eigen::VectorXd lumped_masses(const Mesh48& mesh, const std::vector<double>& density) {
  Eigen::VectorXd m = Eigen::VectorXd::Zero(mesh.vertex_capacity());
  for (const TriangleId t : mesh.live_triangles())
    for (const VertexId v : mesh.vertices(t))
      m(v.value()) += density[t.value()] * mesh.rest_area(t) / 3;
  return m;
}

// Carries per-triangle densities through a change: children inherit their parent's. Parents are
// read before children are written, since a child may reuse its parent's slot.
void carry_density(const BlockChange& ch, std::vector<double>& density) {
  const auto at = [&](TriangleId t) -> double& {
    if (static_cast<int>(density.size()) <= t.value()) density.resize(t.value() + 1, 0.0);
    return density[t.value()];
  };
  if (ch.kind == BlockChange::Kind::kSplit) {
    const double rho1 = at(ch.a1), rho2 = ch.a2.valid() ? at(ch.a2) : 0.0;
    at(ch.a10) = rho1;
    at(ch.a11) = rho1;
    if (ch.a2.valid()) at(ch.a20) = at(ch.a21) = rho2;
  } else {
    const double rho1 = at(ch.a11), rho2 = ch.a2.valid() ? at(ch.a21) : 0.0;
    at(ch.a1) = rho1;
    if (ch.a2.valid()) at(ch.a2) = rho2;
  }
}

BlockDensities densities_of(const BlockChange& ch, const std::vector<double>& density) {
  // For a split the parents' densities are still in the array; for a merge the children's are.
  if (ch.kind == BlockChange::Kind::kSplit)
    return {density[ch.a1.value()], ch.a2.valid() ? density[ch.a2.value()] : 0.0};
  return {density[ch.a11.value()], ch.a2.valid() ? density[ch.a21.value()] : 0.0};
}

TEST(Mesh48Transfer, SplitOfAUnitSquareMatchesTheFormulas) {
  const auto g = quad_grid(1, 1);
  Mesh48 mesh = Mesh48::from_quads(g.vertices, g.quads);
  const double rho = 0.2;  // kg/m²
  Eigen::VectorXd m(4);    // lumped: ρ A / 3 from each triangle at a corner
  const auto [b, c] = mesh.diagonal(BlockId(0));
  const auto [a, d] = mesh.apexes(BlockId(0));
  m(a.value()) = m(d.value()) = rho * 0.5 / 3;
  m(b.value()) = m(c.value()) = rho * 1.0 / 3;
  Eigen::MatrixX3d v(4, 3);
  v << 1, 0, 0, 0, 2, 0, 0, 0, 3, 1, 1, 1;
  const Eigen::MatrixX3d v0 = v;
  Eigen::MatrixX3d x = g.vertices;
  const BlockChange ch = mesh.split(BlockId(0)).front();
  transfer_mass_and_velocity(ch, {rho, rho}, m, v);
  place_split_vertex(ch, x);
  ASSERT_EQ(m.size(), 5);
  EXPECT_NEAR(m(ch.e.value()), rho * 1.0 / 3, 1e-15);         // ρ (A1 + A2) / 3
  EXPECT_NEAR(m(b.value()), rho / 3 - rho * 0.5 / 3, 1e-15);  // lost half its share
  EXPECT_NEAR(m(a.value()), rho * 0.5 / 3, 1e-15);            // unchanged
  EXPECT_NEAR(m.sum(), rho, 1e-15);
  const Eigen::RowVector3d midpoint_velocity = 0.5 * (v0.row(b.value()) + v0.row(c.value()));
  EXPECT_LT((v.row(ch.e.value()) - midpoint_velocity).norm(), 1e-15);
  EXPECT_EQ(x.row(ch.e.value()), 0.5 * (x.row(b.value()) + x.row(c.value())));
  // Merging straight back restores the masses and keeps momentum.
  const Eigen::RowVector3d p0 = (m.asDiagonal() * v).colwise().sum();
  const BlockChange back = mesh.merge(BlockId(0));
  transfer_mass_and_velocity(back, {rho, rho}, m, v);
  EXPECT_NEAR(m(b.value()), rho / 3, 1e-15);
  EXPECT_EQ(m(ch.e.value()), 0.0);
  EXPECT_LT(((m.asDiagonal() * v).colwise().sum() - p0).norm(), 1e-15);
}

// Thousands of random splits and merges with a different density per input triangle: total mass
// and momentum stay what they were, and the masses stay the lumped masses of the current mesh.
void check_conservation(Mesh48 mesh, unsigned seed, int operations, int target_triangles) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(0, 1);
  std::vector<double> density(mesh.triangle_capacity());
  for (double& rho : density) rho = 0.1 + uniform(rng);  // panels of different fabrics
  Eigen::VectorXd m = lumped_masses(mesh, density);
  Eigen::MatrixX3d v(mesh.vertex_capacity(), 3);
  for (Eigen::Index i = 0; i < v.rows(); ++i)
    v.row(i) << uniform(rng) - 0.5, uniform(rng), -uniform(rng);
  const double mass0 = m.sum();
  const Eigen::RowVector3d momentum0 = (m.asDiagonal() * v).colwise().sum();
  const double momentum_scale = (m.array() * v.rowwise().norm().array()).sum();
  int splits = 0, merges = 0;
  for (int op = 0; op < operations; ++op) {
    const auto mergeable = mesh.mergeable_blocks();
    const double p_split = mesh.triangle_count() < target_triangles ? 0.7 : 0.3;
    std::vector<BlockChange> changes;
    if (mergeable.empty() || uniform(rng) < p_split) {
      auto leaves = mesh.leaf_blocks();
      std::erase_if(leaves, [&](BlockId k) { return mesh.level(k) >= 9; });
      changes = mesh.split(leaves[rng() % leaves.size()]);
      splits += static_cast<int>(changes.size());
    } else {
      changes.push_back(mesh.merge(mergeable[rng() % mergeable.size()]));
      ++merges;
    }
    for (const BlockChange& ch : changes) {
      // Densities of a split come from the parents, still listed; merges read the children.
      const BlockDensities rho = densities_of(ch, density);
      carry_density(ch, density);
      transfer_mass_and_velocity(ch, rho, m, v);
    }
    ASSERT_NEAR(m.sum(), mass0, 1e-13 * mass0) << "operation " << op;
    const Eigen::RowVector3d momentum = (m.asDiagonal() * v).colwise().sum();
    ASSERT_LT((momentum - momentum0).norm(), 1e-13 * momentum_scale) << "operation " << op;
    if (op % 50 == 0) {
      const Eigen::VectorXd lumped = lumped_masses(mesh, density);
      ASSERT_LT((m.head(lumped.size()) - lumped).cwiseAbs().maxCoeff(), 1e-13 * mass0)
          << "operation " << op;
    }
  }
  EXPECT_GT(splits, operations / 4);
  EXPECT_GT(merges, operations / 4);
}

TEST(Mesh48Transfer, MassAndMomentumConservedOverThousandsOfRandomOperations) {
  const auto g = quad_grid(4, 4, 0.3, 1.0);
  check_conservation(Mesh48::from_quads(g.vertices, g.quads), 1, 4000, 600);
  check_conservation(Mesh48::from_triangles_sqrt3(icosphere(1)), 2, 3000, 800);
}

TEST(Mesh48Transfer, RemapRowsFollowsCompaction) {
  const auto g = quad_grid(3, 3);
  Mesh48 mesh = Mesh48::from_quads(g.vertices, g.quads);
  std::mt19937 rng(3);
  for (int i = 0; i < 60; ++i) {
    const auto leaves = mesh.leaf_blocks();
    (void)mesh.split(leaves[rng() % leaves.size()]);
  }
  for (const BlockId k : mesh.mergeable_blocks())
    if (mesh.can_merge(k) && rng() % 2 == 0) (void)mesh.merge(k);
  ASSERT_FALSE(mesh.is_compact());
  // Per-vertex state = the rest position, so that it can be checked after renumbering.
  Eigen::MatrixXd state = Eigen::MatrixXd::Zero(mesh.vertex_capacity(), 3);
  for (int v = 0; v < mesh.vertex_capacity(); ++v)
    if (mesh.alive(VertexId(v))) state.row(v) = mesh.rest_position(VertexId(v)).transpose();
  const Mesh48Remap remap = mesh.compact();
  const Eigen::MatrixXd moved = remap_rows(state, remap.vertices, remap.vertex_count);
  ASSERT_EQ(moved.rows(), mesh.vertex_count());
  for (int v = 0; v < mesh.vertex_count(); ++v)
    EXPECT_EQ(moved.row(v).transpose(), mesh.rest_position(VertexId(v)));
}

}  // namespace
}  // namespace sd::meshing
