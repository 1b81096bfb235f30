#include "garment/garment_mesh.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <filesystem>
#include <initializer_list>
#include <map>
#include <set>
#include <string>

#include "garment/body.hpp"
#include "garment/material_frames.hpp"
#include "garment/quality_gate.hpp"
#include "garment/sketch_inputs.hpp"
#include "meshing/quad_mesh.hpp"
#include "scene/sketch_file.hpp"
#include "tests/garment/test_helpers.hpp"

namespace sd::garment {
// The tests read sketch files through the scene layer.
using scene::load_sketch;
using scene::parse_sketch;
using scene::Sketch;

namespace {

const BodySurface& builtin_surface() {
  static const Body body = load_body("builtin");
  static const BodySurface surface(body.mesh);
  return surface;
}

// The sub-mesh of one panel, re-indexed.
meshing::QuadMesh panel_mesh(const Garment& g, int panel) {
  std::map<int, int> index;
  std::vector<Eigen::RowVector4i> faces;
  for (Eigen::Index f = 0; f < g.mesh.face_count(); ++f) {
    if (g.face_panel(f) != panel) continue;
    Eigen::RowVector4i q;
    for (int k = 0; k < 4; ++k) {
      const int v = g.mesh.faces(f, k);
      auto [it, inserted] = index.try_emplace(v, static_cast<int>(index.size()));
      q(k) = it->second;
    }
    faces.push_back(q);
  }
  meshing::QuadMesh m;
  m.vertices.resize(static_cast<Eigen::Index>(index.size()), 3);
  for (const auto& [v, i] : index) m.vertices.row(i) = g.mesh.vertices.row(v);
  m.faces.resize(static_cast<Eigen::Index>(faces.size()), 4);
  for (size_t f = 0; f < faces.size(); ++f) m.faces.row(static_cast<Eigen::Index>(f)) = faces[f];
  return m;
}

class ExampleGarment : public ::testing::TestWithParam<std::filesystem::path> {};

TEST_P(ExampleGarment, IsOneStitchedConformingMesh) {
  const Sketch sketch = load_sketch(GetParam());
  const Garment g = build_garment(sketch, builtin_surface());
  ASSERT_GT(g.mesh.face_count(), 100);
  ASSERT_EQ(g.face_panel.size(), g.mesh.face_count());

  // The garment passes every quad-mesh check except "one boundary loop" (a shirt has several).
  for (const std::string& p : meshing::validate(g.mesh).problems)
    EXPECT_NE(p.find("boundary"), std::string::npos) << GetParam() << ": " << p;

  // Every edge has one or two faces, and two faces traverse it in opposite directions.
  std::map<std::pair<int, int>, std::vector<int>> directed;
  for (Eigen::Index f = 0; f < g.mesh.face_count(); ++f)
    for (int k = 0; k < 4; ++k)
      directed[{g.mesh.faces(f, k), g.mesh.faces(f, (k + 1) % 4)}].push_back(static_cast<int>(f));
  int seams = 0;
  for (const auto& [edge, faces] : directed) {
    EXPECT_EQ(faces.size(), 1u) << "edge traversed twice the same way";
    const auto twin = directed.find({edge.second, edge.first});
    if (twin != directed.end() && edge.first < edge.second &&
        g.face_panel(faces[0]) != g.face_panel(twin->second[0]))
      ++seams;
  }
  EXPECT_EQ(seams, g.seam_edges);
  EXPECT_GT(seams, 0);

  // No duplicated seam vertices: no two vertices at the same place.
  std::vector<std::array<double, 3>> sorted;
  for (Eigen::Index v = 0; v < g.mesh.vertex_count(); ++v)
    sorted.push_back({g.mesh.vertices(v, 0), g.mesh.vertices(v, 1), g.mesh.vertices(v, 2)});
  std::sort(sorted.begin(), sorted.end());
  for (size_t k = 1; k < sorted.size(); ++k) {
    const Eigen::Vector3d a(sorted[k - 1].data()), b(sorted[k].data());
    EXPECT_GT((a - b).norm(), 1e-7) << "duplicate vertex at " << a.transpose();
  }

  // Each panel on its own is a valid disk, and its figures add up.
  int distortion = 0;
  for (size_t p = 0; p < g.panels.size(); ++p) {
    const meshing::MeshCheck check = meshing::validate(panel_mesh(g, static_cast<int>(p)));
    EXPECT_TRUE(check.ok()) << g.panels[p].id << ": " << (check.ok() ? "" : check.problems.front());
    EXPECT_GE(g.panels[p].side_counts.size(), 3u);
    EXPECT_FALSE(g.panels[p].body_part.empty());
    distortion += g.panels[p].distortion;
  }
  EXPECT_GE(distortion, 0);

  // Every example is mirrored across x = 0: the vertex set is symmetric.
  std::set<std::array<long long, 3>> keys;
  auto key = [](double x, double y, double z) {
    return std::array<long long, 3>{std::llround(x * 1e7), std::llround(y * 1e7),
                                    std::llround(z * 1e7)};
  };
  for (Eigen::Index v = 0; v < g.mesh.vertex_count(); ++v)
    keys.insert(key(g.mesh.vertices(v, 0), g.mesh.vertices(v, 1), g.mesh.vertices(v, 2)));
  int asymmetric = 0;
  for (Eigen::Index v = 0; v < g.mesh.vertex_count(); ++v)
    asymmetric +=
        keys.contains(key(-g.mesh.vertices(v, 0), g.mesh.vertices(v, 1), g.mesh.vertices(v, 2)))
            ? 0
            : 1;
  EXPECT_EQ(asymmetric, 0);

  // The outside of the garment faces away from the body: most face normals point away from the
  // nearest body point.
  int outward = 0;
  for (Eigen::Index f = 0; f < g.mesh.face_count(); ++f) {
    const Eigen::Vector3d a = g.mesh.vertices.row(g.mesh.faces(f, 0)),
                          b = g.mesh.vertices.row(g.mesh.faces(f, 1)),
                          c = g.mesh.vertices.row(g.mesh.faces(f, 2)),
                          d = g.mesh.vertices.row(g.mesh.faces(f, 3));
    const Eigen::Vector3d centre = (a + b + c + d) / 4, n = (c - a).cross(d - b);
    outward += n.dot(builtin_surface().closest_point(centre).normal) > 0 ? 1 : 0;
  }
  EXPECT_GT(outward, 0.95 * static_cast<double>(g.mesh.face_count()));
}

TEST_P(ExampleGarment, MaterialFramesAndRestShape) {
  const Garment g = build_garment(load_sketch(GetParam()), builtin_surface());
  const MaterialFrames frames = material_frames(g.mesh);
  for (Eigen::Index f = 0; f < g.mesh.face_count(); ++f) {
    const Eigen::Vector3d w = frames.warp.row(f), t = frames.weft.row(f), n = frames.normal.row(f);
    EXPECT_NEAR(w.norm(), 1, 1e-12);
    EXPECT_NEAR(w.dot(t), 0, 1e-12);
    EXPECT_NEAR(w.dot(n), 0, 1e-12);
    // Warp is the in-face direction closest to +Y: no unit tangent has a larger y.
    EXPECT_NEAR(w.y(), std::sqrt(std::max(0.0, 1 - n.y() * n.y())), 1e-9);
  }
  meshing::TriMesh tris;
  tris.vertices = g.mesh.vertices;
  tris.faces.resize(2 * g.mesh.face_count(), 3);
  Eigen::VectorXi tri_quad(2 * g.mesh.face_count());
  for (Eigen::Index f = 0; f < g.mesh.face_count(); ++f) {
    tris.faces.row(2 * f) << g.mesh.faces(f, 0), g.mesh.faces(f, 1), g.mesh.faces(f, 2);
    tris.faces.row(2 * f + 1) << g.mesh.faces(f, 0), g.mesh.faces(f, 2), g.mesh.faces(f, 3);
    tri_quad(2 * f) = tri_quad(2 * f + 1) = static_cast<int>(f);
  }
  const Eigen::VectorXd ease = Eigen::VectorXd::Constant(g.mesh.face_count(), 1.1);
  const Eigen::MatrixXd rest = triangle_rest_coordinates(tris, tri_quad, frames, ease);
  for (Eigen::Index t = 0; t < tris.face_count(); t += 7) {
    const Eigen::Vector3d p0 = tris.vertices.row(tris.faces(t, 0)),
                          p1 = tris.vertices.row(tris.faces(t, 1)),
                          p2 = tris.vertices.row(tris.faces(t, 2));
    const Eigen::Vector2d u1(rest(t, 2), rest(t, 3)), u2(rest(t, 4), rest(t, 5));
    EXPECT_NEAR(u1.norm(), 1.1 * (p1 - p0).norm(), 1e-12);
    EXPECT_NEAR(u2.norm(), 1.1 * (p2 - p0).norm(), 1e-12);
    EXPECT_NEAR((u2 - u1).norm(), 1.1 * (p2 - p1).norm(), 1e-12);
    EXPECT_GT(u1.x() * u2.y() - u1.y() * u2.x(), 0);  // orientation kept (normal = warp × weft)
  }
}

INSTANTIATE_TEST_SUITE_P(Wardrobe, ExampleGarment, ::testing::ValuesIn(test::example_files()),
                         [](const auto& param_info) {
                           std::string name = param_info.param.stem().string();
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

TEST(Garment, ParityMakesEveryPanelEvenWithFewChanges) {
  for (const auto& file : test::example_files()) {
    const Garment g = build_garment(load_sketch(file), builtin_surface());
    for (const GarmentPanel& p : g.panels) {
      int total = 0;
      for (int c : p.side_counts) total += c;
      EXPECT_EQ(total % 2, 0) << file << " " << p.id;
      for (int c : p.side_counts) EXPECT_GE(c, 1);
    }
    EXPECT_LE(g.parity_changes, static_cast<int>(g.panels.size()));
  }
}

TEST(Garment, ExamplePanelsHaveNoCreaseOfDegenerateQuads) {
  // Where a panel wraps a strongly curved part of the body, relaxing in 3D and projecting can
  // leave a crease of long, thin quads (the t-shirt's back had a quad of aspect ratio 1,579,
  // 22 cm by 0.3 mm, and the body showed through the gap); smoothing along the surface
  // (surface_relaxation.hpp) spreads it out. Every example's worst quad now measures at most
  // 7.0 (the t-shirt's back sleeve); 10 leaves room for small changes of the filler. (The
  // shorts at 2.5 cm quads reached 9.9, and their drape failed with check_body_vertices.)
  for (const auto& file : test::example_files()) {
    const Garment g = build_garment(load_sketch(file), builtin_surface());
    for (const GarmentPanel& p : g.panels)
      EXPECT_LT(p.quality.max_aspect_ratio, 10.0) << file << " " << p.id;
  }
}

TEST(Garment, ExamplesHaveNoFoldedQuadsBeyondTheRecordedFew) {
  // Quads folded over (a corner's scaled Jacobian below zero against the mesh's own normals, as
  // the report counts them), after the garment unfolds them against the body's normals.
  // Recorded figures per example (docs/garment.md): none (the t-shirt's back kept 1 per side at
  // the underarm until the filler passed over plans with too few quads; the shorts' back kept 1
  // per side at the crotch until garment/fold_repair turned the edges there). Seam vertices folded
  // between a panel and its own mirror copy (merged away with a warning): only on the shorts'
  // centre seams, 1 with their 2 cm quads (4 before that change).
  const std::map<std::string, int> recorded = {};
  for (const auto& file : test::example_files()) {
    const Garment g = build_garment(load_sketch(file), builtin_surface());
    int inverted = 0;
    for (const GarmentPanel& p : g.panels) inverted += p.quality.inverted_quads;
    const auto it = recorded.find(file.stem().string());
    EXPECT_LE(inverted, it == recorded.end() ? 0 : it->second) << file;
    EXPECT_EQ(g.merged_doublets.size(), file.stem() == "shorts" ? 1u : 0u) << file;
    // And so every inner vertex of the stitched mesh is in at least three quads.
    std::map<int, int> quads;
    for (Eigen::Index f = 0; f < g.mesh.face_count(); ++f)
      for (int k = 0; k < 4; ++k) ++quads[g.mesh.faces(f, k)];
    std::set<int> boundary;  // vertices of edges in one quad
    std::map<std::pair<int, int>, int> edge_use;
    for (Eigen::Index f = 0; f < g.mesh.face_count(); ++f)
      for (int k = 0; k < 4; ++k) {
        const int a = g.mesh.faces(f, k), b = g.mesh.faces(f, (k + 1) % 4);
        ++edge_use[{std::min(a, b), std::max(a, b)}];
      }
    for (const auto& [edge, uses] : edge_use)
      if (uses == 1) boundary.insert({edge.first, edge.second});
    for (const auto& [v, n] : quads)
      if (!boundary.contains(v)) {
        EXPECT_GE(n, 3) << file << ": inner vertex " << v;
      }
  }
}

TEST(Garment, RaglanBackSleeveLiesOnTheBackOfTheArm) {
  // data/designs/repro/raglan-top.json: the back sleeve is half a tube from the top of the arm
  // to its underside, its interpolated interior on the plane through the arm's axis. From the
  // nearest body points its interior landed on the front of the arm (quads facing into the
  // arm, 5 folded, the back of the arm bare); filled again from the start along its own
  // normals, every quad faces away from the body and none folds or is a sliver.
  const Garment g = build_garment(
      load_sketch(std::filesystem::path(SD_SOURCE_DIR) / "data/designs/repro/raglan-top.json"),
      builtin_surface());
  for (const std::string id : {"sleeve_back", "sleeve_back.mirror"}) {
    int index = -1;
    for (size_t p = 0; p < g.panels.size(); ++p)
      if (g.panels[p].id == id) index = static_cast<int>(p);
    ASSERT_GE(index, 0) << id;
    EXPECT_EQ(g.panels[static_cast<size_t>(index)].quality.inverted_quads, 0) << id;
    EXPECT_LT(g.panels[static_cast<size_t>(index)].quality.max_aspect_ratio, 10.0) << id;
    int faces = 0, inward = 0;
    for (Eigen::Index f = 0; f < g.mesh.face_count(); ++f) {
      if (g.face_panel(f) != index) continue;
      const Eigen::Vector3d a = g.mesh.vertices.row(g.mesh.faces(f, 0)),
                            b = g.mesh.vertices.row(g.mesh.faces(f, 1)),
                            c = g.mesh.vertices.row(g.mesh.faces(f, 2)),
                            d = g.mesh.vertices.row(g.mesh.faces(f, 3));
      const Eigen::Vector3d centre = (a + b + c + d) / 4, n = (c - a).cross(d - b);
      inward += n.dot(builtin_surface().closest_point(centre).normal) < 0 ? 1 : 0;
      ++faces;
    }
    EXPECT_GT(faces, 100) << id;
    EXPECT_EQ(inward, 0) << id;
  }
}

TEST(Garment, BodyPartsOfTheTshirt) {
  const Garment g =
      build_garment(load_sketch(std::filesystem::path(SD_SOURCE_DIR) / "data/examples/tshirt.json"),
                    builtin_surface());
  std::map<std::string, std::string> part;
  for (const GarmentPanel& p : g.panels) part[p.id] = p.body_part;
  EXPECT_EQ(part["front"], "torso");
  EXPECT_EQ(part["back.mirror"], "torso");
  EXPECT_EQ(part["sleeve_front"], "left_arm");
  EXPECT_EQ(part["sleeve_back.mirror"], "right_arm");
}

TEST(Garment, ClassifyBodyPoint) {
  EXPECT_EQ(classify_body_point({0, 1.65, 0}, 1.75), BodyPart::kHead);
  EXPECT_EQ(classify_body_point({0.1, 1.2, 0.1}, 1.75), BodyPart::kTorso);
  EXPECT_EQ(classify_body_point({0.3, 1.0, 0}, 1.75), BodyPart::kLeftArm);
  EXPECT_EQ(classify_body_point({-0.3, 1.0, 0}, 1.75), BodyPart::kRightArm);
  EXPECT_EQ(classify_body_point({0.1, 0.3, 0}, 1.75), BodyPart::kLeftLeg);
  EXPECT_EQ(classify_body_point({-0.1, 0.3, 0}, 1.75), BodyPart::kRightLeg);
}

TEST(Garment, JoinRelabelsGroupsAndSeamOnSphereStitches) {
  // Two panels side by side on a sphere, sharing the middle curve, then joined.
  Sketch s = parse_sketch(R"({
    "curves": [
      { "id": "top_l", "points": [[-0.1, 1.1], [0, 1.1]] }, { "id": "top_r", "points": [[0, 1.1], [0.1, 1.1]] },
      { "id": "mid", "points": [[0, 1.1], [0, 0.9]] },
      { "id": "bot_l", "points": [[-0.1, 0.9], [0, 0.9]] }, { "id": "bot_r", "points": [[0, 0.9], [0.1, 0.9]] },
      { "id": "left", "points": [[-0.1, 0.9], [-0.1, 1.1]] }, { "id": "right", "points": [[0.1, 0.9], [0.1, 1.1]] }
    ],
    "panels": [ { "id": "l", "boundary": ["top_l", "mid", "bot_l", "left"] },
                { "id": "r", "boundary": ["top_r", "right", "bot_r", "mid"] } ],
    "join": [ { "id": "both", "panels": ["l", "r"] } ],
    "edge_length": 0.02
  })",
                          "s.json");
  const BodySurface sphere(meshing::icosphere(0.3, 5, {0, 1, 0}));
  const Garment g = build_garment(s, sphere);
  ASSERT_EQ(g.panels.size(), 2u);
  EXPECT_EQ(g.panels[0].group, "both");
  EXPECT_EQ(g.panels[1].group, "both");
  // The 20 cm stroke lies on the 0.30 m sphere and is pushed out radially by the 1 cm offset, so
  // it measures 0.2041 m × 0.31 / 0.30 = 0.211 m: 11 edges of 2 cm.
  EXPECT_EQ(g.seam_edges, 11);
  // Every vertex lies on the offset sphere (boundary by projection, interior by the filler's
  // projection callback).
  for (Eigen::Index v = 0; v < g.mesh.vertex_count(); ++v)
    EXPECT_NEAR((g.mesh.vertices.row(v).transpose() - Eigen::Vector3d(0, 1, 0)).norm(), 0.31, 2e-3);
}

TEST(Garment, ThreePanelsOnOneCurveIsAnError) {
  Sketch s = parse_sketch(R"({
    "curves": [ { "id": "a", "points": [[-0.1, 1.1], [0.1, 1.1]] },
                { "id": "b", "points": [[0.1, 1.1], [0, 0.9]] },
                { "id": "c", "points": [[0, 0.9], [-0.1, 1.1]] } ],
    "panels": [ { "id": "p", "boundary": ["a", "b", "c"] }, { "id": "q", "boundary": ["a", "b", "c"] },
                { "id": "r", "boundary": ["a", "b", "c"] } ]
  })",
                          "s.json");
  const BodySurface sphere(meshing::icosphere(0.3, 4, {0, 1, 0}));
  try {
    build_garment(s, sphere);
    FAIL();
  } catch (const SketchError& e) {
    EXPECT_EQ(e.json_path(), "/panels/2/boundary");
    EXPECT_NE(std::string(e.what()).find("already joins panels 'p' and 'q'"), std::string::npos)
        << e.what();
  }
}

