#include "garment/network_faces.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "garment/body.hpp"
#include "garment/garment_mesh.hpp"
#include "garment/stroke_projection.hpp"
#include "scene/sketch_file.hpp"
#include "tests/garment/test_helpers.hpp"

namespace sd::garment {
// The tests read sketch files through the scene layer.
using scene::parse_sketch;
using scene::Sketch;

namespace {

const BodySurface& sphere() {
  static const BodySurface surface(meshing::icosphere(0.3, 5, {0, 1, 0}));
  return surface;
}

const BodySurface& builtin_surface() {
  static const Body body = load_body("builtin");
  static const BodySurface surface(body.mesh);
  return surface;
}

// A 2 × 2 grid drawn on the front of the sphere. Curves that cross are not joined, so the middle
// row is two strokes that end on the centre column (splitting it), and the inner strokes end on
// the outer ones: 9 junctions, 12 pieces and, on the sphere, 12 − 9 + 2 = 5 faces: four cells
// and the rest of the sphere.
constexpr const char* kGrid = R"({
  "edge_length": 0.02,
  "curves": [
    { "id": "top",    "points": [[-0.12, 1.12], [0.12, 1.12]] },
    { "id": "mid_l",  "points": [[-0.12, 1.0], [0.0, 1.0]] },
    { "id": "mid_r",  "points": [[0.0, 1.0], [0.12, 1.0]] },
    { "id": "bottom", "points": [[-0.12, 0.88], [0.12, 0.88]] },
    { "id": "left",   "points": [[-0.12, 1.12], [-0.12, 0.88]] },
    { "id": "centre", "points": [[0.0, 1.12], [0.0, 0.88]] },
    { "id": "right",  "points": [[0.12, 1.12], [0.12, 0.88]] }
  ],
  "panels": [
    { "id": "nw", "boundary": "auto", "seed": { "point": [-0.06, 1.06] } },
    { "id": "ne", "boundary": "auto", "seed": { "point": [0.06, 1.06] } },
    { "id": "sw", "boundary": "auto", "seed": { "view": "front", "point": [-0.06, 0.94] } },
    { "id": "se", "boundary": "auto", "seed": { "point3d": [0.06, 0.94, 0.3] } }
  ]
})";

std::multiset<std::string> curves_of(const GarmentPanel& p) {
  return {p.curves.begin(), p.curves.end()};
}

TEST(NetworkFaces, GridOnSphereHasFourCellsAndTheRest) {
  const Sketch s = parse_sketch(kGrid, "grid.json");
  const CurveNetwork net = build_network(s, project_curves(s, sphere()), {});
  EXPECT_EQ(net.nodes.size(), 9u);
  EXPECT_EQ(net.edges.size(), 12u);
  const NetworkFaces faces = trace_faces(net, sphere());
  ASSERT_EQ(faces.faces.size(), 5u);  // Euler: V − E + F = 2 on the sphere
  std::vector<size_t> sizes;
  for (const auto& f : faces.faces) sizes.push_back(f.size());
  std::sort(sizes.begin(), sizes.end());
  EXPECT_EQ(sizes, (std::vector<size_t>{4, 4, 4, 4, 8}));
  // Every half-edge is in exactly one face, and each face is a closed walk.
  std::vector<int> seen(2 * net.edges.size(), 0);
  for (size_t f = 0; f < faces.faces.size(); ++f) {
    const auto& loop = faces.faces[f];
    for (size_t k = 0; k < loop.size(); ++k) {
      ++seen[static_cast<size_t>(2 * loop[k].edge + (loop[k].forward ? 0 : 1))];
      EXPECT_EQ(loop_end_node(net, loop[k]), loop_start_node(net, loop[(k + 1) % loop.size()]));
      EXPECT_EQ(faces.face_left[static_cast<size_t>(2 * loop[k].edge + (loop[k].forward ? 0 : 1))],
                static_cast<int>(f));
    }
  }
  for (int n : seen) EXPECT_EQ(n, 1);
  // The cells run counter-clockwise seen from the front (+z): positive signed area in x-y.
  for (const auto& loop : faces.faces) {
    if (loop.size() != 4) continue;
    double area = 0;
    for (const LoopEdge& e : loop) {
      const Eigen::Vector3d a = net.nodes[static_cast<size_t>(loop_start_node(net, e))];
      const Eigen::Vector3d b = net.nodes[static_cast<size_t>(loop_end_node(net, e))];
      area += a.x() * b.y() - b.x() * a.y();
    }
    EXPECT_GT(area, 0);
  }
}

