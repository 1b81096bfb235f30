#include "sim/parallel.hpp"

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cmath>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "sim/body_collider.hpp"
#include "sim/cloth_model.hpp"
#include "sim/fabric.hpp"
#include "sim/forces.hpp"
#include "sim/implicit_solver.hpp"
#include "sim/self_collision.hpp"
#include "sim/sheet.hpp"
#include "tests/sim/test_bodies.hpp"

namespace sd::sim {
namespace {

// Restores the process-wide thread count after a test changes it.
class ThreadCount : public ::testing::Test {
 protected:
  void TearDown() override { set_thread_count(0); }
};

TEST_F(ThreadCount, ChunksCoverTheRangeOnceInOrderWhateverTheThreads) {
  for (int threads : {1, 2, 4}) {
    set_thread_count(threads);
    EXPECT_EQ(thread_count(), threads);
    for (int n : {0, 1, 255, 256, 1000, 100003}) {
      const int chunks = chunk_count(n, 256);
      std::vector<int> begins(static_cast<std::size_t>(chunks), -1),
          ends(static_cast<std::size_t>(chunks), -1);
      std::vector<std::atomic<int>> hits(static_cast<std::size_t>(n));
      parallel_chunks(n, 256, [&](int c, int first, int last) {
        begins[static_cast<std::size_t>(c)] = first;
        ends[static_cast<std::size_t>(c)] = last;
        for (int i = first; i < last; ++i) ++hits[static_cast<std::size_t>(i)];
      });
      for (int i = 0; i < n; ++i) ASSERT_EQ(hits[static_cast<std::size_t>(i)], 1) << n << " " << i;
      for (int c = 0; c < chunks; ++c) {
        EXPECT_EQ(begins[static_cast<std::size_t>(c)],
                  c == 0 ? 0 : ends[static_cast<std::size_t>(c - 1)]);
        // At least the grain long, except when the range itself is shorter.
        EXPECT_GE(ends[static_cast<std::size_t>(c)] - begins[static_cast<std::size_t>(c)],
                  std::min(n, 256));
      }
      if (chunks > 0) {
        EXPECT_EQ(ends.back(), n);
      }
    }
  }
  set_thread_count(0);
  EXPECT_GE(thread_count(), 1);
}

// The contact queries give the same contacts, in the same order, with the same counts, on one
// thread and on four: the chunks depend on the vertex count only.
TEST_F(ThreadCount, ContactQueriesAreTheSameOnOneAndManyThreads) {
  const BodyCollider body(testing::make_sphere(0.3, 4));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.36, 0.36);
  Eigen::VectorXd x0(3 * 5000), x1(3 * 5000);
  for (Eigen::Index i = 0; i < x0.size(); ++i) {
    x0[i] = u(rng);
    x1[i] = x0[i] + 0.1 * u(rng);
  }
  ContactQuery query;
  query.thickness = 0.01;
  const auto run = [&](int threads, bool swept) {
    set_thread_count(threads);
    ContactCache cache;
    ContactQueryStats stats;
    std::vector<BodyContact> contacts =
        swept ? body.find_contacts_swept(x0, x1, query, &cache, &stats)
              : body.find_contacts(x1, query, &cache, &stats);
    return std::make_pair(contacts, stats);
  };
  for (bool swept : {false, true}) {
    const auto [one, one_stats] = run(1, swept);
    const auto [four, four_stats] = run(4, swept);
    ASSERT_GT(one.size(), 100u) << "the sample must put many points near the sphere";
    ASSERT_EQ(one.size(), four.size());
    for (std::size_t k = 0; k < one.size(); ++k) {
      EXPECT_EQ(one[k].vertex, four[k].vertex);
      EXPECT_EQ(one[k].triangle, four[k].triangle);
      EXPECT_EQ(one[k].distance, four[k].distance);  // bit for bit
      EXPECT_EQ(one[k].crossed, four[k].crossed);
    }
    EXPECT_EQ(one_stats.vertices, 5000);
    EXPECT_EQ(four_stats.vertices, 5000);
    EXPECT_EQ(one_stats.bounded_searches, four_stats.bounded_searches);
    EXPECT_EQ(one_stats.full_searches, four_stats.full_searches);
    EXPECT_EQ(one_stats.sweep_samples, four_stats.sweep_samples);
    EXPECT_EQ(one_stats.crossings, four_stats.crossings);
  }
}

// The self-collision queries test the triangle pairs the tree traversal reaches in chunks on
// many threads and join them in traversal order: the same element pairs, in the same order,
// with the same counts on one thread and on four. A 30x30 sheet crumpled at random (jitter
// about half an edge, so many pairs are near) moving by a random step.
TEST_F(ThreadCount, SelfCollisionQueriesAreTheSameOnOneAndManyThreads) {
  SheetSpec spec;
  spec.columns = spec.rows = 30;
  const SheetScene scene = build_sheet(spec);
  std::vector<std::array<int, 3>> triangles;
  const Eigen::MatrixX3i& faces = scene.input.triangles;
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    triangles.push_back({faces(f, 0), faces(f, 1), faces(f, 2)});
  // Over 1,000 triangles: the tree's refit runs its subtrees on the threads and its nodes'
  // boundaries are found in chunks (sim/self_collision.cpp), and the culling they feed decides
  // which pairs are tested.
  ASSERT_GT(triangles.size(), 1000u);
  std::mt19937 rng(5);
  std::normal_distribution<double> jitter(0.0, 0.015);  // m; edges are 1/30 m
  Eigen::VectorXd x0 = flatten_positions(scene.input.rest_positions);
  Eigen::VectorXd x1 = x0;
  for (Eigen::Index i = 0; i < x0.size(); ++i) {
    x0[i] += jitter(rng);
    x1[i] = x0[i] + 0.5 * jitter(rng);
  }
  const auto run = [&](int threads, bool swept) {
    set_thread_count(threads);
    SelfCollider collider(triangles, x0);
    SelfQueryStats stats;
    std::vector<SelfPair> pairs = swept ? collider.find_collisions(x0, x1, 0.002, &stats)
                                        : collider.find_proximities(x0, 0.01, &stats);
    return std::make_pair(pairs, stats);
  };
  for (const bool swept : {false, true}) {
    const auto [one, one_stats] = run(1, swept);
    const auto [four, four_stats] = run(4, swept);
    ASSERT_GT(one_stats.triangle_pairs, 1000) << "several chunks of triangle pairs";
    ASSERT_GT(one.size(), 10u) << swept;
    ASSERT_EQ(one.size(), four.size());
    for (std::size_t k = 0; k < one.size(); ++k) {
      EXPECT_EQ(one[k].kind, four[k].kind);
      EXPECT_EQ(one[k].vertices, four[k].vertices);
      EXPECT_EQ(one[k].weights, four[k].weights);  // bit for bit
      EXPECT_EQ(one[k].normal, four[k].normal);
    }
    EXPECT_EQ(one_stats.element_tests, four_stats.element_tests);
    EXPECT_EQ(one_stats.triangle_pairs, four_stats.triangle_pairs);
    EXPECT_EQ(one_stats.pairs_found, four_stats.pairs_found);
  }
}

// The force evaluation computes its elements' conditions on many threads and adds them into the
// rows each thread owns (sim/forces.cpp): the force, the energies, the matrix and the product
// ∂f/∂x·u must be the same bits as on one thread. A 40×40 sheet
// (3,200 triangles, 4,720 hinges: several blocks of elements) in a random crumpled state.
TEST_F(ThreadCount, ForcesAndJacobianAreTheSameOnOneAndManyThreads) {
  SheetSpec spec;
  spec.columns = spec.rows = 40;
  const SheetScene scene = build_sheet(spec);
  for (const BendModel bend : {BendModel::hinges, BendModel::quadratic}) {
    ClothModelOptions options;
    options.bend_model = bend;
    const ClothModel model = build_cloth_model(scene.input, fabric_preset("cotton"), options);
    std::mt19937 rng(11);
    std::normal_distribution<double> jitter(0.0, 0.004);  // m, a fifth of an edge
    Eigen::VectorXd x = flatten_positions(scene.input.rest_positions);
    Eigen::VectorXd v(x.size());
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      x[i] += jitter(rng);
      v[i] = 10.0 * jitter(rng);
    }
    const auto run = [&](int threads, JacobianKind kind) {
      set_thread_count(threads);
      SparseMatrixR matrix = model.pattern.zero_matrix;
      JacobianTarget target;
      target.kind = kind;
      target.matrix = &matrix;
      target.dfdx_scale = -1e-4;
      target.dfdv_scale = -1e-2;
      // The product ∂f/∂x·u as the implicit solver's first iteration asks for it.
      const Eigen::VectorXd u = 1e-3 * v;
      Eigen::VectorXd product = Eigen::VectorXd::Zero(x.size());
      target.product_input = &u;
      target.product_output = &product;
      Eigen::VectorXd force;
      EnergyBreakdown energy;
      evaluate_forces(model, ForceSettings{}, x, v, force, &energy, &target);
      return std::make_tuple(force, energy, matrix, product);
    };
    for (const JacobianKind kind : {JacobianKind::solve, JacobianKind::exact}) {
      const auto [force1, energy1, matrix1, product1] = run(1, kind);
      const auto [force2, energy2, matrix2, product2] = run(2, kind);
      const auto [force4, energy4, matrix4, product4] = run(4, kind);
      ASSERT_GT(force1.norm(), 0.0);
      ASSERT_GT(product1.norm(), 0.0);
      EXPECT_TRUE(force1 == force2 && force1 == force4);  // bit for bit
      EXPECT_TRUE(product1 == product2 && product1 == product4);
      EXPECT_EQ(energy1.stretch, energy2.stretch);
      EXPECT_EQ(energy1.shear, energy2.shear);
      EXPECT_EQ(energy1.stretch, energy4.stretch);
      EXPECT_EQ(energy1.shear, energy4.shear);
      EXPECT_EQ(energy1.bend, energy2.bend);
      EXPECT_EQ(energy1.bend, energy4.bend);
      ASSERT_EQ(matrix1.nonZeros(), matrix4.nonZeros());
      EXPECT_TRUE(std::equal(matrix1.valuePtr(), matrix1.valuePtr() + matrix1.nonZeros(),
                             matrix2.valuePtr()));
      EXPECT_TRUE(std::equal(matrix1.valuePtr(), matrix1.valuePtr() + matrix1.nonZeros(),
                             matrix4.valuePtr()));
    }
  }
}

