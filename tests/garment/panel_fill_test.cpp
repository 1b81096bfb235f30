#include "garment/panel_fill.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "garment/body.hpp"
#include "garment/body_surface.hpp"
#include "garment/garment_mesh.hpp"
#include "garment/panel_tasks.hpp"
#include "garment/sketch_inputs.hpp"
#include "meshing/patch_relaxation.hpp"
#include "scene/sketch_file.hpp"

namespace sd::garment {
namespace {

// A garment built on this thread alone (the relaxation tally is per thread), with the tally of
// its relaxations.
struct Built {
  Garment garment;
  meshing::detail::RelaxationTally tally;
};

Built build_counted(const char* file) {
  const scene::Sketch sketch = scene::load_sketch(std::filesystem::path(SD_SOURCE_DIR) / file);
  const Body body = load_sketch_body(sketch);
  const BodySurface surface(body.mesh);
  const int threads = panel_threads();
  set_panel_threads(1);
  meshing::detail::relaxation_tally() = {};
  Built built{build_garment(sketch, surface), {}};
  built.tally = meshing::detail::relaxation_tally();
  set_panel_threads(threads);
  return built;
}

struct Worst {
  int inverted = 0;
  double aspect = 0;
};
Worst worst_of(const Garment& garment) {
  Worst w;
  for (const GarmentPanel& p : garment.panels) {
    w.inverted += p.quality.inverted_quads;
    w.aspect = std::max(w.aspect, p.quality.max_aspect_ratio);
  }
  return w;
}

// The raglan top's sleeves fold in every plan the filler tries; its last resorts (a second
// search, a second relaxation) cost a full relaxation along the body each and mend nothing the
// smoothing and unfolding along the body do not. Filled without them first, the garment is as
// clean and its relaxations that go on to the guarded sweeps fall from 8 (6 with the
// after-sweeps pass stopped early, 8 before either change) to 3.
TEST(PanelFill, SleevesTheBodyMendsSkipTheFillersLastResorts) {
  const Built b = build_counted("data/designs/raglan-top.json");
  EXPECT_LE(b.tally.guarded, 3);
  EXPECT_EQ(worst_of(b.garment).inverted, 0);
  EXPECT_LT(worst_of(b.garment).aspect, 10);
}

// A panel the body does not mend is filled again with the last resorts: the kimono tee's
// panels keep 12 folded quads without them and none with them.
TEST(PanelFill, APanelStillFoldedIsFilledAgainWithTheLastResorts) {
  const Built b = build_counted("data/designs/repro/kimono-tee.json");
  EXPECT_EQ(worst_of(b.garment).inverted, 0);
  EXPECT_LT(worst_of(b.garment).aspect, 10);
}

}  // namespace
}  // namespace sd::garment