TEST(NetworkFaces, SeedsPickTheirCells) {
  const Garment g = build_garment(parse_sketch(kGrid, "grid.json"), sphere());
  ASSERT_EQ(g.panels.size(), 4u);
  std::map<std::string, std::multiset<std::string>> curves;
  for (const GarmentPanel& p : g.panels) {
    curves[p.id] = curves_of(p);
    EXPECT_EQ(p.side_counts.size(), 4u) << p.id;
  }
  EXPECT_EQ(curves["nw"], (std::multiset<std::string>{"top", "centre", "mid_l", "left"}));
  EXPECT_EQ(curves["ne"], (std::multiset<std::string>{"top", "right", "mid_r", "centre"}));
  EXPECT_EQ(curves["sw"], (std::multiset<std::string>{"mid_l", "centre", "bottom", "left"}));
  EXPECT_EQ(curves["se"], (std::multiset<std::string>{"mid_r", "right", "bottom", "centre"}));
  // The four inner pieces (two of the centre column, mid_l, mid_r: 6 edges of 2 cm each on the
  // offset sphere) are seams.
  EXPECT_EQ(g.seam_edges, 4 * 6);
  for (const GarmentPanel& p : g.panels) EXPECT_EQ(p.quality.inverted_quads, 0) << p.id;
}

// The explicit and the "auto" forms of the A-line skirt give the same panels.
TEST(NetworkFaces, AutoSkirtMatchesTheListedSkirt) {
  const std::filesystem::path file =
      std::filesystem::path(SD_SOURCE_DIR) / "data/examples/a-line-skirt.json";
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  const Sketch listed = parse_sketch(text.str(), file.string());
  nlohmann::json j = nlohmann::json::parse(text.str(), nullptr, true, /*ignore_comments=*/true);
  const std::map<std::string, nlohmann::json> seeds = {
      {"yoke_front", {{"point", {0.08, 0.95}}}},
      {"yoke_back", {{"view", "back"}, {"point", {-0.08, 0.95}}}},
      {"skirt_front", {{"point3d", {0.12, 0.70, 0.16}}}},
      {"skirt_back", {{"point3d", {0.12, 0.70, -0.15}}}}};
  for (auto& panel : j["panels"]) {
    panel["boundary"] = "auto";
    panel["seed"] = seeds.at(panel["id"].get<std::string>());
  }
  const Sketch automatic = parse_sketch(j.dump(), "auto-skirt.json");
  const Garment a = build_garment(listed, builtin_surface());
  const Garment b = build_garment(automatic, builtin_surface());
  ASSERT_EQ(a.panels.size(), b.panels.size());
  for (size_t p = 0; p < a.panels.size(); ++p) {
    const GarmentPanel &pa = a.panels[p], &pb = b.panels[p];
    EXPECT_EQ(pa.id, pb.id);
    EXPECT_EQ(curves_of(pa), curves_of(pb)) << pa.id;
    // Same sides up to where the loop starts.
    std::vector<int> sa = pa.side_counts, sb = pb.side_counts;
    ASSERT_EQ(sa.size(), sb.size()) << pa.id;
    bool rotation = false;
    for (size_t r = 0; r < sb.size() && !rotation; ++r) {
      std::rotate(sb.begin(), sb.begin() + 1, sb.end());
      rotation = sa == sb;
    }
    EXPECT_TRUE(rotation) << pa.id;
    EXPECT_EQ(pa.faces, pb.faces) << pa.id;
    EXPECT_EQ(pa.distortion, pb.distortion) << pa.id;
  }
  EXPECT_EQ(a.mesh.vertex_count(), b.mesh.vertex_count());
  EXPECT_EQ(a.seam_edges, b.seam_edges);
}

std::string error_of(const std::string& text, const BodySurface& body,
                     std::string* path = nullptr) {
  try {
    build_garment(parse_sketch(text, "bad.json"), body);
  } catch (const SketchError& e) {
    if (path) *path = e.json_path();
    return e.what();
  }
  return "accepted";
}

