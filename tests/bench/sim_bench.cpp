// Simulator kernels and the 64x64 sheet drape (docs/benchmarks.md, "Simulator").
#include <benchmark/benchmark.h>

#include <Eigen/IterativeLinearSolvers>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "sim/cholmod_solver.hpp"
#include "sim/forces.hpp"
#include "sim/parallel.hpp"
#include "sim/pcg_solver.hpp"
#include "sim/sheet.hpp"
#include "sim/simulation.hpp"

namespace {

using namespace sd::sim;

struct Sheet {
  SheetScene scene;
  ClothModel model;
};

// 1 m cotton sheet, horizontal, pinned at its two far corners: it falls and swings.
Sheet sheet(int n) {
  SheetSpec spec;
  spec.size = {1.0, 1.0};
  spec.columns = n;
  spec.rows = n;
  spec.orientation = SheetOrientation::horizontal;
  spec.pins = {"top-left", "top-right"};
  Sheet s{build_sheet(spec), {}};
  s.model = build_cloth_model(s.scene.input, fabric_preset("cotton"));
  return s;
}

std::vector<Pin> pins(const Sheet& s) {
  std::vector<Pin> out;
  for (int v : s.scene.pinned_vertices) out.push_back({v, {}});
  return out;
}

SimulationSettings drape_settings(LinearSolverKind solver, Integrator integrator) {
  SimulationSettings settings;
  settings.solver = solver;
  settings.integrator = integrator;
  settings.dt = 1.0 / 24;  // one step per film frame, as Blender's reference figure
  settings.duration = 2.0;
  settings.stop_at_rest = false;
  settings.record_energy = false;
  settings.forces.air_drag = 0.1;
  return settings;
}

// Linear solver by benchmark argument: 0 PCG + block Jacobi, 1 CHOLMOD, 2 PCG + block IC(0).
void set_solver(SimulationSettings& settings, int64_t which) {
  settings.solver = which == 1 ? LinearSolverKind::cholmod : LinearSolverKind::pcg;
  settings.pcg_preconditioner =
      which == 0 ? PcgPreconditioner::block_jacobi : PcgPreconditioner::block_incomplete_cholesky;
}

// The whole 2 s drape of the 64x64 sheet; args: solver (see set_solver), integrator (0 IE,
// 1 BDF2 with simplified Newton and its fallback, 2 linearly implicit BDF2: one solve a step).
void BM_SheetDrape64(benchmark::State& state) {
  const Sheet s = sheet(64);
  const auto integrator = state.range(1) == 0 ? Integrator::implicit_euler : Integrator::bdf2;
  SimulationSettings settings = drape_settings(LinearSolverKind::pcg, integrator);
  set_solver(settings, state.range(0));
  if (state.range(1) == 2) settings.newton_iterations = 1;
  SimulationReport report;
  for (auto _ : state) {
    Simulation sim(s.model, flatten_positions(s.scene.input.rest_positions), pins(s), settings);
    report = sim.run();
    benchmark::DoNotOptimize(sim.positions().data());
  }
  state.counters["steps"] = report.steps;
  state.counters["retries"] = report.retries;
  state.counters["cg_mean"] = report.cg_iterations_mean;
  state.counters["cg_max"] = report.cg_iterations_max;
  state.counters["newton_mean"] = report.newton_iterations_mean;
  state.counters["wall_s"] = report.wall_time_s;
  state.counters["ms_per_frame"] = 1e3 * report.wall_time_s / (report.sim_time * 24.0);
  state.counters["forces_s"] = report.forces_s;
  state.counters["solve_s"] = report.solve_s;
  state.counters["max_strain"] = report.max_strain;
  state.counters["fallbacks"] = report.integrator_fallbacks;
  state.counters["vertices"] = report.vertices;
}
BENCHMARK(BM_SheetDrape64)
    ->ArgsProduct({{0, 1, 2}, {0}})
    ->ArgsProduct({{1, 2}, {1, 2}})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// One implicit Euler step of the 64x64 sheet in mid-swing (after 0.5 s).
void BM_SheetStep64(benchmark::State& state) {
  const Sheet s = sheet(64);
  SimulationSettings settings = drape_settings(LinearSolverKind::pcg, Integrator::implicit_euler);
  set_solver(settings, state.range(0));
  settings.duration = 0.5;
  Simulation warm(s.model, flatten_positions(s.scene.input.rest_positions), pins(s), settings);
  warm.run();
  const Eigen::VectorXd x = warm.positions();
  const Eigen::VectorXd v = warm.velocities();
  for (auto _ : state) {
    state.PauseTiming();
    Simulation sim(s.model, x, pins(s), settings);
    sim.set_velocities(v);
    state.ResumeTiming();
    benchmark::DoNotOptimize(sim.step().cg_iterations);
  }
}
BENCHMARK(BM_SheetStep64)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// The linear system of that mid-swing step (implicit Euler, h = 1/24 s, pins at rest):
// A = M − h ∂f/∂v − h² ∂f/∂x, b = h (f + h ∂f/∂x v), and its exact solution (CHOLMOD).
struct MidSwingSystem {
  Sheet sheet;
  SparseMatrixR a;
  Eigen::VectorXd b, z, exact;
  ConstraintFilter filter;
};

const MidSwingSystem& mid_swing_system() {
  static const MidSwingSystem system = [] {
    MidSwingSystem m{sheet(64), {}, {}, {}, {}, {}};
    const Sheet& s = m.sheet;
    SimulationSettings settings =
        drape_settings(LinearSolverKind::cholmod, Integrator::implicit_euler);
    settings.duration = 0.5;
    Simulation warm(s.model, flatten_positions(s.scene.input.rest_positions), pins(s), settings);
    warm.run();
    const double h = 1.0 / 24;
    m.a = s.model.pattern.zero_matrix;
    for (int i = 0; i < s.model.vertex_count; ++i)
      for (int k = 0; k < 3; ++k)
        m.a.valuePtr()[block_value_index(m.a, i, s.model.pattern.diagonal_offsets[i], k, k)] =
            s.model.mass[i];
    Eigen::VectorXd force, kv = Eigen::VectorXd::Zero(warm.velocities().size());
    JacobianTarget target;
    target.matrix = &m.a;
    target.dfdx_scale = -h * h;
    target.dfdv_scale = -h;
    target.product_input = &warm.velocities();
    target.product_output = &kv;
    evaluate_forces(s.model, settings.forces, warm.positions(), warm.velocities(), force, nullptr,
                    &target);
    m.b = h * (force + h * kv);
    m.filter = ConstraintFilter(s.model.vertex_count);
    for (int p : s.scene.pinned_vertices) m.filter.pin(p, Eigen::Vector3d::Zero());
    m.filter.constrained_correction(warm.velocities(), m.z);
    CholmodSolver cholmod;
    cholmod.factorize(m.a, m.filter);
    cholmod.solve(m.a, m.filter, m.b, m.z, m.exact);
    return m;
  }();
  return system;
}

// Error of an approximate solution in the energy norm of A, relative to the exact step.
double energy_error(const MidSwingSystem& m, const Eigen::VectorXd& s) {
  const Eigen::VectorXd e = s - m.exact;
  const Eigen::VectorXd d = m.exact - m.z;
  return std::sqrt(e.dot(m.a * e) / d.dot(m.a * d));
}

// The PCG alone on the mid-swing system; args: preconditioner (0 block Jacobi, 1 block IC(0)),
// tolerance 10^-arg. Reports iterations and the energy-norm error of the result.
void BM_MidSwingPcg64(benchmark::State& state) {
  const MidSwingSystem& m = mid_swing_system();
  PcgSolver pcg(state.range(0) == 0 ? PcgPreconditioner::block_jacobi
                                    : PcgPreconditioner::block_incomplete_cholesky);
  const double tolerance = std::pow(10.0, -static_cast<double>(state.range(1)));
  Eigen::VectorXd step;
  LinearSolveStats stats;
  for (auto _ : state) {
    stats = pcg.solve(m.a, m.sheet.model.pattern.diagonal_offsets, m.filter, m.b, m.z, step,
                      tolerance, 5000);
    benchmark::DoNotOptimize(step.data());
  }
  state.counters["iterations"] = stats.iterations;
  state.counters["energy_error"] = energy_error(m, step);
  state.counters["residual"] = constrained_relative_residual(m.a, m.filter, m.b, m.z, step);
}
BENCHMARK(BM_MidSwingPcg64)->ArgsProduct({{0, 1}, {2, 3, 4}})->Unit(benchmark::kMillisecond);

// Building each preconditioner alone (block IC(0): filtered copy + factorisation).
void BM_MidSwingIncompleteCholesky64(benchmark::State& state) {
  const MidSwingSystem& m = mid_swing_system();
  BlockIncompleteCholesky ic;
  for (auto _ : state)
    benchmark::DoNotOptimize(ic.factorize(m.a, m.sheet.model.pattern.diagonal_offsets, m.filter));
  state.counters["shift"] = ic.shift();
}
BENCHMARK(BM_MidSwingIncompleteCholesky64)->Unit(benchmark::kMillisecond);

// Eigen's scalar IncompleteCholesky (AMD ordering, fill limited to the pattern's column counts,
// diagonal shift) in Eigen's CG on the explicitly filtered matrix S A S + (I − S), to the
// same Euclidean residual reduction the block IC(0) PCG reaches at 1e-3.
void BM_MidSwingEigenIncompleteCholesky64(benchmark::State& state) {
  const MidSwingSystem& m = mid_swing_system();
  using ColMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
  ColMatrix filtered = m.a;  // structurally symmetric
  const int n = m.sheet.model.vertex_count;
  for (int k = 0; k < filtered.outerSize(); ++k)
    for (ColMatrix::InnerIterator it(filtered, k); it; ++it) {
      const int i = static_cast<int>(it.row()) / 3, j = static_cast<int>(it.col()) / 3;
      if (!m.filter.is_free(i) || !m.filter.is_free(j))
        it.valueRef() = it.row() == it.col() ? 1.0 : 0.0;  // pins only: S_i = 0
    }
  Eigen::VectorXd rhs = m.b - m.a * m.z;
  m.filter.apply(rhs);
  PcgSolver reference(PcgPreconditioner::block_incomplete_cholesky);
  Eigen::VectorXd step;
  reference.solve(m.a, m.sheet.model.pattern.diagonal_offsets, m.filter, m.b, m.z, step, 1e-3,
                  5000);
  const double target = constrained_relative_residual(m.a, m.filter, m.b, m.z, step);
  Eigen::ConjugateGradient<ColMatrix, Eigen::Lower | Eigen::Upper,
                           Eigen::IncompleteCholesky<double, Eigen::Lower>>
      cg;
  cg.setTolerance(target);
  cg.setMaxIterations(5000);
  Eigen::VectorXd y;
  for (auto _ : state) {
    cg.compute(filtered);
    y = cg.solve(rhs);
    benchmark::DoNotOptimize(y.data());
  }
  Eigen::VectorXd s = m.z + y;
  state.counters["iterations"] = static_cast<double>(cg.iterations());
  state.counters["energy_error"] = energy_error(m, s);
  state.counters["residual"] = constrained_relative_residual(m.a, m.filter, m.b, m.z, s);
  state.counters["vertices"] = n;
}
BENCHMARK(BM_MidSwingEigenIncompleteCholesky64)->Unit(benchmark::kMillisecond);

// CHOLMOD on the mid-swing system: numeric factorisation (analysis reused) + solve;
// arg 0 supernodal, 1 simplicial.
void BM_MidSwingCholmod64(benchmark::State& state) {
  const MidSwingSystem& m = mid_swing_system();
  CholmodSolver cholmod(state.range(0) == 0 ? CholmodMethod::supernodal
                                            : CholmodMethod::simplicial);
  Eigen::VectorXd step;
  cholmod.factorize(m.a, m.filter);  // the symbolic analysis, outside the timing
  for (auto _ : state) {
    cholmod.factorize(m.a, m.filter);
    cholmod.solve(m.a, m.filter, m.b, m.z, step);
    benchmark::DoNotOptimize(step.data());
  }
  state.counters["energy_error"] = energy_error(m, step);
}
BENCHMARK(BM_MidSwingCholmod64)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Force and Jacobian assembly alone (64x64).
void BM_AssembleForcesJacobian64(benchmark::State& state) {
  const Sheet s = sheet(64);
  const Eigen::VectorXd x = flatten_positions(s.scene.input.rest_positions);
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(x.size());
  SparseMatrixR matrix = s.model.pattern.zero_matrix;
  Eigen::VectorXd force;
  JacobianTarget target;
  target.matrix = &matrix;
  target.dfdx_scale = -1e-3;
  target.dfdv_scale = -1e-2;
  for (auto _ : state) {
    evaluate_forces(s.model, ForceSettings{}, x, v, force, nullptr, &target);
    benchmark::DoNotOptimize(force.data());
  }
}
BENCHMARK(BM_AssembleForcesJacobian64)->Unit(benchmark::kMillisecond);

// Times the solve's assembly (forces, matrix with the implicit step's scales, product ∂f/∂x·u)
// of `model` on `scene`'s sheet crumpled by a fixed pattern, a fifth of an edge, with fixed
// velocities; returns the number of matrix entries the pattern holds.
Eigen::Index time_crumpled_assembly(benchmark::State& state, const ClothModel& model,
                                    const SheetScene& scene) {
  Eigen::VectorXd x = flatten_positions(scene.input.rest_positions);
  Eigen::VectorXd v(x.size());
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    x[i] += 0.004 * std::sin(1.7 * static_cast<double>(i));
    v[i] = 0.04 * std::cos(0.9 * static_cast<double>(i));
  }
  const Eigen::VectorXd u = 1e-3 * v;
  SparseMatrixR matrix = model.pattern.zero_matrix;
  Eigen::VectorXd force, product(x.size());
  JacobianTarget target;
  target.matrix = &matrix;
  target.dfdx_scale = -1e-3;
  target.dfdv_scale = -1e-2;
  target.product_input = &u;
  target.product_output = &product;
  for (auto _ : state) {
    std::fill(matrix.valuePtr(), matrix.valuePtr() + matrix.nonZeros(), 0.0);
    product.setZero();
    evaluate_forces(model, ForceSettings{}, x, v, force, nullptr, &target);
    benchmark::DoNotOptimize(force.data());
  }
  return matrix.nonZeros();
}

