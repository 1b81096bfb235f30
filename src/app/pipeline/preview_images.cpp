#include "src/app/pipeline/preview_images.hpp"

#include <fmt/format.h>

#include <map>

#include "src/render/previews.hpp"

namespace sd::app {
namespace {

render::Scene preview_scene(const meshing::TriMesh* body, const PreviewCloth& cloth,
                            bool wireframe) {
  render::Scene scene;
  if (body != nullptr) {
    scene = render::cloth_over_body_scene(*body, cloth.mesh, cloth.face_panel);
  } else {
    render::SceneMesh& c = scene.meshes.emplace_back();
    c.mesh = cloth.mesh;
    c.role = render::MeshRole::kCloth;
    c.face_colours = render::panel_colours(
        cloth.face_panel.size() ? cloth.face_panel : Eigen::VectorXi::Zero(cloth.mesh.face_count()),
        cloth.mesh.faces);
  }
  if (wireframe) {
    render::Wireframe wire;
    wire.edges = cloth.wire_edges;
    if (cloth.face_levels.size() == cloth.mesh.face_count() && cloth.face_levels.size() > 0) {
      wire.face_values = cloth.face_levels;
      wire.colour_map = render::ColourMap::kLevels;
    }
    scene.meshes.back().wireframe = wire;
  }
  if (cloth.marker.face_count() > 0) {
    render::SceneMesh& marker = scene.meshes.emplace_back();
    marker.mesh = cloth.marker;
    marker.role = render::MeshRole::kCloth;
    marker.colour = marker.back_colour = {0.85f, 0.1f, 0.1f};
  }
  return scene;
}

}  // namespace

std::vector<std::string> stage_preview_images(const std::vector<scene::ImageSpec>& images,
                                              bool default_wireframe, const meshing::TriMesh* body,
                                              const PreviewCloth& cloth, const std::string& prefix,
                                              const std::filesystem::path& dir,
                                              StagedOutputs& outputs) {
  if (images.empty()) return {};
  render::Renderer renderer;
  return stage_preview_images(renderer, images, default_wireframe, body, cloth, prefix, dir,
                              outputs);
}

std::vector<std::string> stage_preview_images(render::Renderer& renderer,
                                              const std::vector<scene::ImageSpec>& images,
                                              bool default_wireframe, const meshing::TriMesh* body,
                                              const PreviewCloth& cloth, const std::string& prefix,
                                              const std::filesystem::path& dir,
                                              StagedOutputs& outputs) {
  std::vector<std::string> files;
  std::map<std::string, int> used_names;
  for (const scene::ImageSpec& spec : images) {
    const render::Scene scene =
        preview_scene(body, cloth, spec.wireframe.value_or(default_wireframe));
    const render::ImageSize size{spec.width, spec.height};
    render::Camera camera;
    std::string name;
    if (spec.view == "camera") {
      camera.eye = spec.camera.eye;
      camera.target = spec.camera.target;
      camera.up = spec.camera.up;
      camera.fov_y_deg = spec.camera.fov_degrees;
      name = "camera";
    } else {
      name = spec.view;
      camera = render::frame_view(render::parse_view_name(name), render::scene_bounds(scene),
                                  size.aspect());
    }
    const int n = used_names[name]++;
    const std::string file = n == 0 ? fmt::format("{}-{}.png", prefix, name)
                                    : fmt::format("{}-{}-{}.png", prefix, name, n + 1);
    outputs.stage(dir / file, render::encode_png(renderer.render(scene, camera, size)));
    files.push_back(file);
  }
  return files;
}

}  // namespace sd::app