TEST(Garment, TJunctionSplitsTheCurve) {
  // "mid" ends on the interior of "top" and "bottom": both are split, each panel uses a part.
  Sketch s = parse_sketch(R"({
    "curves": [ { "id": "top", "points": [[-0.1, 1.1], [0.1, 1.1]] },
                { "id": "bottom", "points": [[-0.1, 0.9], [0.1, 0.9]] },
                { "id": "mid", "points": [[0.0, 1.1], [0.0, 0.9]] },
                { "id": "left", "points": [[-0.1, 0.9], [-0.1, 1.1]] },
                { "id": "right", "points": [[0.1, 0.9], [0.1, 1.1]] } ],
    "panels": [ { "id": "l", "boundary": ["top", "mid", "bottom", "left"] },
                { "id": "r", "boundary": ["top", "right", "bottom", "mid"] } ],
    "edge_length": 0.02
  })",
                          "s.json");
  const BodySurface sphere(meshing::icosphere(0.3, 5, {0, 1, 0}));
  const Garment g = build_garment(s, sphere);
  EXPECT_EQ(g.seam_edges, 11);  // mid: 0.211 m on the offset sphere (see the test above)
  ASSERT_EQ(g.panels[0].side_counts.size(), 4u);
  // The left panel uses half of "top" and half of "bottom" (about 0.105 m: 5 edges each), all of
  // "mid" and "left" (11 each).
  std::vector<int> counts = g.panels[0].side_counts;
  std::sort(counts.begin(), counts.end());
  EXPECT_EQ(counts, (std::vector<int>{5, 5, 11, 11}));
  EXPECT_EQ(std::count(g.panels[0].curves.begin(), g.panels[0].curves.end(), "top"), 1);
}

