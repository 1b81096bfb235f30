#include "garment/unused_curves.hpp"

#include <gtest/gtest.h>

#include <string>

#include "garment/body_surface.hpp"
#include "meshing/tri_mesh.hpp"
#include "scene/sketch_file.hpp"

namespace sd::garment {
namespace {

// Two panels side by side on a sphere sharing 'mid', and `extra` curves after them.
scene::Sketch two_panels(const std::string& extra) {
  return scene::parse_sketch(R"({
    "curves": [
      { "id": "top_l", "points": [[-0.1, 1.1], [0, 1.1]] }, { "id": "top_r", "points": [[0, 1.1], [0.1, 1.1]] },
      { "id": "mid", "points": [[0, 1.1], [0, 0.9]] },
      { "id": "bot_l", "points": [[-0.1, 0.9], [0, 0.9]] }, { "id": "bot_r", "points": [[0, 0.9], [0.1, 0.9]] },
      { "id": "left", "points": [[-0.1, 0.9], [-0.1, 1.1]] }, { "id": "right", "points": [[0.1, 0.9], [0.1, 1.1]] })" +
                                 extra + R"(
    ],
    "panels": [ { "id": "l", "boundary": ["top_l", "mid", "bot_l", "left"] },
                { "id": "r", "boundary": ["top_r", "right", "bot_r", "mid"] } ],
    "edge_length": 0.02
  })",
                             "s.json");
}

// Trial 40, P5: a curve drawn over a panel's edge ('dart' along 'right') and one drawn apart
// ('guide', beside the panels), in no panel, were silently ignored. Each is named with its path, in
// file order; the garment without them has none.
TEST(UnusedCurves, EachCurveInNoPanelIsNamedWithItsPath) {
  const BodySurface sphere(meshing::icosphere(0.3, 5, {0, 1, 0}));
  const scene::Sketch clean = two_panels("");
  EXPECT_TRUE(unused_curve_warnings(clean, build_garment(clean, sphere)).empty());
  const scene::Sketch extra = two_panels(R"(,
      { "id": "dart", "points": [[0.1, 1.08], [0.1, 0.92]] },
      { "id": "guide", "points": [[0.15, 1.0], [0.2, 1.0]] })");
  const std::vector<std::string> warnings =
      unused_curve_warnings(extra, build_garment(extra, sphere));
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_EQ(warnings[0].rfind("s.json: /curves/7: curve 'dart' is in no panel: a forgotten panel "
                              "or a typo in a boundary list?",
                              0),
            0u)
      << warnings[0];
  EXPECT_EQ(warnings[1].rfind("s.json: /curves/8: curve 'guide' is in no panel", 0), 0u)
      << warnings[1];
}

// Trial 42, P9: a mirrored design with "mirror": true left off one panel validated "ok" with
// that panel's copy missing and its seams open. Two panels right of the centre sewn along 'mid',
// both mirrored: no warning; 'r' not mirrored: 'mid.mirror' borders only 'l.mirror', and 'r' is
// named as the panel that probably lacks "mirror": true.
TEST(UnusedCurves, AMirrorCopyBorderingFewerPanelsNamesThePanelLackingMirror) {
  const BodySurface sphere(meshing::icosphere(0.3, 5, {0, 1, 0}));
  const auto sketch = [](bool r_mirrored) {
    return scene::parse_sketch(std::string(R"({
    "curves": [
      { "id": "top_l", "points": [[0.02, 1.1], [0.1, 1.1]] }, { "id": "top_r", "points": [[0.1, 1.1], [0.18, 1.1]] },
      { "id": "mid", "points": [[0.1, 1.1], [0.1, 0.9]] },
      { "id": "bot_l", "points": [[0.02, 0.9], [0.1, 0.9]] }, { "id": "bot_r", "points": [[0.1, 0.9], [0.18, 0.9]] },
      { "id": "left", "points": [[0.02, 0.9], [0.02, 1.1]] }, { "id": "right", "points": [[0.18, 0.9], [0.18, 1.1]] }
    ],
    "panels": [ { "id": "l", "boundary": ["top_l", "mid", "bot_l", "left"], "mirror": true },
                { "id": "r", "boundary": ["top_r", "right", "bot_r", "mid"], "mirror": )") +
                                   (r_mirrored ? "true" : "false") + R"( } ],
    "edge_length": 0.02
  })",
                               "s.json");
  };
  const scene::Sketch both = sketch(true);
  EXPECT_TRUE(half_mirrored_warnings(both, build_garment(both, sphere)).empty());
  const scene::Sketch one = sketch(false);
  const std::vector<std::string> warnings = half_mirrored_warnings(one, build_garment(one, sphere));
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0].rfind("s.json: /panels/1: curve 'mid' is a seam between 'l' and 'r', but "
                              "its copy 'mid.mirror' borders only 'l.mirror': is \"mirror\": "
                              "true missing on panel 'r'?",
                              0),
            0u)
      << warnings[0];
}

}  // namespace
}  // namespace sd::garment
