#include "garment/panel_surface.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "garment/body.hpp"
#include "garment/body_clearance.hpp"
#include "garment/body_surface.hpp"
#include "garment/garment_mesh.hpp"
#include "garment/quality_gate.hpp"
#include "garment/sketch_inputs.hpp"
#include "garment/surface_relaxation.hpp"
#include "meshing/slice_dent.hpp"
#include "scene/sketch_file.hpp"
#include "tests/garment/quad_grids.hpp"
#include "tests/garment/test_helpers.hpp"

namespace sd::garment {
// The tests read sketch files through the scene layer.
using scene::load_sketch;
using scene::Sketch;

namespace {

TEST(PanelSurface, HarmonicSpanReproducesALinearBoundary) {
  // Boundary on the plane z = 0.3 x − 0.2 y: the uniform Laplacian of a regular grid is exact
  // for linear functions, so every interior vertex lands on the plane.
  const int n = 12;
  meshing::QuadMesh mesh = test::plane_grid(n);
  const std::vector<char> fixed = test::grid_boundary(n);
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
    mesh.vertices(v, 2) = fixed[static_cast<size_t>(v)]
                              ? 0.3 * mesh.vertices(v, 0) - 0.2 * mesh.vertices(v, 1)
                              : 5.0;  // far off: the span must not depend on the start
  span_harmonic(mesh, fixed);
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
    EXPECT_NEAR(mesh.vertices(v, 2), 0.3 * mesh.vertices(v, 0) - 0.2 * mesh.vertices(v, 1), 1e-9);
}

// The membrane with each vertex weighted in its neighbours' means by mean_weights: k rhombi of
// one size around a vertex of valence k (test::rhombus_tiling) are its solution, where the
// uniform membrane pulls the ring round a vertex of valence 3 in (spoke midpoints at 0.73 of
// their place) and pushes the ring round one of valence 5 out: the small and large quads round
// irregular vertices of the capes' and skirts' free panels (issue 18, twelfth round). No
// obstacle: only the weights are tested.
double membrane_off_rhombus_tiling(int k, bool weighted) {
  auto [mesh, fixed] = test::rhombus_tiling(k);
  const meshing::QuadMesh tiling = mesh;
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
    if (!fixed[static_cast<size_t>(v)]) mesh.vertices(v, 2) = 5.0;  // the start does not matter
  const std::vector<double> weights =
      weighted ? mean_weights(mesh, fixed, true) : std::vector<double>{};
  const PushOut nothing = [](const Eigen::Vector3d&) -> std::optional<Eigen::Vector3d> {
    return std::nullopt;
  };
  span_over_obstacle(mesh, fixed, nothing, 30, weights);
  return (mesh.vertices - tiling.vertices).cwiseAbs().maxCoeff();
}

TEST(PanelSurface, WeightedMembraneKeepsQuadsRoundIrregularVerticesAtOneSize) {
  // An LU solve of a system of at most 31 unknowns: exact to rounding.
  EXPECT_LT(membrane_off_rhombus_tiling(3, true), 1e-9);
  EXPECT_LT(membrane_off_rhombus_tiling(5, true), 1e-9);
  // Uniform weights leave the tiling by a quarter of a quad's side at valence 3 (0.27: the spoke
  // midpoints at 0.73) and by 0.18 at valence 5 (as the smoothing along the body measured).
  EXPECT_GT(membrane_off_rhombus_tiling(3, false), 0.2);
  EXPECT_GT(membrane_off_rhombus_tiling(5, false), 0.1);
}

TEST(PanelSurface, ClothBetweenVerticesIsLiftedOutOfTheObstacle) {
  // A 3 × 3 grid of unit quads at z = 0 over a ball of radius 1.05 centred 1 below the middle
  // quad's centre: its top pokes 0.05 through the middle of that quad, while every vertex stays
  // outside (the inner ones are sqrt(1.5) = 1.22 from the centre). The vertices alone would leave
  // the membrane flat, through the ball. The middle quad's deepest sample is its centre, whose
  // push is (0, 0, 0.05): its four corners (the free ones) move up by exactly that, and then no
  // sample of any quad is inside.
  const int n = 3;
  const double r = 1.05;
  const Eigen::Vector3d centre(1.5, 1.5, -1.0);
  meshing::QuadMesh mesh = test::plane_grid(n);
  const std::vector<char> fixed = test::grid_boundary(n);
  const PushOut push_out = [&](const Eigen::Vector3d& p) -> std::optional<Eigen::Vector3d> {
    const Eigen::Vector3d d = p - centre;
    if (d.norm() >= r) return std::nullopt;
    return centre + r * d.normalized();
  };
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
    ASSERT_FALSE(push_out(mesh.vertices.row(v).transpose())) << v;
  span_over_obstacle(mesh, fixed, push_out);
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v) {
    const double x = mesh.vertices(v, 0), y = mesh.vertices(v, 1);
    const auto near = [](double a, double b) { return std::abs(a - b) < 1e-9; };
    const bool inner = (near(x, 1) || near(x, 2)) && (near(y, 1) || near(y, 2));
    EXPECT_NEAR(mesh.vertices(v, 2), inner ? 0.05 : 0.0, 1e-12) << x << " " << y;
  }
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f)
    for (const Eigen::Vector3d& x : quad_samples(mesh, f))
      EXPECT_GE((x - centre).norm(), r - 1e-12) << f;
}