// The tank top of the third rehearsal on the Collada human (data/designs/repro/tank-human.json):
// its back folded with the underarm, where the armhole runs on into the side seam at 51°, as a
// sixth corner (garment/fold_repair mended the 3 folds, the long thin quads there stayed), and
// the gate's warning named that corner and gave "corners" without it; with that list
// (data/designs/tank-human.json) the back has no fold and no warning. Since round 44 the filler
// does that itself (the back filled again with its corners judged about the body: no warning on
// it), so the told corner is checked on the forearm long-sleeve top's back sleeve, long thin quads
// where the underarm begins (81°).
TEST(Garment, AFoldingPanelIsToldWhichTurningCornerToDrop) {
  const std::filesystem::path designs = std::filesystem::path(SD_SOURCE_DIR) / "data/designs";
  const Sketch first = load_sketch(designs / "repro/tank-human.json");
  if (!std::filesystem::exists(first.resolve(first.body.mesh)))
    GTEST_SKIP() << "the Collada human (assimp-testmodels) is not installed";
  const Body body = load_sketch_body(first);
  const BodySurface surface(body.mesh);
  for (const QualityWarning& w : check_quality(build_garment(first, surface), first, nullptr))
    EXPECT_NE(w.panel, "back") << w.message;
  const Sketch forearm = load_sketch(designs / "repro/long-sleeve-top-human-forearm.json");
  const BodySurface forearm_surface(load_sketch_body(forearm).mesh);
  bool told = false;
  for (const QualityWarning& w :
       check_quality(build_garment(forearm, forearm_surface), forearm, nullptr))
    told = told || (w.panel == "sleeve_back" && w.kind == "aspect_ratio" &&
                    w.message.find("where 'underarm' begins") != std::string::npos &&
                    w.message.find(R"("corners": ["armhole_b", "sleeve_top", "cuff_b"])") !=
                        std::string::npos);
  EXPECT_TRUE(told);

  const Sketch second = load_sketch(designs / "tank-human.json");
  const Garment clean = build_garment(second, surface);
  EXPECT_TRUE(check_quality(clean, second, nullptr).empty());
  for (const GarmentPanel& panel : clean.panels) {
    EXPECT_EQ(panel.quality.inverted_quads, 0) << panel.id;
    EXPECT_TRUE(panel.turning_corners.empty()) << panel.id;  // listed corners: nothing to suggest
  }
}

