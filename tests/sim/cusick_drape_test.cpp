// The Cusick drape test (BS 5058, ISO 9073-9; Cusick 1968) reproduced by the simulator: a 30 cm
// disc of fabric clamped between two 18 cm discs drapes under its own weight into folds; the
// drape coefficient DC = (shadow − support) / (specimen − support) and the count of folds
// (nodes) are measured from its shadow (sim/drape_coefficient). docs/fabrics.md, "Cusick drape".
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "sim/drape_coefficient.hpp"
#include "sim/fabric.hpp"
#include "sim/sheet.hpp"
#include "sim/static_equilibrium.hpp"
#include "tests/sim/test_scenes.hpp"

namespace sd::sim {
namespace {

struct CusickRun {
  DrapeShadow shadow;
  bool converged = false;
  double seconds = 0.0;
  int vertices = 0;
};

// The quadratic bending, linear compression, static: the equilibrium reached as gravity grows
// from the flat disc, lifted by a random 0.1 mm so that the symmetric state is left (16 load
// steps). docs/fabrics.md compares it with dynamic drapes.
CusickRun drape(const FabricParameters& fabric, int cells, unsigned seed = 1) {
  const auto start = std::chrono::steady_clock::now();
  const SheetScene scene = testing::cusick_disc(cells);
  const ClothModel model = build_cloth_model(scene.input, fabric);
  Eigen::VectorXd x = flatten_positions(scene.input.rest_positions);
  std::vector<char> pinned(static_cast<size_t>(model.vertex_count), 0);
  for (int v : scene.pinned_vertices) pinned[static_cast<size_t>(v)] = 1;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> lift(0.0, 1e-4);
  for (int v = 0; v < model.vertex_count; ++v)
    if (!pinned[static_cast<size_t>(v)]) x(3 * v + 1) += lift(rng);
  CusickRun run;
  run.vertices = model.vertex_count;
  {
    StaticOptions static_options;
    static_options.load_steps = 16;
    const StaticResult result = solve_static(model, x, scene.pinned_vertices, static_options);
    run.converged = result.converged;
  }
  Eigen::MatrixX3d positions(model.vertex_count, 3);
  for (int v = 0; v < model.vertex_count; ++v) positions.row(v) = x.segment<3>(3 * v).transpose();
  run.shadow = measure_drape_shadow(positions, scene.input.triangles, {0.0, 1.0, 0.0},
                                    Eigen::Vector3d::UnitY());
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return run;
}

// Cotton and denim at 1.5 cm cells, static: the drape coefficient lies in the published range
// (cotton 0.5-0.7, denim 0.7-0.9; docs/fabrics.md gives the sources) with 4-10 nodes.
// Measured: cotton 0.644 with 5 nodes, denim 0.857 with 4 (0.612 and 0.856 at 1 cm cells). The
// other presets are not asserted: silk's static solve does not converge and jersey, wool and
// polyester move by more than 0.03 from 1.5 to 1 cm cells (docs/fabrics.md, "Cusick drape").
TEST(CusickDrape, CottonAndDenimDrapeWithinTheirPublishedRanges) {
  struct Case {
    std::string name;
    double low, high;
  };
  for (const Case& c : {Case{"cotton", 0.5, 0.7}, Case{"denim", 0.7, 0.9}}) {
    const CusickRun run = drape(fabric_preset(c.name), 20);
    std::printf("Cusick %s, 20 cells (%d vertices): DC %.3f, %d nodes, %.1f s\n", c.name.c_str(),
                run.vertices, run.shadow.drape_coefficient, run.shadow.nodes, run.seconds);
    EXPECT_TRUE(run.converged) << c.name;
    EXPECT_GE(run.shadow.drape_coefficient, c.low) << c.name;
    EXPECT_LE(run.shadow.drape_coefficient, c.high) << c.name;
    EXPECT_GE(run.shadow.nodes, 4) << c.name;
    EXPECT_LE(run.shadow.nodes, 10) << c.name;
  }
}

}  // namespace
}  // namespace sd::sim
