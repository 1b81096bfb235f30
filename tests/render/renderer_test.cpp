// Real OSMesa renders checked against independent facts: a CPU rasterisation of the same
// triangles, colours chosen per side, shadows on and off, edges drawn or not, goldens.

#include "src/render/renderer.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "garment/body.hpp"
#include "src/render/previews.hpp"
#include "tests/render/test_scenes.hpp"

namespace sd::render {
namespace {

const Eigen::Vector3f kBlack = Eigen::Vector3f::Zero();

class RendererTest : public ::testing::Test {
 protected:
  // One context for the whole suite, as in batch runs (also checks that it can be reused).
  static void SetUpTestSuite() {
    renderer_ = new Renderer();
    body_ = new meshing::TriMesh(garment::load_body("builtin").mesh);
  }
  static void TearDownTestSuite() {
    delete renderer_;
    delete body_;
  }
  static Renderer& renderer() { return *renderer_; }
  static const meshing::TriMesh& body() { return *body_; }

  // A mesh alone on black: no floor, no shadows.
  static Scene silhouette_scene(const meshing::TriMesh& mesh) {
    Scene scene;
    scene.ground = false;
    scene.shadows = false;
    scene.background = kBlack;
    scene.meshes.emplace_back().mesh = mesh;
    return scene;
  }

