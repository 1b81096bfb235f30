// Kernels the other benchmark files do not time on their own, each with the bytes it must move
// so docs/benchmarks.md can set it against the memory bandwidth measured here (STREAM triad):
// the sparse matrix-vector product of the 64x64 sheet's system, one CHOLMOD numeric
// factorisation and one CHOLMOD solve (symbolic analysis reused, as in a run). Force assembly,
// one PCG iteration (sim_bench), the BVH point query (collision_bench) and one 4-8 split
// (mesh48_bench) are timed in their modules' files.
//
// Run with OPENBLAS_NUM_THREADS=1 (the simulator's setting on this 2-core machine).

#include <benchmark/benchmark.h>

#include <Eigen/Core>
#include <vector>

#include "sim/cholmod_solver.hpp"
#include "sim/cloth_model.hpp"
#include "sim/constraint_filter.hpp"
#include "sim/fabric.hpp"
#include "sim/forces.hpp"
#include "sim/implicit_solver.hpp"
#include "sim/sheet.hpp"

namespace {

using namespace sd::sim;

// The system matrix A = M − h ∂f/∂v − h² ∂f/∂x of a 1 m cotton sheet of n×n quads, slightly
// stretched (random 1 mm offsets), pinned at two corners, h = 1/60 s: what a step solves.
struct System {
  ClothModel model;
  SparseMatrixR a;
  Eigen::VectorXd b;
  ConstraintFilter filter;
};

System sheet_system(int n) {
  SheetSpec spec;
  spec.columns = spec.rows = n;
  spec.orientation = SheetOrientation::horizontal;
  spec.pins = {"top-left", "top-right"};
  const SheetScene scene = build_sheet(spec);
  System s{build_cloth_model(scene.input, fabric_preset("cotton")), {}, {}, {}};
  Eigen::VectorXd x = flatten_positions(scene.input.rest_positions);
  x += 1e-3 * Eigen::VectorXd::Random(x.size());
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(x.size());
  s.a = s.model.pattern.zero_matrix;
  for (int i = 0; i < s.model.vertex_count; ++i)
    for (int k = 0; k < 3; ++k)
      s.a.valuePtr()[block_value_index(
          s.a, i, s.model.pattern.diagonal_offsets[static_cast<size_t>(i)], k, k)] =
          s.model.mass[i];
  const double h = 1.0 / 60;
  JacobianTarget target;
  target.matrix = &s.a;
  target.dfdx_scale = -h * h;
  target.dfdv_scale = -h;
  Eigen::VectorXd force;
  evaluate_forces(s.model, ForceSettings{}, x, v, force, nullptr, &target);
  s.b = h * force;
  s.filter = ConstraintFilter(s.model.vertex_count);
  for (int p : scene.pinned_vertices) s.filter.pin(p, Eigen::Vector3d::Zero());
  return s;
}

// Bytes an SpMV must stream at least: values (8) + column indices (4) per non-zero, row
// pointers (4) per row, x read and y written (8 + 8) per row (x is re-read from cache).
double spmv_bytes(const SparseMatrixR& a) {
  return 12.0 * static_cast<double>(a.nonZeros()) + 20.0 * static_cast<double>(a.rows());
}

// y = A x with the 3n×3n row-major matrix (Eigen), arg: quads per side.
void BM_SpMV(benchmark::State& state) {
  const System s = sheet_system(static_cast<int>(state.range(0)));
  const Eigen::VectorXd x = Eigen::VectorXd::Random(s.a.cols());
  Eigen::VectorXd y(s.a.rows());
  for (auto _ : state) {
    y.noalias() = s.a * x;
    benchmark::DoNotOptimize(y.data());
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * spmv_bytes(s.a)));
  state.counters["vertices"] = s.model.vertex_count;
  state.counters["matrix_MB"] = spmv_bytes(s.a) / 1e6;
  state.counters["ns_per_vertex"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * s.model.vertex_count * 1e-9,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_SpMV)->Arg(64)->Arg(128)->Unit(benchmark::kMicrosecond);

// One numeric factorisation of S A S + (I − S) after the first (analysed) one: what each
// implicit Euler step pays with CHOLMOD.
void BM_CholmodFactor(benchmark::State& state) {
  const System s = sheet_system(static_cast<int>(state.range(0)));
  CholmodSolver solver;
  if (!solver.factorize(s.a, s.filter)) state.SkipWithError("matrix not positive definite");
  for (auto _ : state) benchmark::DoNotOptimize(solver.factorize(s.a, s.filter));
  state.counters["vertices"] = s.model.vertex_count;
  state.counters["analyses"] = solver.symbolic_analyses();
}
BENCHMARK(BM_CholmodFactor)->Arg(32)->Arg(64)->Unit(benchmark::kMillisecond);

// The symbolic analysis and the first numeric factorisation of a new pattern: what a step
// after an adaptive topology change pays (BM_CholmodFactor is the factorisation alone).
void BM_CholmodAnalyseAndFactor(benchmark::State& state) {
  const System s = sheet_system(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    CholmodSolver solver;
    benchmark::DoNotOptimize(solver.factorize(s.a, s.filter));
  }
  state.counters["vertices"] = s.model.vertex_count;
}
BENCHMARK(BM_CholmodAnalyseAndFactor)->Arg(32)->Arg(64)->Unit(benchmark::kMillisecond);

// One linearised implicit Euler solve with CHOLMOD (assembly, factorisation, solve) of the 64x64
// sheet, each step with a different subset of 40 self-contact pair springs across the sheet
// (vertex i against the triangle of vertex i + 600: not neighbours in the mesh), as a garment's
// springs come and go: the solver keeps the cross blocks of earlier steps so that the pattern,
// and its symbolic analysis, stay (counter: analyses per solve).
void BM_CholmodPairSpringsComeAndGo(benchmark::State& state) {
  const System s = sheet_system(64);
  const ClothModel& model = s.model;
  SheetSpec spec;
  spec.columns = spec.rows = 64;
  spec.orientation = SheetOrientation::horizontal;
  spec.pins = {"top-left", "top-right"};
  const Eigen::VectorXd x = flatten_positions(build_sheet(spec).input.rest_positions);
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(x.size());
  std::vector<StepForces> steps(8);
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 40; ++j) {
      if ((j + k) % 3 == 0) continue;  // each step leaves out a different third
      const int i = 100 + 50 * j;
      PairSpring spring;
      spring.vertices = {i, model.triangles[i + 600].vertices[0],
                         model.triangles[i + 600].vertices[1],
                         model.triangles[i + 600].vertices[2]};
      spring.weights << 1.0, -1.0 / 3.0, -1.0 / 3.0, -1.0 / 3.0;
      spring.normal = Eigen::Vector3d::UnitY();
      spring.target = 0.004;
      spring.stiffness = 50.0;
      spring.damping = 0.5;
      steps[k].pair_springs.push_back(spring);
    }
  NewtonSettings settings;
  settings.solver = LinearSolverKind::cholmod;
  ImplicitSolver solver;
  std::size_t k = 0;
  for (auto _ : state) {
    const ImplicitSolveResult r = solver.solve(model, ForceSettings{}, s.filter, x, v, 1.0 / 60, x,
                                               v, settings, &steps[k++ % steps.size()]);
    benchmark::DoNotOptimize(r.v.data());
  }
  state.counters["vertices"] = model.vertex_count;
  state.counters["analyses_per_solve"] =
      static_cast<double>(solver.cholmod().symbolic_analyses()) /
      static_cast<double>(solver.cholmod().numeric_factorizations());
}
BENCHMARK(BM_CholmodPairSpringsComeAndGo)->Unit(benchmark::kMillisecond);

