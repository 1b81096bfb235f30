#include "garment/unused_curves.hpp"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace sd::garment