// Pair springs between far parts of a 40×40 sheet widen the solver's matrix by blocks outside
// the mesh's pattern; the widened matrix is written in place by rows on the threads
// (ImplicitSolver::add_cross_blocks). It must be the same bits on any thread count, symmetric,
// hold every cross block, and the CHOLMOD step on it the same bits too.
TEST_F(ThreadCount, PairSpringCrossBlocksAreTheSameOnOneAndManyThreads) {
  SheetSpec spec;
  spec.columns = spec.rows = 40;
  const SheetScene scene = build_sheet(spec);
  const ClothModel model = build_cloth_model(scene.input, fabric_preset("cotton"));
  ASSERT_GT(model.vertex_count, 1024) << "several chunks of rows";
  const Eigen::VectorXd x = flatten_positions(scene.input.rest_positions);
  Eigen::VectorXd v = Eigen::VectorXd::Zero(x.size());
  for (int i = 0; i < model.vertex_count; ++i) v[3 * i + 1] = -0.2 - 1e-4 * i;
  StepForces extra;
  // A vertex of the first rows held against a triangle of the last rows, and back.
  const int triangles = static_cast<int>(model.triangles.size());
  for (int k = 0; k < 60; ++k) {
    const int near = 7 * k, far = triangles - 1 - 11 * k;
    for (const auto& [vertex, triangle] :
         {std::pair{near, far}, std::pair{model.vertex_count - 1 - 5 * k, 3 * k}}) {
      PairSpring spring;
      const std::array<int, 3>& corners = model.triangles[triangle].vertices;
      spring.vertices = {vertex, corners[0], corners[1], corners[2]};
      spring.weights << 1.0, -0.2, -0.5, -0.3;
      spring.normal = Eigen::Vector3d(0.1, 1.0, -0.2).normalized();
      spring.target = 0.005;
      spring.stiffness = 30.0;
      spring.damping = 0.4;
      spring.friction = 1.5;
      extra.pair_springs.push_back(spring);
    }
  }
  NewtonSettings settings;
  settings.solver = LinearSolverKind::cholmod;
  const ConstraintFilter filter(model.vertex_count);
  const auto run = [&](int threads) {
    set_thread_count(threads);
    ImplicitSolver solver;
    const ImplicitSolveResult r =
        solver.solve(model, ForceSettings{}, filter, x, v, 1.0 / 60.0, x, v, settings, &extra);
    return std::make_pair(SparseMatrixR(solver.matrix()), r.v);
  };
  const auto [matrix1, v1] = run(1);
  const auto [matrix4, v4] = run(4);
  const SparseMatrixR& mesh = model.pattern.zero_matrix;
  int cross = 0;  // blocks not in the mesh's pattern, one per ordered pair of vertices
  std::set<std::pair<int, int>> pairs;
  for (const PairSpring& s : extra.pair_springs)
    for (int i : s.vertices)
      for (int j : s.vertices)
        if (i != j && block_offset(mesh, i, j) < 0 && pairs.insert({i, j}).second) ++cross;
  ASSERT_GT(cross, 100);
  EXPECT_EQ(matrix1.nonZeros(), mesh.nonZeros() + 9 * cross);
  for (const auto& [i, j] : pairs) EXPECT_GE(block_offset(matrix1, i, j), 0) << i << " " << j;
  // Symmetric to rounding (the elements' Hessians are): a cross block written into the wrong
  // row or place would leave an O(1) difference.
  EXPECT_LT(SparseMatrixR(matrix1 - SparseMatrixR(matrix1.transpose())).norm(),
            1e-12 * matrix1.norm());
  ASSERT_EQ(matrix1.nonZeros(), matrix4.nonZeros());
  EXPECT_TRUE(std::equal(matrix1.outerIndexPtr(), matrix1.outerIndexPtr() + matrix1.rows() + 1,
                         matrix4.outerIndexPtr()));
  EXPECT_TRUE(std::equal(matrix1.innerIndexPtr(), matrix1.innerIndexPtr() + matrix1.nonZeros(),
                         matrix4.innerIndexPtr()));
  EXPECT_TRUE(
      std::equal(matrix1.valuePtr(), matrix1.valuePtr() + matrix1.nonZeros(), matrix4.valuePtr()));
  ASSERT_TRUE(v1.allFinite());
  EXPECT_TRUE(v1 == v4);  // bit for bit
}

