#include "src/render/previews.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <stdexcept>

namespace sd::render {

std::vector<Image> render_views(Renderer& renderer, const Scene& scene,
                                std::span<const ViewName> views, ImageSize size,
                                const std::function<void(size_t)>& on_view_done) {
  const PreparedScene prepared = renderer.prepare(scene);
  std::vector<Image> images;
  images.reserve(views.size());
  for (size_t i = 0; i < views.size(); ++i) {
    const Camera camera = frame_view(views[i], prepared.bounds(), size.aspect());
    images.push_back(renderer.render(prepared, camera, size));
    if (on_view_done) on_view_done(i);
  }
  return images;
}

Scene cloth_over_body_scene(const meshing::TriMesh& body, const meshing::TriMesh& cloth,
                            const Eigen::VectorXi& panel_ids) {
  if (panel_ids.size() != 0 && panel_ids.size() != cloth.face_count())
    throw std::invalid_argument(fmt::format("{} panel ids for a cloth of {} triangles",
                                            panel_ids.size(), cloth.face_count()));
  Scene scene;
  SceneMesh& b = scene.meshes.emplace_back();
  b.mesh = body;
  b.role = MeshRole::kBody;
  SceneMesh& c = scene.meshes.emplace_back();
  c.mesh = cloth;
  c.role = MeshRole::kCloth;
  c.face_colours = panel_colours(
      panel_ids.size() ? panel_ids : Eigen::VectorXi::Zero(cloth.face_count()), cloth.faces);
  return scene;
}

Image render_quad_patch(Renderer& renderer, const Eigen::MatrixX3d& vertices,
                        const Eigen::MatrixX4i& quads, ImageSize size, const PatchStyle& style) {
  if (quads.rows() == 0) throw std::invalid_argument("the patch has no quads to draw");
  if (style.quad_colours.rows() != 0 && style.quad_colours.rows() != quads.rows())
    throw std::invalid_argument(
        fmt::format("{} quad colours for {} quads", style.quad_colours.rows(), quads.rows()));
  Scene scene;
  scene.ground = false;
  scene.shadows = false;
  scene.background = style.background;
  SceneMesh& patch = scene.meshes.emplace_back();
  patch.mesh.vertices = vertices;
  patch.mesh.faces = triangulate_quads(quads);
  patch.role = MeshRole::kCloth;
  patch.colour = style.colour;
  patch.back_colour = style.colour;  // either side of a flat patch is the same patch
  if (style.quad_colours.rows() != 0) {
    patch.face_colours.resize(2 * quads.rows(), 3);
    for (Eigen::Index q = 0; q < quads.rows(); ++q)
      patch.face_colours.row(2 * q) = patch.face_colours.row(2 * q + 1) = style.quad_colours.row(q);
  }
  Wireframe wire;
  wire.edges = quad_edges(quads);
  wire.colour = style.edge_colour;
  wire.width_px = style.edge_width_px;
  patch.wireframe = wire;
  validate_scene(scene);

  // Vector area of a quad: half the cross product of its diagonals.
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  for (Eigen::Index q = 0; q < quads.rows(); ++q)
    normal += 0.5 * (vertices.row(quads(q, 2)) - vertices.row(quads(q, 0)))
                        .cross(vertices.row(quads(q, 3)) - vertices.row(quads(q, 1)))
                        .transpose();
  Eigen::Vector3d forward =
      normal.norm() > 0 ? Eigen::Vector3d(-normal.normalized()) : Eigen::Vector3d(0, -1, 0);
  // Image up: +Y where it is not (nearly) the viewing axis, else -Z as in the `top` view.
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  if (std::abs(forward.dot(up)) > 0.99) up = -Eigen::Vector3d::UnitZ();
  const Camera camera =
      frame_direction(forward, up, meshing::bounding_box(patch.mesh), size.aspect());
  return renderer.render(scene, camera, size);
}

}  // namespace sd::render
