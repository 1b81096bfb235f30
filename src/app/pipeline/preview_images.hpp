#pragma once
// The PNG previews a sketch file asks for (`output.images`), shared by `mesh` and `run`: the
// cloth in one colour per panel, over the body when there is one, optionally with its edges.

#include <filesystem>
#include <string>
#include <vector>

#include "meshing/tri_mesh.hpp"
#include "scene/sketch_file.hpp"
#include "src/app/pipeline/atomic_file.hpp"
#include "src/render/renderer.hpp"

namespace sd::app {

struct PreviewCloth {
  meshing::TriMesh mesh;        // triangles to draw
  Eigen::VectorXi face_panel;   // #F panel (colour) index, or empty for one colour
  Eigen::MatrixX2i wire_edges;  // #E by 2 edges drawn when a wireframe is asked for
  Eigen::VectorXd face_levels;  // optional #F values (4-8 levels) colouring the wireframe
  meshing::TriMesh marker;      // optional, drawn in red over the cloth (where a drape failed)
};

// Renders each image of `images` (one GL context for all) and stages it as
// `<prefix>-<view>.png` in `dir` (a repeated view gets `-2`, `-3`, ...). `body` may be null.
// Returns the file names staged.
std::vector<std::string> stage_preview_images(const std::vector<scene::ImageSpec>& images,
                                              bool default_wireframe, const meshing::TriMesh* body,
                                              const PreviewCloth& cloth, const std::string& prefix,
                                              const std::filesystem::path& dir,
                                              StagedOutputs& outputs);
// The same with a renderer the caller keeps (`run`'s images and its PNG sequence share one
// context: a context per call cost its shaders' compilation, and memory, each time).
std::vector<std::string> stage_preview_images(render::Renderer& renderer,
                                              const std::vector<scene::ImageSpec>& images,
                                              bool default_wireframe, const meshing::TriMesh* body,
                                              const PreviewCloth& cloth, const std::string& prefix,
                                              const std::filesystem::path& dir,
                                              StagedOutputs& outputs);

}  // namespace sd::app