 private:
  static inline Renderer* renderer_ = nullptr;
  static inline meshing::TriMesh* body_ = nullptr;
};

TEST_F(RendererTest, CreatesACoreProfileContext) {
  EXPECT_EQ(renderer().gl_version().rfind("4.", 0), 0u) << renderer().gl_version();
  EXPECT_NE(renderer().gl_version().find("Core"), std::string::npos) << renderer().gl_version();
  EXPECT_FALSE(renderer().gl_renderer().empty());
}

// The covered pixels must be exactly those whose centre falls in a projected triangle, except
// within one pixel of the silhouette, where multisampling blends and rasterisation tie rules
// may differ from a centre test.
void expect_silhouette_matches(Renderer& renderer, const meshing::TriMesh& mesh,
                               const Camera& camera, ImageSize size, double min_fraction,
                               const std::string& label) {
  SCOPED_TRACE(label);
  Scene scene;
  scene.ground = false;
  scene.shadows = false;
  scene.background = kBlack;
  scene.meshes.emplace_back().mesh = mesh;
  const Image image = renderer.render(scene, camera, size);
  const std::vector<unsigned char> expected = test::cpu_silhouette(mesh, camera, size);
  const std::vector<unsigned char> band = test::mask_boundary(expected, size.width, size.height);
  long covered = 0, expected_covered = 0, band_pixels = 0, mismatches_outside_band = 0;
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x) {
      const size_t i = static_cast<size_t>(y) * size.width + x;
      const std::uint8_t* p = image.pixel(x, y);
      const bool gpu = p[0] + p[1] + p[2] > 0;
      covered += gpu;
      expected_covered += expected[i];
      band_pixels += band[i];
      if (!band[i] && gpu != static_cast<bool>(expected[i])) ++mismatches_outside_band;
    }
  const double total = static_cast<double>(size.width) * size.height;
  EXPECT_GT(expected_covered / total, min_fraction);  // the framing shows the object large
  EXPECT_EQ(mismatches_outside_band, 0);
  EXPECT_LE(std::abs(covered - expected_covered), band_pixels / 2 + 1)
      << "covered " << covered / total << " expected " << expected_covered / total;
}

TEST_F(RendererTest, BodySilhouetteMatchesCpuProjection) {
  const ImageSize size{160, 240};
  const meshing::BoundingBox box = meshing::bounding_box(body());
  // A standing figure framed in a 2:3 image: its height spans ~88% of the image height and
  // its arms ~40% of the width; a body fills roughly a fifth of its framed box.
  for (ViewName v : {ViewName::kFront, ViewName::kThreeQuarter, ViewName::kLeft}) {
    const Camera camera = frame_view(v, box, size.aspect());
    expect_silhouette_matches(renderer(), body(), camera, size, v == ViewName::kLeft ? 0.05 : 0.08,
                              "body " + view_name(v));
  }
}

TEST_F(RendererTest, SyntheticSilhouettesMatchCpuProjection) {
  // An L of two boxes (not mirror-symmetric, so a flipped image would fail) and a sphere.
  const meshing::TriMesh ell = test::merge({test::box_mesh({0, 0, 0}, {1, 0.25, 0.25}),
                                            test::box_mesh({0, 0.25, 0}, {0.25, 0.8, 0.25})});
  const meshing::TriMesh sphere = meshing::icosphere(0.4, 3, {0.2, 0.3, -0.1});
  for (ViewName v : {ViewName::kFront, ViewName::kTop, ViewName::kRight, ViewName::kThreeQuarter}) {
    const ImageSize size{200, 150};
    expect_silhouette_matches(renderer(), ell,
                              frame_view(v, meshing::bounding_box(ell), size.aspect()), size, 0.1,
                              "ell " + view_name(v));
    expect_silhouette_matches(renderer(), sphere,
                              frame_view(v, meshing::bounding_box(sphere), size.aspect()), size,
                              0.2, "sphere " + view_name(v));
  }
  // An explicit camera off the axes, with a narrow field of view.
  Camera c;
  c.eye = {2.0, 1.5, 3.0};
  c.target = {0.3, 0.3, 0.1};
  c.fov_y_deg = 20;
  expect_silhouette_matches(renderer(), ell, c, {120, 120}, 0.05, "ell explicit");
}

TEST_F(RendererTest, FrontCameraSeesThePlusZSide) {
  // A box whose +Z faces are red and -Z faces blue (rows 2-3 and 0-1 of box_mesh).
  Scene scene = silhouette_scene(test::box_mesh({-0.5, 0, -0.5}, {0.5, 1, 0.5}));
  SceneMesh& m = scene.meshes[0];
  m.face_colours = Eigen::MatrixX3f::Constant(12, 3, 0.5f);
  m.face_colours.topRows(2).rowwise() = Eigen::RowVector3f(0.1f, 0.1f, 0.9f);
  m.face_colours.middleRows(2, 2).rowwise() = Eigen::RowVector3f(0.9f, 0.1f, 0.1f);
  const ImageSize size{64, 64};
  const PreparedScene prepared = renderer().prepare(scene);
  const Image front =
      renderer().render(prepared, frame_view(ViewName::kFront, prepared.bounds(), 1), size);
  const Image back =
      renderer().render(prepared, frame_view(ViewName::kBack, prepared.bounds(), 1), size);
  const std::uint8_t* f = front.pixel(32, 36);
  const std::uint8_t* b = back.pixel(32, 36);
  EXPECT_GT(f[0], 2 * f[2]) << "front view should show the red +Z face";
  EXPECT_GT(b[2], 2 * b[0]) << "back view should show the blue -Z face";
}

TEST_F(RendererTest, FrontAndBackOfTheBodyDiffer) {
  Scene scene;
  scene.meshes.emplace_back().mesh = body();
  const ImageSize size{160, 240};
  const PreparedScene prepared = renderer().prepare(scene);
  const Image front = renderer().render(
      prepared, frame_view(ViewName::kFront, prepared.bounds(), size.aspect()), size);
  const Image back = renderer().render(
      prepared, frame_view(ViewName::kBack, prepared.bounds(), size.aspect()), size);
  // Compare the front with the mirrored back: the figure is left-right symmetric, so the
  // silhouettes nearly coincide and what differs is the face, chest and feet against the back
  // of the head, shoulder blades and heels.
  long differing = 0, inside = 0;
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x) {
      const std::uint8_t* f = front.pixel(x, y);
      const std::uint8_t* b = back.pixel(size.width - 1 - x, y);
      int d = 0;
      for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(f[c] - b[c]));
      differing += d > 12;
      inside += std::abs(f[0] - static_cast<int>(scene.background.x() * 255)) > 12;
    }
  EXPECT_GT(differing, 500) << "of " << inside << " non-background pixels";
}

