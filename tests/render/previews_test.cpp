#include "src/render/previews.hpp"

#include <gtest/gtest.h>

#include "tests/render/test_scenes.hpp"

namespace sd::render {
namespace {

// (n+1)^2 vertices of an n by n grid over [0,1]^2 mapped by `place(u, v)`.
template <class Place>
void grid(int n, Place place, Eigen::MatrixX3d& vertices, Eigen::MatrixX4i& quads) {
  vertices.resize((n + 1) * (n + 1), 3);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      vertices.row(j * (n + 1) + i) = place(double(i) / n, double(j) / n).transpose();
  quads.resize(n * n, 4);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i;
      quads.row(j * n + i) << a, a + 1, a + n + 2, a + n + 1;
    }
}

// Runs of dark pixels (lines crossed) along a row or column of the image. A 1.2 px line may
// straddle two pixels at ~50% coverage each: halfway between the fill (~190) and the edge
// colour (~26) is ~110, so "dark" is anything clearly below the fill.
int dark_runs(const Image& image, bool along_row, int index) {
  int runs = 0;
  bool in_run = false;
  const int count = along_row ? image.width : image.height;
  for (int k = 0; k < count; ++k) {
    const std::uint8_t* p = along_row ? image.pixel(k, index) : image.pixel(index, k);
    const bool dark = p[0] + p[1] + p[2] < 3 * 160;
    runs += dark && !in_run;
    in_run = dark;
  }
  return runs;
}

class PreviewsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { renderer_ = new Renderer(); }
  static void TearDownTestSuite() { delete renderer_; }
  static Renderer& renderer() { return *renderer_; }

 private:
  static inline Renderer* renderer_ = nullptr;
};

// A 4 by 4 patch lying flat (facing +Y) seen from above: lines through the middle of the
// image cross exactly the 5 quad edges of each direction, and no diagonal.
TEST_F(PreviewsTest, FlatPatchShowsItsQuadEdges) {
  Eigen::MatrixX3d v;
  Eigen::MatrixX4i q;
  // Quads (0, 1, n+2, n+1) run counter-clockwise seen from +Y when u goes to +X and v to -Z.
  grid(
      4, [](double u, double w) { return Eigen::Vector3d(u, 0.3, -w); }, v, q);
  const Image image = render_quad_patch(renderer(), v, q, {200, 200});
  // Through quad centres (rows/columns at 1/8, 3/8, ... of the patch) so no horizontal edge is
  // crossed along a row; the patch fills the framed square, centred.
  for (int k : {-1, 1}) {
    const int centre = 100 + k * 11;  // a little off the middle edge line
    EXPECT_EQ(dark_runs(image, true, centre), 5) << "row " << centre;
    EXPECT_EQ(dark_runs(image, false, centre), 5) << "column " << centre;
  }
  // Background stays white outside the patch.
  EXPECT_EQ(image.pixel(1, 1)[0], 255);
}

// A patch in the XY plane facing +Z is drawn with +Y up and +X right (not mirrored).
TEST_F(PreviewsTest, PatchOrientationIsNotMirrored) {
  Eigen::MatrixX3d v;
  Eigen::MatrixX4i q;
  grid(
      2, [](double u, double w) { return Eigen::Vector3d(u, w, 0); }, v, q);
  PatchStyle style;
  style.quad_colours = Eigen::MatrixX3f::Constant(4, 3, 0.8f);
  style.quad_colours.row(3) << 0.9f, 0.1f, 0.1f;  // the quad at +X, +Y
  const Image image = render_quad_patch(renderer(), v, q, {100, 100}, style);
  const std::uint8_t* top_right = image.pixel(70, 30);
  const std::uint8_t* bottom_left = image.pixel(30, 70);
  EXPECT_GT(top_right[0], 2 * top_right[1]);
  EXPECT_LT(std::abs(bottom_left[0] - bottom_left[1]), 20);
}

TEST_F(PreviewsTest, RenderViewsGivesOneImagePerView) {
  Scene scene;
  scene.meshes.emplace_back().mesh = meshing::icosphere(0.5, 1, {0, 0.5, 0});
  const std::vector<ViewName> views{ViewName::kFront, ViewName::kLeft, ViewName::kTop};
  std::vector<size_t> done;
  const std::vector<Image> images =
      render_views(renderer(), scene, views, {48, 32}, [&](size_t i) { done.push_back(i); });
  ASSERT_EQ(images.size(), 3u);
  for (const Image& image : images) EXPECT_EQ(image.size(), (ImageSize{48, 32}));
  EXPECT_EQ(done, (std::vector<size_t>{0, 1, 2}));
}

TEST_F(PreviewsTest, ClothSceneChecksPanelIds) {
  const meshing::TriMesh body = test::box_mesh({0, 0, 0}, {1, 2, 1});
  const meshing::TriMesh cloth = test::box_mesh({-0.1, 1, -0.1}, {1.1, 1.5, 1.1});
  EXPECT_THROW(cloth_over_body_scene(body, cloth, Eigen::VectorXi::Zero(5)), std::invalid_argument);
  const Scene scene = cloth_over_body_scene(body, cloth, Eigen::VectorXi::LinSpaced(12, 0, 11));
  ASSERT_EQ(scene.meshes.size(), 2u);
  EXPECT_EQ(scene.meshes[1].role, MeshRole::kCloth);
  EXPECT_EQ(scene.meshes[1].face_colours.rows(), 12);
}

}  // namespace
}  // namespace sd::render