// Body vertices through a crumpled cloth: the same piercings in the same order on any thread count.
TEST_F(ThreadCount, PiercingSearchIsTheSameOnOneAndManyThreads) {
  const BodyCollider body(testing::make_sphere(0.3, 5));  // 10,242 vertices: several chunks
  // A 40×40 grid of triangles wrapped at radius 0.3 ± 1 cm around the sphere's upper half.
  constexpr int kN = 40;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> jitter(-0.01, 0.01);
  Eigen::VectorXd x(3 * (kN + 1) * (kN + 1));
  for (int i = 0; i <= kN; ++i)
    for (int j = 0; j <= kN; ++j) {
      const double theta = 1.4 * i / kN - 0.7, phi = 1.4 * j / kN - 0.7;
      const Eigen::Vector3d dir(std::sin(theta), std::cos(theta) * std::cos(phi),
                                std::cos(theta) * std::sin(phi));
      x.segment<3>(3 * (i * (kN + 1) + j)) = (0.3 + jitter(rng)) * dir.normalized();
    }
  std::vector<std::array<int, 3>> triangles;
  for (int i = 0; i < kN; ++i)
    for (int j = 0; j < kN; ++j) {
      const int a = i * (kN + 1) + j, b = a + 1, c = a + kN + 1, d = c + 1;
      triangles.push_back({a, c, b});
      triangles.push_back({b, c, d});
    }
  const ClothTriangles cloth(triangles);
  const auto run = [&](int threads) {
    set_thread_count(threads);
    PiercingQueryStats stats;
    std::vector<BodyPiercing> found =
        body.find_piercings(x, cloth, -0.02, 0.02, 0.0, &stats, /*every_triangle=*/true);
    return std::make_pair(found, stats);
  };
  const auto [one, one_stats] = run(1);
  const auto [four, four_stats] = run(4);
  ASSERT_GT(one.size(), 50u) << "the jittered cloth must cover body vertices from both sides";
  ASSERT_EQ(one.size(), four.size());
  for (std::size_t k = 0; k < one.size(); ++k) {
    EXPECT_EQ(one[k].body_vertex, four[k].body_vertex);
    EXPECT_EQ(one[k].cloth_triangle, four[k].cloth_triangle);
    EXPECT_EQ(one[k].height, four[k].height);
  }
  EXPECT_EQ(one_stats.body_vertices, four_stats.body_vertices);
  EXPECT_EQ(one_stats.pairs, four_stats.pairs);
  EXPECT_EQ(one_stats.inside_checks, four_stats.inside_checks);
  EXPECT_EQ(one_stats.piercings, four_stats.piercings);
}

}  // namespace
}  // namespace sd::sim