TEST_F(RendererTest, ShadowDarkensTheGroundUnderTheBody) {
  const ImageSize size{160, 240};
  Scene lit;
  lit.meshes.emplace_back().mesh = body();
  Scene unshadowed = lit;
  unshadowed.shadows = false;
  for (ViewName v : {ViewName::kFront, ViewName::kThreeQuarter, ViewName::kTop}) {
    SCOPED_TRACE(view_name(v));
    const Camera camera = frame_view(v, meshing::bounding_box(body()), size.aspect());
    const Image with = renderer().render(lit, camera, size);
    const Image without = renderer().render(unshadowed, camera, size);
    // Floor pixels: away from the body's silhouette (and its one-pixel band).
    const std::vector<unsigned char> silhouette = test::cpu_silhouette(body(), camera, size);
    const std::vector<unsigned char> band =
        test::mask_boundary(silhouette, size.width, size.height);
    long darker = 0, brighter = 0;
    double centroid_x = 0;
    for (int y = 0; y < size.height; ++y)
      for (int x = 0; x < size.width; ++x) {
        const size_t i = static_cast<size_t>(y) * size.width + x;
        if (silhouette[i] || band[i]) continue;
        const double l0 = test::luminance(without, x, y), l1 = test::luminance(with, x, y);
        brighter += l1 > l0 + 1;
        if (l1 < 0.85 * l0) {
          ++darker;
          centroid_x += x;
        }
      }
    // Shadows only take light away.
    EXPECT_EQ(brighter, 0);
    // The body's shadow is ~1.5 m long (1.75 m at 50° elevation) and ~0.3 m wide; even
    // partly hidden behind the body it covers well over 1% of a framed view.
    EXPECT_GT(darker, static_cast<long>(0.01 * size.width * size.height));
    // The key light is to the camera's left, so the shadow falls to the right in the image.
    if (darker > 0 && v != ViewName::kTop) {
      EXPECT_GT(centroid_x / darker, size.width / 2.0);
    }
  }
}

// A flat 4 by 4 grid of quads in the XY plane (1 m square, facing +Z).
struct Grid {
  Eigen::MatrixX3d vertices;
  Eigen::MatrixX4i quads;
};
Grid quad_grid(int n) {
  Grid g;
  g.vertices.resize((n + 1) * (n + 1), 3);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) g.vertices.row(j * (n + 1) + i) << double(i) / n, double(j) / n, 0;
  g.quads.resize(n * n, 4);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i;
      g.quads.row(j * n + i) << a, a + 1, a + n + 2, a + n + 1;
    }
  return g;
}