TEST(PanelSurface, ObstacleOnlyPushesOut) {
  // A flat membrane (z = 0, 12 × 12 units) over a ball of radius 3 whose top pokes 1.5 through
  // it: no vertex ends inside the ball, and far from the ball the membrane keeps z >= 0 (it is
  // lifted by the tent, never pulled below its boundary's plane). The vertices first pushed onto
  // the ball are lifted off it where the unit quads between them sag into it (their centres 0.085
  // deep on a ball of radius 3), so the top is at 1.5 or above.
  const int n = 12;
  const double r = 3.0;
  const Eigen::Vector3d centre(6.0, 6.0, -1.5);
  meshing::QuadMesh mesh = test::plane_grid(n);
  const std::vector<char> fixed = test::grid_boundary(n);
  const PushOut push_out = [&](const Eigen::Vector3d& p) -> std::optional<Eigen::Vector3d> {
    const Eigen::Vector3d d = p - centre;
    if (d.norm() >= r) return std::nullopt;
    return centre + r * d.normalized();
  };
  const SpannedSurface result = span_over_obstacle(mesh, fixed, push_out);
  EXPECT_GT(result.contacts, 0);
  EXPECT_TRUE(result.settled);
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v) {
    const Eigen::Vector3d p = mesh.vertices.row(v).transpose();
    EXPECT_GE((p - centre).norm(), r - 1e-9);
    EXPECT_GE(p.z(), -1e-12);
  }
  double deepest = 0;
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f)
    for (const Eigen::Vector3d& x : quad_samples(mesh, f))
      deepest = std::max(deepest, r - (x - centre).norm());
  // With its vertices alone on the ball, a unit quad's centre sags R − sqrt(R² − 1/2) = 0.085
  // into it; each vertex is lifted once (a quad beside a vertex lifted already can keep part of
  // its sag: 0.026 here), so the deepest sample is well under that.
  EXPECT_LT(deepest, 0.5 * (r - std::sqrt(r * r - 0.5)));
  EXPECT_GE(mesh.vertices(6 * (n + 1) + 6, 2), 1.5 - 1e-9);
}