// Force and Jacobian assembly of a garment-sized cloth as garments bend it (hinges), with the
// implicit solver's product ∂f/∂x·u: a 48×48 sheet (2,401 vertices, 4,608 triangles, 6,816
// hinges), crumpled, on range(0) threads (sim/parallel.hpp). Wall time: the point of a second
// thread (the machine's other load shows here too).
void BM_AssembleHingesForcesJacobian(benchmark::State& state) {
  const int previous_threads = thread_count();
  set_thread_count(static_cast<int>(state.range(0)));
  SheetSpec spec;
  spec.columns = spec.rows = 48;
  const SheetScene scene = build_sheet(spec);
  ClothModelOptions options;
  options.bend_model = BendModel::hinges;
  const ClothModel model = build_cloth_model(scene.input, fabric_preset("cotton"), options);
  time_crumpled_assembly(state, model, scene);
  set_thread_count(previous_threads);
}
BENCHMARK(BM_AssembleHingesForcesJacobian)
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// What each bending model costs a 48x48 sheet (2,401 vertices) per assembly of the solve's
// forces, matrix and product, and how many matrix entries its pattern holds (the PCG's product
// and its IC(0) factor scale with them); arg: 0 hinges, 1 quadratic on a flat rest, 2 quadratic
// on a curved rest (the sheet rolled into a cylinder of radius 0.3 m, so every vertex bend has a
// rest curvature and its N(x) term). One thread; the same crumple as above.
void BM_BendingAssembly(benchmark::State& state) {
  const int previous_threads = thread_count();
  set_thread_count(1);
  SheetSpec spec;
  spec.columns = spec.rows = 48;
  SheetScene scene = build_sheet(spec);
  if (state.range(0) == 2) {
    for (Eigen::Index i = 0; i < scene.input.rest_positions.rows(); ++i) {
      const double angle = scene.input.rest_positions(i, 0) / 0.3;
      scene.input.rest_positions(i, 0) = 0.3 * std::sin(angle);
      scene.input.rest_positions(i, 2) = 0.3 * (1.0 - std::cos(angle));
    }
  }
  ClothModelOptions options;
  options.bend_model = state.range(0) == 0 ? BendModel::hinges : BendModel::quadratic;
  const ClothModel model = build_cloth_model(scene.input, fabric_preset("cotton"), options);
  const Eigen::Index entries = time_crumpled_assembly(state, model, scene);
  state.counters["nnz_per_vertex"] =
      static_cast<double>(entries) / static_cast<double>(model.vertex_count);
  set_thread_count(previous_threads);
}
BENCHMARK(BM_BendingAssembly)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);

