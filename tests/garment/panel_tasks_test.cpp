#include "garment/panel_tasks.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "garment/body.hpp"
#include "garment/body_surface.hpp"
#include "garment/garment_mesh.hpp"
#include "scene/sketch_file.hpp"

namespace sd::garment {
namespace {

// Sets the panel threads for one test and puts back what was there.
class PanelThreads {
 public:
  explicit PanelThreads(int n) : before_(panel_threads()) { set_panel_threads(n); }
  ~PanelThreads() { set_panel_threads(before_); }
  PanelThreads(const PanelThreads&) = delete;
  PanelThreads& operator=(const PanelThreads&) = delete;

 private:
  int before_;
};

TEST(PanelTasks, RunsEveryTaskOnceOnAnyNumberOfThreads) {
  for (const int threads : {1, 2, 3, 8}) {
    const PanelThreads set(threads);
    EXPECT_EQ(panel_threads(), threads);
    std::vector<std::atomic<int>> runs(23);
    run_panel_tasks(23, [&](int i) { ++runs[static_cast<size_t>(i)]; });
    for (size_t i = 0; i < runs.size(); ++i) EXPECT_EQ(runs[i].load(), 1) << "task " << i;
  }
  run_panel_tasks(0, [](int) { FAIL() << "no task to run"; });
}

// Every task runs even when some throw, and the lowest index's exception comes out: the one a
// loop in order would have met first (the first panel that cannot be filled is the one named).
TEST(PanelTasks, RethrowsTheFailureOfTheLowestIndexAfterRunningAll) {
  for (const int threads : {1, 2}) {
    const PanelThreads set(threads);
    std::atomic<int> ran{0};
    try {
      run_panel_tasks(6, [&](int i) {
        ++ran;
        if (i == 4 || i == 2) throw std::runtime_error("task " + std::to_string(i));
      });
      FAIL() << "nothing thrown";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "task 2");
    }
    EXPECT_EQ(ran.load(), 6);
  }
}

TEST(PanelTasks, NonPositiveCountMeansEveryCore) {
  const PanelThreads set(0);
  EXPECT_GE(panel_threads(), 1);
}

// The garment is the same, bit for bit, whether its panels are filled one after the other or
// side by side: the raglan top (its sleeves fold in their first plans and take longest) and the
// shorts (mirrored halves, a doublet merged at the centre front).
TEST(PanelTasks, GarmentsAreTheSameBitsOnOneThreadAndOnTwo) {
  static const Body body = load_body("builtin");
  static const BodySurface surface(body.mesh);
  for (const char* file : {"data/designs/raglan-top.json", "data/examples/shorts.json"}) {
    const scene::Sketch sketch = scene::load_sketch(std::filesystem::path(SD_SOURCE_DIR) / file);
    Garment one, two;
    {
      const PanelThreads set(1);
      one = build_garment(sketch, surface);
    }
    {
      const PanelThreads set(2);
      two = build_garment(sketch, surface);
    }
    SCOPED_TRACE(file);
    ASSERT_EQ(one.mesh.vertices.rows(), two.mesh.vertices.rows());
    EXPECT_TRUE(one.mesh.vertices == two.mesh.vertices);  // exact, not within a tolerance
    EXPECT_TRUE(one.mesh.faces == two.mesh.faces);
    EXPECT_TRUE(one.face_panel == two.face_panel);
    ASSERT_EQ(one.panels.size(), two.panels.size());
    for (size_t p = 0; p < one.panels.size(); ++p) {
      EXPECT_EQ(one.panels[p].fit, two.panels[p].fit);
      EXPECT_EQ(one.panels[p].span_gap, two.panels[p].span_gap);
      EXPECT_EQ(one.panels[p].quality.inverted_quads, two.panels[p].quality.inverted_quads);
      EXPECT_EQ(one.panels[p].quality.scaled_jacobian_min,
                two.panels[p].quality.scaled_jacobian_min);
    }
    EXPECT_EQ(one.edge_curve, two.edge_curve);
  }
}

}  // namespace
}  // namespace sd::garment