std::string grid_with(const std::string& panels, const std::string& extra_curve = "") {
  std::string text = kGrid;
  const size_t a = text.find("\"panels\""), b = text.rfind(']');
  text = text.substr(0, a) + "\"panels\": " + panels + text.substr(b + 1);
  if (!extra_curve.empty()) {
    const size_t c = text.find("\"curves\": [") + 11;
    text.insert(c, extra_curve + ",");
  }
  return text;
}

TEST(NetworkFaces, DesignerMistakes) {
  std::string path;
  // A seed on a curve.
  EXPECT_NE(
      error_of(
          grid_with(R"([{ "id": "p", "boundary": "auto", "seed": { "point": [0.0, 1.06] } }])"),
          sphere(), &path)
          .find("lies on curve 'centre'"),
      std::string::npos);
  EXPECT_EQ(path, "/panels/0/seed");
  // Two seeds in one cell.
  EXPECT_NE(
      error_of(grid_with(R"([{ "id": "p", "boundary": "auto", "seed": { "point": [0.05, 1.05] } },
                                   { "id": "q", "boundary": "auto", "seed": { "point": [0.07, 1.07] } }])"),
               sphere(), &path)
          .find("panels 'p' and 'q' lie in the same region"),
      std::string::npos);
  EXPECT_EQ(path, "/panels/1/seed");
  // A curve sticking into the cell with a free end.
  const std::string dangling = R"({ "id": "dart", "points": [[0.06, 1.12], [0.06, 1.05]] })";
  EXPECT_NE(
      error_of(
          grid_with(R"([{ "id": "p", "boundary": "auto", "seed": { "point": [0.03, 1.03] } }])",
                    dangling),
          sphere(), &path)
          .find("curve 'dart' ends inside it"),
      std::string::npos);
  EXPECT_EQ(path, "/panels/0/seed");
  // A loop floating inside a cell, not connected to it.
  const std::string island =
      R"({ "id": "island", "closed": true, "points": [[0.05, 1.05], [0.08, 1.05], [0.065, 1.08]] })";
  EXPECT_NE(
      error_of(
          grid_with(R"([{ "id": "p", "boundary": "auto", "seed": { "point": [0.02, 1.02] } }])",
                    island),
          sphere())
          .find("has curve 'island' inside it"),
      std::string::npos);
  // A seed that misses the sphere.
  EXPECT_NE(
      error_of(grid_with(R"([{ "id": "p", "boundary": "auto", "seed": { "point": [0.5, 1.0] } }])"),
               sphere(), &path)
          .find("misses the body in the front view"),
      std::string::npos);
  EXPECT_EQ(path, "/panels/0/seed/point");
  // "auto" needs a seed, a listed boundary takes none.
  EXPECT_NE(error_of(grid_with(R"([{ "id": "p", "boundary": "auto" }])"), sphere(), &path)
                .find("no \"seed\""),
            std::string::npos);
  EXPECT_EQ(path, "/panels/0/boundary");
  EXPECT_NE(
      error_of(
          grid_with(
              R"([{ "id": "p", "boundary": ["top", "right", "bottom", "left"], "seed": { "point": [0, 1] } }])"),
          sphere(), &path)
          .find("only picks the region"),
      std::string::npos);
  EXPECT_EQ(path, "/panels/0/seed");
}

TEST(NetworkFaces, TheOuterRegionIsAPanelToo) {
  // On a closed surface there is no unbounded face: a seed outside the grid picks the region
  // around it, bounded by the grid's 8 outer pieces (the sphere minus the grid).
  const Sketch s = parse_sketch(
      grid_with(R"([{ "id": "rest", "boundary": "auto", "seed": { "point3d": [0, 1, -0.3] } }])"),
      "rest.json");
  const CurveNetwork net = build_network(s, project_curves(s, sphere()), {});
  const NetworkFaces faces = trace_faces(net, sphere());
  const std::vector<LoopEdge> loop = auto_panel_loop(s, net, faces, sphere(), s.panels[0]);
  EXPECT_EQ(loop.size(), 8u);
}

}  // namespace
}  // namespace sd::garment
