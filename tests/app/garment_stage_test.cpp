#include "src/app/pipeline/garment_stage.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "garment/body_surface.hpp"
#include "garment/sketch_error.hpp"
#include "garment/sketch_inputs.hpp"

namespace sd::app {
namespace {

// A garment quad squeezed to no area (the filler once left such quads where a free panel's
// membrane was pushed into a crease of the body) is not an internal 4-8 mesh error with vertex
// numbers: it fails at the panel's JSON path with the place and the nearest landmark.
TEST(GarmentMesh48, ACollapsedQuadNamesItsPanelPlaceAndLandmark) {
  const scene::Sketch sketch =
      scene::load_sketch(std::filesystem::path(SD_SOURCE_DIR) / "data/designs/pencil-skirt.json");
  const garment::Body body = garment::load_sketch_body(sketch);
  const garment::BodySurface surface(body.mesh);
  garment::Garment g = garment::build_garment(sketch, surface);
  EXPECT_NO_THROW(garment_mesh48(sketch, body, g));  // as meshed: every quad has area

  // The last quad's second corner put on its first: both of its triangle pairs lose their area.
  const Eigen::Index f = g.mesh.face_count() - 1;
  g.mesh.vertices.row(g.mesh.faces(f, 1)) = g.mesh.vertices.row(g.mesh.faces(f, 0));
  const garment::GarmentPanel& panel = g.panels[static_cast<size_t>(g.face_panel(f))];
  const std::string original = panel.id.substr(0, panel.id.find('.'));
  std::string path;
  for (const garment::PanelSpec& spec : sketch.panels)
    if (spec.id == original) path = spec.json_path;
  ASSERT_FALSE(path.empty());
  try {
    garment_mesh48(sketch, body, g);
    FAIL() << "the collapsed quad was accepted";
  } catch (const garment::SketchError& e) {
    EXPECT_EQ(e.json_path(), path);
    EXPECT_NE(e.sentence().find("panel '" + panel.id + "' has a collapsed quad at ("),
              std::string::npos)
        << e.sentence();
    EXPECT_NE(e.sentence().find("near the body's "), std::string::npos) << e.sentence();
    EXPECT_EQ(e.sentence().find("vertices"), std::string::npos) << e.sentence();
  }
}

}  // namespace
}  // namespace sd::app