// The advice that rewrites the sketch is tried before it is given, and following it gives fewer
// warnings. The shell top on the Collada human (data/designs/repro, sixth rehearsal) was told
// to drop its back's corner at 'side', which turned its 2 warnings into 3 (1 since
// garment/fold_repair mends the back's fold at the neck, 2 or more with that list): that offer is
// now left out, and its front's quads 2.38 times the edge length below the armhole get a curve's
// own edge_length instead, which applied left fewer warnings. Since round 43 (the panel's
// finishing ranked by the gate's measures, docs/meshing.md) that front is clean as it is, so the
// shell top is told nothing but the body's inside_body. The tank top's back, whose corner list
// the trial kept and which applied left fewer warnings, is filled clean since round 44 (its
// corners judged about the body, docs/meshing.md): no file of the corpus has a kept corner list
// now (the forearm long-sleeve top's is tried and dropped), so that half of the test went; a
// curve's own edge_length applied leaving fewer warnings is
// QuadSizeAdviceTriesTheCurvesNearTheQuads.
TEST(Garment, TheGatesAdviceThatWouldAddWarningsIsNotGiven) {
  const std::filesystem::path repro = std::filesystem::path(SD_SOURCE_DIR) / "data/designs/repro";
  const Sketch shell = load_sketch(repro / "shell-top-human.json");
  if (!std::filesystem::exists(shell.resolve(shell.body.mesh)))
    GTEST_SKIP() << "the Collada human (assimp-testmodels) is not installed";
  const Body body = load_sketch_body(shell);
  const BodySurface surface(body.mesh);
  std::vector<QualityWarning> told =
      check_quality_tried(build_garment(shell, surface), shell, body.mesh, nullptr);
  // The advice is weighed by check_quality's kinds; the body's `inside_body` (the back 9 mm
  // inside the neck) comes on top and is not advice.
  std::erase_if(told, [](const QualityWarning& w) { return w.kind == "inside_body"; });
  EXPECT_TRUE(told.empty()) << told.front().message;
}