TEST_F(RendererTest, WireframeDrawsExactlyTheGivenEdgesInTheirLevelColours) {
  const int n = 4;
  const Grid grid = quad_grid(n);
  Scene plain = silhouette_scene({});
  plain.background = {1, 1, 1};
  SceneMesh& m = plain.meshes[0];
  m.mesh.vertices = grid.vertices;
  m.mesh.faces = triangulate_quads(grid.quads);
  m.role = MeshRole::kCloth;
  m.colour = {0.85f, 0.85f, 0.85f};
  Scene wired = plain;
  Wireframe w;
  w.edges = quad_edges(grid.quads);
  // Level of each triangle = 4 + its quad's row (levels 4..7), shown with the level map.
  w.face_values.resize(m.mesh.face_count());
  for (Eigen::Index t = 0; t < w.face_values.size(); ++t) w.face_values[t] = 4 + (t / 2) / n;
  w.colour_map = ColourMap::kLevels;
  w.width_px = 3;
  wired.meshes[0].wireframe = w;

  Camera camera;
  camera.eye = {0.5, 0.5, 2.5};
  camera.target = {0.5, 0.5, 0};
  camera.fov_y_deg = 30;
  const ImageSize size{200, 200};
  const Image a = renderer().render(plain, camera, size);
  const Image b = renderer().render(wired, camera, size);
  const auto pixel_at = [&](const Eigen::Vector3d& p) {
    Eigen::Vector2d px = Eigen::Vector2d::Zero();
    EXPECT_TRUE(test::project(camera, p, size, px));
    return Eigen::Vector2i(static_cast<int>(px.x()), static_cast<int>(px.y()));
  };
  for (Eigen::Index e = 0; e < w.edges.rows(); ++e) {
    const Eigen::Vector3d mid =
        0.5 * (grid.vertices.row(w.edges(e, 0)) + grid.vertices.row(w.edges(e, 1))).transpose();
    const Eigen::Vector2i px = pixel_at(mid);
    EXPECT_GT(test::channel_difference(a, b, px.x(), px.y()), 40) << "edge " << e;
    // Vertical edges inside row r have level 4 + r; the line is 3 px wide, so its centre
    // pixel is fully covered and shows the map's colour (lines are unlit).
    const bool vertical =
        std::abs(grid.vertices(w.edges(e, 0), 0) - grid.vertices(w.edges(e, 1), 0)) < 1e-9;
    if (vertical) {
      const int row = static_cast<int>(mid.y() * n);
      const Eigen::Vector3f expected = colour_map(ColourMap::kLevels, row) * 255.0f;
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(b.pixel(px.x(), px.y())[c], expected[c], 2.0)
            << "edge " << e << " channel " << c;
    }
  }
  // The triangulation's diagonals are not edges: quad centres and points along the diagonals
  // are untouched.
  for (Eigen::Index q = 0; q < grid.quads.rows(); ++q)
    for (double s : {0.3, 0.5, 0.7}) {
      const Eigen::Vector3d p =
          ((1 - s) * grid.vertices.row(grid.quads(q, 0)) + s * grid.vertices.row(grid.quads(q, 2)))
              .transpose();
      const Eigen::Vector2i px = pixel_at(p);
      EXPECT_LE(test::channel_difference(a, b, px.x(), px.y()), 1) << "quad " << q << " at " << s;
    }
}

TEST_F(RendererTest, ClothIsLitOnBothSidesWithItsBackColour) {
  Scene scene = silhouette_scene({});
  SceneMesh& m = scene.meshes[0];
  Grid g = quad_grid(1);
  m.mesh.vertices = g.vertices;
  m.mesh.faces = triangulate_quads(g.quads);
  m.colour = {0.9f, 0.15f, 0.1f};
  m.back_colour = {0.1f, 0.2f, 0.9f};
  const ImageSize size{40, 40};
  Camera front;
  front.eye = {0.5, 0.5, 3};
  front.target = {0.5, 0.5, 0};
  Camera back = front;
  back.eye.z() = -3;
  for (MeshRole role : {MeshRole::kCloth, MeshRole::kBody}) {
    m.role = role;
    const Image f = renderer().render(scene, front, size);
    const Image b = renderer().render(scene, back, size);
    EXPECT_GT(f.pixel(20, 20)[0], 2 * f.pixel(20, 20)[2]);
    if (role == MeshRole::kCloth) {
      EXPECT_GT(b.pixel(20, 20)[2], 2 * b.pixel(20, 20)[0]) << "cloth back face shows back colour";
      // Two-sided lighting: the back is lit as brightly as a front face of its colour would be.
      EXPECT_GT(b.pixel(20, 20)[2], 120);
    } else {
      EXPECT_GT(b.pixel(20, 20)[0], 2 * b.pixel(20, 20)[2]) << "a body has one colour";
    }
  }
}