// Cost of one PCG iteration per vertex (SpMV, filter, block-Jacobi, three vector updates), on
// the 64x64 system; compare with BM_StreamCopy's bandwidth (see docs/benchmarks.md).
void BM_PcgIterationPerVertex64(benchmark::State& state) {
  const Sheet s = sheet(64);
  Eigen::VectorXd x = flatten_positions(s.scene.input.rest_positions);
  x += 1e-3 * Eigen::VectorXd::Random(x.size());
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(x.size());
  SparseMatrixR a = s.model.pattern.zero_matrix;
  for (int i = 0; i < s.model.vertex_count; ++i)
    for (int k = 0; k < 3; ++k)
      a.valuePtr()[block_value_index(a, i, s.model.pattern.diagonal_offsets[i], k, k)] =
          s.model.mass[i];
  JacobianTarget target;
  target.matrix = &a;
  const double h = 1.0 / 24;
  target.dfdx_scale = -h * h;
  target.dfdv_scale = -h;
  Eigen::VectorXd force;
  evaluate_forces(s.model, ForceSettings{}, x, v, force, nullptr, &target);
  const Eigen::VectorXd b = h * force;
  ConstraintFilter filter(s.model.vertex_count);
  for (int p : s.scene.pinned_vertices) filter.pin(p, Eigen::Vector3d::Zero());
  const Eigen::VectorXd z = Eigen::VectorXd::Zero(b.size());
  PcgSolver pcg;
  Eigen::VectorXd step;
  long iterations = 0;
  for (auto _ : state) {
    const LinearSolveStats stats =
        pcg.solve(a, s.model.pattern.diagonal_offsets, filter, b, z, step, 1e-30, 50);
    iterations += stats.iterations;
    benchmark::DoNotOptimize(step.data());
  }
  state.counters["ns_per_iteration_vertex"] =
      benchmark::Counter(static_cast<double>(iterations) * s.model.vertex_count * 1e-9,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  // Bytes the SpMV must stream at least: values + column indices + row pointers + x + y.
  const double bytes = 12.0 * a.nonZeros() + 4.0 * a.rows() + 16.0 * a.rows();
  state.counters["spmv_bytes_per_vertex"] = bytes / s.model.vertex_count;
  state.counters["nnz_per_vertex"] = static_cast<double>(a.nonZeros()) / s.model.vertex_count;
}
BENCHMARK(BM_PcgIterationPerVertex64)->Unit(benchmark::kMillisecond);

// Memory bandwidth, STREAM-like copy of 2 × 64 MB (bytes_per_second counts read + write).
void BM_StreamCopy(benchmark::State& state) {
  const std::size_t n = 8u << 20;  // doubles per array
  std::vector<double> a(n, 1.0), b(n, 0.0);
  for (auto _ : state) {
    std::memcpy(b.data(), a.data(), n * sizeof(double));
    benchmark::DoNotOptimize(b.data());
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * 2 * n * sizeof(double));
}
BENCHMARK(BM_StreamCopy)->Unit(benchmark::kMillisecond);

}  // namespace