// A panel's quads larger than asked get a curve's own edge_length from the few curves nearest
// them, not only the nearest. The shift dress moved to the Collada human with "drawn_on"
// (data/designs/author-38), without its hem's own edge_length, has its skirt front's widest
// quads (2.09 times the 2.5 cm edge) at the side seam; 'side_skirt' at 2.3 or 2 cm gives more
// warnings, so only that curve tried offered nothing. The hem or the hip seam with more edges
// cleans the skirt: one of them is offered, and applied it leaves fewer warnings.
TEST(Garment, QuadSizeAdviceTriesTheCurvesNearTheQuads) {
  Sketch dress = load_sketch(std::filesystem::path(SD_SOURCE_DIR) /
                             "data/designs/author-38/shift-dress-human.json");
  if (!std::filesystem::exists(dress.resolve(dress.body.mesh)))
    GTEST_SKIP() << "the Collada human (assimp-testmodels) is not installed";
  for (CurveSpec& curve : dress.curves)
    if (curve.id == "hem_f") curve.edge_length.reset();
  const Body body = load_sketch_body(dress);
  const BodySurface surface(body.mesh);
  const auto count = [&](const GarmentRequest& sketch) {
    return check_quality(build_garment(sketch, surface), sketch, nullptr).size();
  };
  const std::vector<QualityWarning> told =
      check_quality_tried(build_garment(dress, surface), dress, body.mesh, nullptr);
  const QualityWarning* size = nullptr;
  for (const QualityWarning& w : told)
    if (w.kind == "quad_size" && w.panel == "skirt_front") size = &w;
  ASSERT_NE(size, nullptr);
  ASSERT_FALSE(size->curve.empty()) << size->message;
  EXPECT_NE(size->curve, "side_skirt");
  const std::size_t before = count(dress);
  GarmentRequest side = dress;  // the nearest curve, at the first length the gate tries
  for (CurveSpec& curve : side.curves)
    if (curve.id == "side_skirt") curve.edge_length = size->curve_edge_length;
  EXPECT_GE(count(side), before);
  GarmentRequest finer = dress;
  for (CurveSpec& curve : finer.curves)
    if (curve.id == size->curve) curve.edge_length = size->curve_edge_length;
  EXPECT_LT(count(finer), before);
}