// Pixels strictly between background and the object's flat colour.
long partial_pixels(const Image& image) {
  long count = 0;
  const int full = image.pixel(image.width / 2, image.height / 2)[0];
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const int v = image.pixel(x, y)[0];
      count += v > 0.1 * full && v < 0.9 * full;
    }
  return count;
}

TEST_F(RendererTest, AntialiasingBlendsEdgePixels) {
  // A flat quad facing the camera, turned 20° in its plane so its edges are slanted: with one
  // light setup and no shadows its colour is uniform, so partial values come only from
  // coverage.
  Scene scene = silhouette_scene({});
  SceneMesh& m = scene.meshes[0];
  Grid g = quad_grid(1);
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.35, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  m.mesh.vertices = g.vertices * turn.transpose();
  m.mesh.faces = triangulate_quads(g.quads);
  m.colour = {0.8f, 0.8f, 0.8f};
  m.role = MeshRole::kCloth;
  Camera camera;
  camera.eye = {0.2, 0.7, 3};
  camera.target = {0.2, 0.7, 0};
  camera.fov_y_deg = 35;
  const ImageSize size{120, 120};
  Renderer aliased({.antialiasing = Antialiasing::kNone});
  Renderer supersampled({.antialiasing = Antialiasing::kSupersample2});
  const Image none = aliased.render(scene, camera, size);
  const Image msaa = renderer().render(scene, camera, size);
  const Image ssaa = supersampled.render(scene, camera, size);
  EXPECT_EQ(partial_pixels(none), 0);
  // The quad's perimeter is ~4 * 65 px; most edge pixels are partly covered.
  EXPECT_GT(partial_pixels(msaa), 100);
  EXPECT_GT(partial_pixels(ssaa), 100);
}

TEST_F(RendererTest, RenderingIsDeterministic) {
  Scene scene;
  scene.meshes.emplace_back().mesh = body();
  const PreparedScene prepared = renderer().prepare(scene);
  const Camera camera = frame_view(ViewName::kThreeQuarter, prepared.bounds(), 0.75);
  const Image a = renderer().render(prepared, camera, {90, 120});
  const Image c = renderer().render(prepared, camera, {60, 80});  // size change in between
  const Image b = renderer().render(prepared, camera, {90, 120});
  EXPECT_EQ(a.rgba, b.rgba);
  EXPECT_EQ(c.width, 60);
  EXPECT_EQ(c.height, 80);
}