// One solve with the factor (forward and back substitution plus the filtering).
void BM_CholmodSolve(benchmark::State& state) {
  const System s = sheet_system(static_cast<int>(state.range(0)));
  CholmodSolver solver;
  if (!solver.factorize(s.a, s.filter)) state.SkipWithError("matrix not positive definite");
  const Eigen::VectorXd z = Eigen::VectorXd::Zero(s.b.size());
  Eigen::VectorXd x;
  for (auto _ : state) {
    solver.solve(s.a, s.filter, s.b, z, x);
    benchmark::DoNotOptimize(x.data());
  }
  state.counters["vertices"] = s.model.vertex_count;
}
BENCHMARK(BM_CholmodSolve)->Arg(32)->Arg(64)->Unit(benchmark::kMillisecond);

// STREAM triad a = b + s·c over 3 × 64 MB: the machine's sustainable memory bandwidth (read
// b and c, write a: 24 bytes per element counted, as STREAM does).
void BM_StreamTriad(benchmark::State& state) {
  const std::size_t n = 8u << 20;
  std::vector<double> a(n, 0.0), b(n, 1.0), c(n, 2.0);
  const double scalar = 3.0;
  for (auto _ : state) {
    double* __restrict pa = a.data();
    const double* __restrict pb = b.data();
    const double* __restrict pc = c.data();
    for (std::size_t i = 0; i < n; ++i) pa[i] = pb[i] + scalar * pc[i];
    benchmark::DoNotOptimize(a.data());
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * 3 * static_cast<int64_t>(n) *
                          static_cast<int64_t>(sizeof(double)));
}
BENCHMARK(BM_StreamTriad)->Unit(benchmark::kMillisecond);

}  // namespace