// Trial 40, P9: the poncho's back at 3 cm (data/designs/repro/poncho-back-coarse.json) has quads
// up to 2.13 times the edge at the shoulder, and none of its curves with an edge_length of its own
// alone helps, so the warning offered nothing until the designer lowered the panel to 2.5 cm (then
// it offered 'cb' at 1.7 cm). The first warning now offers the panel a fifth lower (2.4 cm) with
// one of its curves: neither alone gives fewer warnings, both together do.
TEST(Garment, QuadSizeAdviceLowersThePanelWhenNoCurveAloneHelps) {
  const Sketch poncho = load_sketch(std::filesystem::path(SD_SOURCE_DIR) /
                                    "data/designs/repro/poncho-back-coarse.json");
  const Body body = load_sketch_body(poncho);
  const BodySurface surface(body.mesh);
  const auto count = [&](const GarmentRequest& sketch) {
    return check_quality(build_garment(sketch, surface), sketch, nullptr).size();
  };
  const std::vector<QualityWarning> told =
      check_quality_tried(build_garment(poncho, surface), poncho, body.mesh, nullptr);
  const QualityWarning* size = nullptr;
  for (const QualityWarning& w : told)
    if (w.kind == "quad_size" && w.panel == "back") size = &w;
  ASSERT_NE(size, nullptr);
  ASSERT_FALSE(size->curve.empty()) << size->message;
  EXPECT_DOUBLE_EQ(size->panel_edge_length, 0.024);
  EXPECT_NE(size->message.find(fmt::format(
                "panel 'back' with \"edge_length\": 0.024 and curve '{}' with its own "
                "\"edge_length\": {:g} (more edges along both) give the garment fewer warnings",
                size->curve, size->curve_edge_length)),
            std::string::npos)
      << size->message;
  const std::size_t before = count(poncho);
  GarmentRequest curve_only = poncho;
  for (CurveSpec& curve : curve_only.curves)
    if (curve.id == size->curve) curve.edge_length = size->curve_edge_length;
  EXPECT_GE(count(curve_only), before);
  GarmentRequest panel_only = poncho;
  for (PanelSpec& panel : panel_only.panels)
    if (panel.id == "back") panel.edge_length = size->panel_edge_length;
  EXPECT_GE(count(panel_only), before);
  GarmentRequest both = curve_only;
  for (PanelSpec& panel : both.panels)
    if (panel.id == "back") panel.edge_length = size->panel_edge_length;
  EXPECT_LT(count(both), before);
}