TEST_F(RendererTest, RejectsBadRequests) {
  Scene scene;
  scene.meshes.emplace_back().mesh = test::box_mesh({0, 0, 0}, {1, 1, 1});
  Camera camera;
  EXPECT_THROW(renderer().render(scene, camera, {0, 10}), std::invalid_argument);
  EXPECT_THROW(renderer().render(scene, camera, {10, kMaxImageSide + 1}), std::invalid_argument);
  camera.target = camera.eye;
  EXPECT_THROW(renderer().render(scene, camera, {10, 10}), ViewError);
  scene.meshes[0].mesh.faces(0, 0) = 99;
  EXPECT_THROW(renderer().prepare(scene), std::invalid_argument);
  // A scene from one renderer cannot be drawn by another.
  Renderer other;
  scene.meshes[0].mesh = test::box_mesh({0, 0, 0}, {1, 1, 1});
  const PreparedScene prepared = other.prepare(scene);
  EXPECT_THROW(renderer().render(prepared, Camera{}, {10, 10}), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// Goldens: small reference images in tests/render/golden/. Regenerate after an intended change
// with SD_UPDATE_GOLDENS=1 (then look at them and commit). The tolerance allows Mesa versions
// to round differently: mean difference under 1.5 levels and under 0.5% of pixels off by more
// than 24 levels.

void compare_with_golden(const Image& image, const std::string& name) {
  const std::filesystem::path golden =
      std::filesystem::path(SD_SOURCE_DIR) / "tests/render/golden" / (name + ".png");
  const char* update = std::getenv("SD_UPDATE_GOLDENS");
  if (update != nullptr && std::string(update) == "1") {
    std::ofstream(golden, std::ios::binary) << encode_png(image);
    std::cout << "updated golden " << golden << "\n";
    return;
  }
  std::ifstream in(golden, std::ios::binary);
  ASSERT_TRUE(in) << "missing golden " << golden << ": run with SD_UPDATE_GOLDENS=1";
  std::stringstream bytes;
  bytes << in.rdbuf();
  const Image expected = decode_png(bytes.str());
  ASSERT_EQ(expected.size(), image.size());
  double total = 0;
  long large = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const int d = test::channel_difference(image, expected, x, y);
      total += d;
      large += d > 24;
    }
  const double pixels = static_cast<double>(image.width) * image.height;
  const bool ok = total / pixels < 1.5 && large < 0.005 * pixels;
  if (!ok) {
    const std::filesystem::path actual =
        std::filesystem::path(SD_BINARY_DIR) / ("golden_actual_" + name + ".png");
    std::ofstream(actual, std::ios::binary) << encode_png(image);
    ADD_FAILURE() << name << ": mean difference " << total / pixels << ", " << large
                  << " pixels off by more than 24; the render is in " << actual;
  }
}

TEST_F(RendererTest, GoldenBodyThreeQuarter) {
  Scene scene;
  scene.meshes.emplace_back().mesh = body();
  const ImageSize size{160, 240};
  const Camera camera = frame_view(ViewName::kThreeQuarter, scene_bounds(scene), size.aspect());
  compare_with_golden(renderer().render(scene, camera, size), "body_three_quarter");
}

// A two-panel skirt (a truncated cone around the hips, front and back halves) over the body,
// with its quad edges coloured by level: panel colours, two-sided cloth and the overlay.
TEST_F(RendererTest, GoldenSkirtOverBody) {
  const meshing::BoundingBox box = meshing::bounding_box(body());
  const int rings = 6, segments = 32;
  const double top = 0.58 * box.max.y(), bottom = 0.38 * box.max.y();
  meshing::TriMesh skirt;
  skirt.vertices.resize(rings * segments, 3);
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const double t = double(r) / (rings - 1), phi = 2 * std::numbers::pi * s / segments;
      const double radius = 0.19 + 0.12 * t;
      skirt.vertices.row(r * segments + s) << radius * std::cos(phi), top + t * (bottom - top),
          radius * std::sin(phi);
    }
  Eigen::MatrixX4i quads((rings - 1) * segments, 4);
  for (int r = 0; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s)
      // Counter-clockwise seen from outside: around first, then down.
      quads.row(r * segments + s) << r * segments + s, r * segments + (s + 1) % segments,
          (r + 1) * segments + (s + 1) % segments, (r + 1) * segments + s;
  skirt.faces = triangulate_quads(quads);
  Eigen::VectorXi panels(skirt.face_count());
  for (Eigen::Index t = 0; t < panels.size(); ++t)
    panels[t] = ((t / 2) % segments) < segments / 2 ? 1 : 0;  // z > 0 half is panel 1
  Scene scene = cloth_over_body_scene(body(), skirt, panels);
  Wireframe w;
  w.edges = quad_edges(quads);
  w.face_values.resize(skirt.face_count());
  for (Eigen::Index t = 0; t < w.face_values.size(); ++t)
    w.face_values[t] = 4 + (t / 2) / segments % 5;
  w.colour_map = ColourMap::kLevels;
  scene.meshes[1].wireframe = w;
  const ImageSize size{160, 240};
  const Camera camera = frame_view(ViewName::kThreeQuarter, scene_bounds(scene), size.aspect());
  compare_with_golden(renderer().render(scene, camera, size), "skirt_over_body");
}

}  // namespace
}  // namespace sd::render
