// Fill consistency in a garment (issue 18): over a sweep of edge_length, every panel of the
// examples and the design corpus gets fewer quads as its edges get longer, and the quads follow
// the edge length (mean side within 0.5-2 edge lengths). Before the filler passed over plans with
// too few quads for the panel's area, the raglan sleeve of the issue went 238 → 304 → 81 quads
// at 2, 2.5 and 3.5 cm, and a sleeve of sides (27, 5, 14, 14, 4) had 34 quads of ~22 cm² where
// 6 cm² was asked for.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "garment/body.hpp"
#include "garment/body_surface.hpp"
#include "garment/garment_mesh.hpp"
#include "garment/sketch_inputs.hpp"
#include "scene/sketch_file.hpp"
#include "tests/garment/test_helpers.hpp"

namespace sd::garment {
// The tests read sketch files through the scene layer.
using scene::load_sketch;
using scene::Sketch;

namespace {

namespace fs = std::filesystem;

// Edge lengths of the sweep, m (the examples and designs use 2-3 cm).
constexpr std::array<double, 4> kSweep = {0.02, 0.025, 0.03, 0.035};
// A quad's mean side outside [kSmallest, kLargest] edge lengths is out of the band; a garment
// may have at most kOutsideShare of its quads there (tapering panels, a godet's apex, need
// small quads; see the test's comment on what is left).
constexpr double kSmallest = 0.5, kLargest = 2.0, kOutsideShare = 0.04;
// Over every example and design at the four edge lengths together: the quads outside the band as
// measured on 27 November 2026 (docs/garment.md, "Which plans and which vertices": 578 of about
// 170,000, then 712 with the four designs added that day: wide-leg trousers, hip cape, capelet on
// the Collada human, tiered skirt), and of them the large quads at an interior vertex of valence 5
// or more (73, then 99). Issue 18's ninth round (docs/garment.md, "Fill consistency, ninth
// round") weighted those vertices in the smoothing along the body (99 → 67) and let a plan have as
// many quads as the counts-only plan, which made the hip cape's back monotone but gives the
// tapering capes more small quads at their necks (712 → 740: small 493 → 553, large 219 → 187),
// for 79 → 66 gate warnings and 10 → 6 folded quads over the same sweep. The yoke flared skirt,
// added with that round after its sweep, brings 5,550 quads and (by difference) 36 outside (740 →
// 776, measured when the round landed: 776 of 203,020; 712 of 196,233 without the round and the
// skirt). The tenth round's plan-rank rule and the eleventh's holding back of the valence 5+
// weights (the arms-lowering t-shirt's drape: docs/garment.md, "Fill consistency, eleventh
// round") leave 794 of 202,850 (99 large at valence 5+ again). Bounds that only hold what is
// reached: a change of the filler or of the smoothing that adds out-of-band quads fails here, one
// that removes some lowers them. The twelfth round's valence weights in a free panel's membrane
// over the body (span_over_obstacle: 0 at valence 3, 1 + 2 cos(2π/k) at k ≥ 5) reach 471 of
// 202,850 and 75 (gate warnings 87 → 85), but are held back (kSpanWeighted in
// garment/panel_fill.cpp: the capelet on the Collada human's drape; docs/garment.md, "Fill
// consistency, twelfth round"): with them on, these bounds become 471 and 75.
constexpr int kMostOutside = 794, kMostLargeAtValence5 = 99;

std::vector<fs::path> garment_files() {
  std::vector<fs::path> files = test::example_files();
  for (const auto& entry : fs::directory_iterator(fs::path(SD_SOURCE_DIR) / "data/designs"))
    if (entry.path().extension() == ".json") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

// Each vertex of panel `panel`'s quads: "boundary" (on an edge of one of its quads: the panel's
// outline, seams included), else by its valence among them, "interior valence 3", "interior
// valence 5+" or "regular"; vertices of other panels are "".
std::vector<std::string> vertex_kinds(const Garment& garment, int panel) {
  const meshing::QuadMesh& mesh = garment.mesh;
  std::map<std::pair<int, int>, int> uses;
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f)
    if (garment.face_panel(f) == panel)
      for (int k = 0; k < 4; ++k) ++uses[std::minmax(mesh.faces(f, k), mesh.faces(f, (k + 1) % 4))];
  std::vector<int> valence(static_cast<size_t>(mesh.vertex_count()), 0);
  std::vector<char> boundary(valence.size(), 0);
  for (const auto& [edge, count] : uses)
    for (const int v : {edge.first, edge.second}) {
      ++valence[static_cast<size_t>(v)];
      if (count == 1) boundary[static_cast<size_t>(v)] = 1;
    }
  std::vector<std::string> kinds(valence.size());
  for (size_t v = 0; v < kinds.size(); ++v)
    if (boundary[v])
      kinds[v] = "boundary";
    else if (valence[v] == 3)
      kinds[v] = "interior valence 3";
    else if (valence[v] >= 5)
      kinds[v] = "interior valence 5+";
    else if (valence[v] == 4)
      kinds[v] = "regular";
  return kinds;
}

TEST(FillConsistency, QuadCountsFallAndSizesFollowTheEdgeLength) {
  int garments = 0, total_quads = 0, total_outside = 0;
  std::map<std::string, int> causes, plans;  // out-of-band quads by where they are, by plan
  double worst_share = 0;
  std::string worst;
  for (const fs::path& file : garment_files()) {
    Sketch sketch = load_sketch(file);
    if (sketch.body.mesh != "builtin" && !fs::exists(sketch.resolve(sketch.body.mesh)))
      continue;  // the design's body is not installed
    const Body body = load_sketch_body(sketch);
    const BodySurface surface(body.mesh);
    // One edge length for the whole garment: the sweep's.
    for (PanelSpec& panel : sketch.panels) panel.edge_length.reset();
    for (CurveSpec& curve : sketch.curves) curve.edge_length.reset();
    std::map<std::string, int> previous;
    for (const double edge : kSweep) {
      sketch.edge_length = edge;
      const Garment garment = build_garment(sketch, surface);
      std::map<int, std::vector<std::string>> kinds;  // by panel, when first needed
      int outside = 0;
      for (Eigen::Index f = 0; f < garment.mesh.face_count(); ++f) {
        const double side = meshing::mean_side(garment.mesh, f) / edge;
        if (side >= kSmallest && side <= kLargest) continue;
        ++outside;
        // Where it is in its panel: on the panel's boundary, at an interior vertex of valence 3,
        // of valence 5 or more, or among regular interior vertices only (the first that applies).
        const int p = garment.face_panel(f);
        if (!kinds.contains(p)) kinds[p] = vertex_kinds(garment, p);
        std::string at = "regular interior";
        for (const char* kind : {"boundary", "interior valence 3", "interior valence 5+"})
          for (int k = 0; k < 4 && at == "regular interior"; ++k)
            if (kinds[p][static_cast<size_t>(garment.mesh.faces(f, k))] == kind) at = kind;
        const GarmentPanel& panel = garment.panels[static_cast<size_t>(p)];
        ++causes[std::string(side < kSmallest ? "small" : "large") + ", " + at];
        ++plans[panel.partition];
      }
      total_quads += static_cast<int>(garment.mesh.face_count());
      total_outside += outside;
      const double share = outside / static_cast<double>(garment.mesh.face_count());
      if (share > worst_share) {
        worst_share = share;
        worst = file.stem().string() + " at " + std::to_string(edge) + " m";
      }
      EXPECT_LE(outside, kOutsideShare * static_cast<double>(garment.mesh.face_count()))
          << file.filename() << " at " << edge << " m: " << outside << " of "
          << garment.mesh.face_count() << " quads outside " << kSmallest << "-" << kLargest
          << " edge lengths";
      for (const GarmentPanel& panel : garment.panels) {
        if (panel.mirror_copy) continue;
        const auto it = previous.find(panel.id);
        if (it != previous.end()) {
          EXPECT_LE(panel.faces, it->second)
              << file.filename() << " panel '" << panel.id << "' at " << edge
              << " m has more quads (" << panel.faces << ") than at the shorter edge before ("
              << it->second << ")";
        }
        previous[panel.id] = panel.faces;
      }
    }
    ++garments;
  }
  EXPECT_GE(garments, 6);
  EXPECT_LE(total_outside, kMostOutside);
  EXPECT_LE(causes["large, interior valence 5+"], kMostLargeAtValence5);
  // The figures docs/garment.md reports ("Fill consistency").
  RecordProperty("outside_share_all",
                 std::to_string(total_outside) + " of " + std::to_string(total_quads));
  RecordProperty("outside_share_worst", std::to_string(worst_share) + " (" + worst + ")");
  std::printf(
      "quads outside %.1f-%.1f edge lengths: %d of %d over every garment and edge "
      "length; the largest share %.2f %% (%s)\n",
      kSmallest, kLargest, total_outside, total_quads, 100 * worst_share, worst.c_str());
  for (const auto& [cause, count] : causes) std::printf("  %s: %d\n", cause.c_str(), count);
  for (const auto& [plan, count] : plans) std::printf("  in %s plans: %d\n", plan.c_str(), count);
}

// A panel whose fold no plan undoes must still come out near the body: the raglan top at 2 cm
// edges refills its back sleeve from the start along its normals, and the untangling's pattern
// search there walked one vertex 6e8 m away (off the body the projection leaves a point where it
// is, and a vertex's step grows with its edges), which the fill kept for having fewer folded
// quads. Untangling now moves no vertex more than 10 mean edge lengths.
TEST(FillConsistency, NoVertexRunsAwayWhereAFoldCannotBeUndone) {
  Sketch sketch = load_sketch(fs::path(SD_SOURCE_DIR) / "data/designs/raglan-top.json");
  const Body body = load_sketch_body(sketch);
  const BodySurface surface(body.mesh);
  sketch.edge_length = 0.02;
  const Garment garment = build_garment(sketch, surface);
  const Eigen::Vector3d low = surface.box().min - Eigen::Vector3d::Constant(0.1);
  const Eigen::Vector3d high = surface.box().max + Eigen::Vector3d::Constant(0.1);
  for (Eigen::Index v = 0; v < garment.mesh.vertex_count(); ++v) {
    const Eigen::Vector3d p = garment.mesh.vertices.row(v).transpose();
    ASSERT_TRUE((p.array() >= low.array()).all() && (p.array() <= high.array()).all())
        << "vertex " << v << " at " << p.transpose() << " m";
  }
  for (const GarmentPanel& panel : garment.panels)
    EXPECT_LT(panel.area, 0.5) << "panel '" << panel.id << "': " << panel.area << " m²";
}

}  // namespace
}  // namespace sd::garment