// Trial 41, P6: the quad-size advice must clear the quads it is about, not move them. The raglan
// top's front (data/designs/repro/raglan-top.json, 5 quads up to 2.40 times the 2.5 cm edge) was
// offered 'raglan_f' at 2 cm, which gave the garment fewer warnings (another panel's went) but
// left 4 of the front's quads 2.25 times the edge; the kimono blouse's front was offered
// 'underarm' at 2 cm, which left one at 2.36. Whatever is offered now, applied, leaves no quad of
// that panel larger than the band.
TEST(Garment, QuadSizeAdviceClearsThePanelsLargeQuads) {
  const std::filesystem::path repro = std::filesystem::path(SD_SOURCE_DIR) / "data/designs/repro";
  for (const char* file : {"raglan-top.json", "kimono-blouse.json"}) {
    const Sketch sketch = load_sketch(repro / file);
    const Body body = load_sketch_body(sketch);
    const BodySurface surface(body.mesh);
    const QualityLimits limits;
    const std::vector<QualityWarning> told =
        check_quality_tried(build_garment(sketch, surface), sketch, body.mesh, nullptr);
    int offers = 0;
    for (const QualityWarning& w : told) {
      if (w.kind != "quad_size" || !(w.worst > limits.size_high)) continue;
      if (w.curve.empty() && !(w.panel_edge_length > 0)) continue;  // nothing offered
      ++offers;
      GarmentRequest followed = sketch;
      for (CurveSpec& curve : followed.curves)
        if (curve.id == w.curve) curve.edge_length = w.curve_edge_length;
      for (PanelSpec& panel : followed.panels)
        if (panel.id == w.panel && w.panel_edge_length > 0) panel.edge_length = w.panel_edge_length;
      const std::vector<QualityWarning> after =
          check_quality(build_garment(followed, surface), followed, nullptr);
      EXPECT_LT(after.size(), check_quality(build_garment(sketch, surface), sketch, nullptr).size())
          << file << ": " << w.message;
      for (const QualityWarning& q : after)
        EXPECT_FALSE(q.panel == w.panel && q.kind == "quad_size" && q.worst > limits.size_high)
            << file << ": following \"" << w.message << "\" left " << q.message;
    }
    RecordProperty(file, offers);
  }
}

// Trial 38 / issue 18: the shift dress written on the built-in body and moved to the Collada
// human with "drawn_on" had 6 quality warnings there, 4 at the back armhole (folds, slivers, a
// panel through itself), and the offsets were blamed. It was the back bodice's six corners on
// that body; with the corner list the gate offered, the hem's edge_length it offers and the
// neckline 1.5 cm off the body, the one file is clean on both bodies (inside_body included).
TEST(Garment, ShiftDressDrawnOnTheBuiltinBodyIsCleanOnTheColladaHuman) {
  const std::filesystem::path dir = std::filesystem::path(SD_SOURCE_DIR) / "data/designs/author-38";
  const Sketch dress = load_sketch(dir / "shift-dress-human.json");
  if (!std::filesystem::exists(dress.resolve(dress.body.mesh)))
    GTEST_SKIP() << "the Collada human (assimp-testmodels) is not installed";
  for (const Sketch& sketch : {load_sketch(dir / "shift-dress.json"), dress}) {
    const Body body = load_sketch_body(sketch);
    const BodySurface surface(body.mesh);
    for (const QualityWarning& w :
         check_quality_tried(build_garment(sketch, surface), sketch, body.mesh, nullptr))
      ADD_FAILURE() << sketch.file << ": " << w.message;
  }
}

// Trial 38's halter top kept a quad 2.36 times the edge in its one-piece front (round the neck:
// six corners, two reflex layout vertices the filler put on the hem and the neckline). With a
// seam across the strap (data/designs/author-38/halter-top.json) it is clean; without the
// strap's own edge_length it has the one warning, and the gate offers exactly that curve: at
// 1.8 cm since round 43 (its quads 2.11 times the edge instead of 2.39 once the smoothing is
// ranked by the gate's measures, docs/meshing.md; the file keeps the 1.6 cm offered before).
TEST(Garment, HalterTopWithASeamAcrossTheStrapIsClean) {
  const Sketch halter =
      load_sketch(std::filesystem::path(SD_SOURCE_DIR) / "data/designs/author-38/halter-top.json");
  const Body body = load_sketch_body(halter);
  const BodySurface surface(body.mesh);
  EXPECT_TRUE(
      check_quality_tried(build_garment(halter, surface), halter, body.mesh, nullptr).empty());
  GarmentRequest plain = halter;
  for (CurveSpec& curve : plain.curves)
    if (curve.id == "strap_lo") curve.edge_length.reset();
  const std::vector<QualityWarning> told =
      check_quality_tried(build_garment(plain, surface), plain, body.mesh, nullptr);
  ASSERT_EQ(told.size(), 1u);
  EXPECT_EQ(told[0].kind, "quad_size");
  EXPECT_EQ(told[0].curve, "strap_lo");
  EXPECT_DOUBLE_EQ(told[0].curve_edge_length, 0.018);
}