TEST(PanelSurface, MembraneSpansAGapWithoutSinkingIntoIt) {
  // Two "legs" (balls) under a membrane with a gap between them: the vertices over the gap
  // stay above the straight line between the legs' tops instead of following the gap down.
  const int n = 16;
  const double r = 2.0;
  const Eigen::Vector3d left(4.0, 8.0, -1.0), right(12.0, 8.0, -1.0);
  meshing::QuadMesh mesh = test::plane_grid(n);
  const std::vector<char> fixed = test::grid_boundary(n);
  const PushOut push_out = [&](const Eigen::Vector3d& p) -> std::optional<Eigen::Vector3d> {
    for (const Eigen::Vector3d& c : {left, right})
      if ((p - c).norm() < r) return c + r * (p - c).normalized();
    return std::nullopt;
  };
  span_over_obstacle(mesh, fixed, push_out);
  // Between the balls (x = 8) the membrane is lifted by both tents: above its plane.
  EXPECT_GT(mesh.vertices(8 * (n + 1) + 8, 2), 0.0);
}

// The obstacle problem with contacts let go: a flat membrane (16 x 16 units, z = 0) over a ball
// of radius 3 whose top pokes 1.5 through it. Pushed along the membrane's normals (+z here), and
// with `release`, the membrane ends touching the ball only where the ball holds it up: no vertex
// inside the ball, every held one with its neighbours' mean inside (it would lift off otherwise),
// the top held exactly, and fewer contacts than the pushes without release leave (which keep
// every vertex once pushed, down the ball's flanks where the membrane leaves it).
TEST(PanelSurface, ReleasedContactsAreOnlyWhereTheObstacleHoldsTheMembrane) {
  const int n = 16;
  const double r = 3.0;
  const Eigen::Vector3d centre(8.0, 8.0, -1.5);
  const auto inside = [&](const Eigen::Vector3d& p) { return (p - centre).norm() < r; };
  const PushAlong push_along =
      [&](const Eigen::Vector3d& p,
          const Eigen::Vector3d& normal) -> std::optional<Eigen::Vector3d> {
    if (!inside(p)) return std::nullopt;
    // Where the ray p + t normal leaves the ball (t > 0): |p + t n - c| = r.
    const Eigen::Vector3d d = p - centre;
    const double b = d.dot(normal);
    return Eigen::Vector3d(p + (-b + std::sqrt(b * b - d.squaredNorm() + r * r)) * normal);
  };
  const std::vector<char> fixed = test::grid_boundary(n);
  meshing::QuadMesh kept = test::plane_grid(n);
  meshing::QuadMesh released = kept;
  const SpannedSurface without = span_over_obstacle(kept, fixed, push_along, false);
  const SpannedSurface with = span_over_obstacle(released, fixed, push_along, true);
  EXPECT_TRUE(with.settled);

  const meshing::QuadMesh grid = test::plane_grid(n);  // the vertices' grid places
  const auto on_ball = [&](const meshing::QuadMesh& m, Eigen::Index v) {
    return std::abs((m.vertices.row(v).transpose() - centre).norm() - r) < 1e-9;
  };
  int held_with = 0, held_without = 0;
  for (Eigen::Index v = 0; v < released.vertex_count(); ++v) {
    const Eigen::Vector3d p = released.vertices.row(v).transpose();
    EXPECT_GE((p - centre).norm(), r - 1e-9) << "vertex " << v << " inside the ball";
    held_without += on_ball(kept, v) ? 1 : 0;
    if (!on_ball(released, v)) continue;
    ++held_with;
    // Its neighbours pull it into the ball: the membrane rests on the ball there. (On a regular
    // grid a vertex's two edge neighbours per direction: the mean of the four.)
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    int count = 0;
    for (Eigen::Index u = 0; u < released.vertex_count(); ++u)
      if ((grid.vertices.row(u) - grid.vertices.row(v)).cwiseAbs().sum() == 1.0) {
        mean += released.vertices.row(u).transpose();
        ++count;
      }
    ASSERT_EQ(count, 4);
    EXPECT_TRUE(inside(mean / count)) << "vertex " << v << " is held but would lift off";
  }
  EXPECT_NEAR(released.vertices(8 * (n + 1) + 8, 2), 1.5, 1e-9);  // the top
  EXPECT_GT(held_with, 0);
  EXPECT_LT(held_with, held_without);
  EXPECT_GE(without.contacts, held_without);
}

