#pragma once
// Ready-made previews for other modules: named views of a scene, cloth over a body, and a flat
// quad patch seen face-on with its quad edges (for `sketchdrape fill --png`).

#include <Eigen/Core>
#include <functional>
#include <span>
#include <vector>

#include "meshing/tri_mesh.hpp"
#include "src/render/camera.hpp"
#include "src/render/image.hpp"
#include "src/render/renderer.hpp"
#include "src/render/scene.hpp"

namespace sd::render {

// Renders `scene` once per view, each framed around the scene's meshes (frame_view). The scene
// is uploaded once. `on_view_done(i)` is called after view i (for progress bars).
std::vector<Image> render_views(Renderer& renderer, const Scene& scene,
                                std::span<const ViewName> views, ImageSize size,
                                const std::function<void(size_t)>& on_view_done = {});

// A body (opaque, neutral colour) and cloth over it (two-sided, one colour per panel id from
// panel_colours, panels sewn together in different colours). `panel_ids` is #F of the cloth, or
// empty for a single panel. Add a wireframe to scene.meshes[1] if wanted.
Scene cloth_over_body_scene(const meshing::TriMesh& body, const meshing::TriMesh& cloth,
                            const Eigen::VectorXi& panel_ids = {});

struct PatchStyle {
  Eigen::MatrixX3f quad_colours;  // optional #Q by 3 sRGB; else `colour`
  Eigen::Vector3f colour{0.62f, 0.76f, 0.90f};
  Eigen::Vector3f edge_colour{0.10f, 0.12f, 0.16f};
  float edge_width_px = 1.2f;
  Eigen::Vector3f background{1.0f, 1.0f, 1.0f};
};

// A quad mesh (#V by 3 vertices, #Q by 4 indices in order around each quad) drawn two-sided
// from the side its quads face (their summed vector area), with the quad edges — not the
// triangle diagonals — as wireframe. A patch in the XY plane facing +Z appears with +Y up;
// one facing +Y is seen from above with -Z up. No floor, no shadows.
Image render_quad_patch(Renderer& renderer, const Eigen::MatrixX3d& vertices,
                        const Eigen::MatrixX4i& quads, ImageSize size,
                        const PatchStyle& style = {});

}  // namespace sd::render