// Issue 18, round 42 (docs/meshing.md, "Round 42: an arm that widens"): one-piece panels that run
// out into a strap widening towards the body, written without tuning (data/designs/repro/), were
// refused by --strict (1, 5 and 7 warnings: quads 2.4-3.4 × the edge, folds, slivers); filled
// with a cut across the strap where it joins, every panel passes the gate, and the strap's panel
// is the one the cut changed ("arm-cut").
TEST(Garment, OnePieceStrapsThatWidenPassTheGate) {
  for (const char* name : {"halter-one-piece", "bib-apron-top", "thin-strap-one-shoulder"}) {
    const Sketch sketch = load_sketch(std::filesystem::path(SD_SOURCE_DIR) / "data/designs/repro" /
                                      (std::string(name) + ".json"));
    const Body body = load_sketch_body(sketch);
    const BodySurface surface(body.mesh);
    const Garment garment = build_garment(sketch, surface);
    EXPECT_TRUE(check_quality_tried(garment, sketch, body.mesh, nullptr).empty()) << name;
    EXPECT_TRUE(std::any_of(garment.panels.begin(), garment.panels.end(),
                            [](const GarmentPanel& p) { return p.partition == "arm-cut"; }))
        << name;
  }
}

// Every panel of each named design of data/designs/repro meshes without a quality warning.
void expect_repro_designs_pass_the_gate(std::initializer_list<const char*> names) {
  for (const char* name : names) {
    const Sketch sketch = load_sketch(std::filesystem::path(SD_SOURCE_DIR) / "data/designs/repro" /
                                      (std::string(name) + ".json"));
    const Body body = load_sketch_body(sketch);
    const BodySurface surface(body.mesh);
    const Garment garment = build_garment(sketch, surface);
    for (const QualityWarning& w : check_quality(garment, sketch, nullptr))
      ADD_FAILURE() << name << ": " << w.message;
  }
}

// Issue 18, round 43 (docs/meshing.md, "Round 43: quads off size after the smoothing"): the
// one-piece one-shoulder top's back (a 4-edge shoulder between sides of 13 and 21 edges, no
// arm) is filled with a valence-6 vertex under the strap; the fill had 4 quads up to 2.29 × the
// edge round it and was kept over its smoothing along the body for a better worst corner. Chosen
// by the gate's measures, with the smoothing that weighs that vertex as a candidate, it is clean;
// so is the kimono tee's (1 quad_size warning before).
TEST(Garment, OnePieceBackWideningUnderTheStrapPassesTheGate) {
  expect_repro_designs_pass_the_gate({"one-shoulder-top-one-piece", "kimono-tee"});
}

// Above QualityLimits::max_trial_quads the advice that needs the garment meshed again is not
// tried, and so not offered: the forearm long-sleeve top's back sleeve, offered an untried corner
// list (the tank top's back was the example until round 44 filled it clean), gets the plain
// warning, the same warnings in number and kind (no trial build is run, so a fine preview does not
// spend minutes re-meshing before it says anything).
TEST(Garment, TheGatesAdviceIsNotTriedAboveTheQuadLimit) {
  const Sketch tank = load_sketch(std::filesystem::path(SD_SOURCE_DIR) /
                                  "data/designs/repro/long-sleeve-top-human-forearm.json");
  if (!std::filesystem::exists(tank.resolve(tank.body.mesh)))
    GTEST_SKIP() << "the Collada human (assimp-testmodels) is not installed";
  const Body body = load_sketch_body(tank);
  const Garment garment = build_garment(tank, BodySurface(body.mesh));
  QualityLimits limits;
  limits.max_trial_quads = static_cast<int>(garment.mesh.face_count()) - 1;
  const std::vector<QualityWarning> plain = check_quality(garment, tank, nullptr, limits);
  std::vector<QualityWarning> told = check_quality_tried(garment, tank, body.mesh, nullptr, limits);
  // The body's own check (inside_body, the back 9 mm at the neck) is not advice: it has no
  // counterpart in check_quality, which is not given the body.
  std::erase_if(told, [](const QualityWarning& w) { return w.kind == "inside_body"; });
  ASSERT_EQ(told.size(), plain.size());
  bool offered_before = false;
  for (const QualityWarning& w : plain) offered_before |= !w.corners.empty();
  EXPECT_TRUE(offered_before);  // the untried list (which the trial, run, drops here)
  for (size_t i = 0; i < told.size(); ++i) {
    EXPECT_EQ(told[i].kind, plain[i].kind);
    EXPECT_TRUE(told[i].corners.empty()) << told[i].message;
    EXPECT_TRUE(told[i].curve.empty()) << told[i].message;
    if (!plain[i].corners_hint.empty()) {
      EXPECT_EQ(told[i].message.find(plain[i].corners_hint), std::string::npos) << told[i].message;
    }
  }
}

// Issue 18, round 44 (docs/meshing.md, "Round 44"): the kimono blouse's back (a sleeve cut in one
// with the bodice) was planned with its reflex and flat boundary positions judged about the
// loop's overall normal, which the sleeve's run over the shoulder turns against: 9 quads off
// the gate's size band, distortion 28 for the garment and 3 warnings. A body panel left with a
// sliver or quads off size is filled again with those positions judged about the body's normals
// and takes that fill when it has fewer flaws and no more of any: the blouse is clean, and so
// is the peplum bodice (its back had a sliver, 1 warning).
TEST(Garment, PanelsRefilledWithCornersJudgedAboutTheBodyPassTheGate) {
  expect_repro_designs_pass_the_gate({"kimono-blouse", "fill-peplum-bodice"});
}

}  // namespace
}  // namespace sd::garment