const BodySurface& builtin_surface() {
  static const Body body = load_body("builtin");
  static const BodySurface surface(body.mesh);
  return surface;
}

TEST(PanelSurface, AutoFitLaysTheTshirtOnTheBodyAndSpansTheSkirt) {
  const Garment tshirt =
      build_garment(load_sketch(std::filesystem::path(SD_SOURCE_DIR) / "data/examples/tshirt.json"),
                    builtin_surface());
  for (const GarmentPanel& p : tshirt.panels) EXPECT_EQ(p.fit, "body") << p.id;
  const Garment skirt = build_garment(
      load_sketch(std::filesystem::path(SD_SOURCE_DIR) / "data/examples/a-line-skirt.json"),
      builtin_surface());
  for (const GarmentPanel& p : skirt.panels)
    EXPECT_EQ(p.fit, p.id.starts_with("skirt") ? "free" : "body") << p.id;
}

TEST(PanelSurface, FitBodyKeepsTheSkirtOnTheLegs) {
  // The same skirt with "fit": "body" on every panel is pulled into the hollow between the
  // legs: its designed shape dents deeper than the spanned one.
  const Sketch spanned =
      load_sketch(std::filesystem::path(SD_SOURCE_DIR) / "data/examples/a-line-skirt.json");
  Sketch glued = spanned;
  for (PanelSpec& p : glued.panels) p.fit = PanelFit::kBody;
  const auto dent = [](const Garment& g) {
    meshing::TriMesh tris;
    tris.vertices = g.mesh.vertices;
    tris.faces.resize(2 * g.mesh.face_count(), 3);
    for (Eigen::Index f = 0; f < g.mesh.face_count(); ++f) {
      tris.faces.row(2 * f) << g.mesh.faces(f, 0), g.mesh.faces(f, 1), g.mesh.faces(f, 2);
      tris.faces.row(2 * f + 1) << g.mesh.faces(f, 0), g.mesh.faces(f, 2), g.mesh.faces(f, 3);
    }
    return meshing::slice_dent(tris).depth;
  };
  const double free_dent = dent(build_garment(spanned, builtin_surface()));
  const double body_dent = dent(build_garment(glued, builtin_surface()));
  EXPECT_LT(free_dent, 0.02);
  EXPECT_GT(body_dent, free_dent + 0.01);
}

}  // namespace
}  // namespace sd::garment

namespace sd::garment {
namespace {

// A new user's wide shorts (data/designs/repro/wide-shorts.json): the free front legs lay 6.3 mm
// inside the inner thighs between vertices that were all outside, and the gate said nothing.
// Now no sample of any panel is inside the body, and the gate has no inside_body warning.
TEST(PanelSurface, TheWideShortsLegsAreOutOfTheThighs) {
  const scene::Sketch sketch = scene::load_sketch(std::filesystem::path(SD_SOURCE_DIR) /
                                                  "data/designs/repro/wide-shorts.json");
  const Body body = load_sketch_body(sketch);
  const BodySurface surface(body.mesh);
  const Garment g = build_garment(sketch, surface);
  for (const PanelInsideBody& p : find_panels_inside_body(g, surface, 0.0))
    ADD_FAILURE() << g.panels[static_cast<size_t>(p.panel)].id << ": " << p.quads << " quads, "
                  << 1e3 * p.deepest << " mm deep";
  for (const QualityWarning& w : check_quality_tried(g, sketch, body.mesh, nullptr))
    EXPECT_NE(w.kind, "inside_body") << w.message;
}

}  // namespace
}  // namespace sd::garment
