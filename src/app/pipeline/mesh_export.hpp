#pragma once
// Mesh files the pipeline writes: Wavefront OBJ (with one group per panel) and binary glTF.
// Both return the file's bytes; writing them is left to StagedOutputs so nothing partial is
// ever left on disk.

#include <Eigen/Core>
#include <string>
#include <vector>

namespace sd::app {

// A polygon mesh to export: #V by 3 positions, #F by k corner indices (k = 3 or 4, counter-
// clockwise), and for each face the index of its group in `group_names` (empty: one group).
struct ExportMesh {
  Eigen::MatrixX3d vertices;
  Eigen::MatrixXi faces;
  std::vector<int> face_groups;
  std::vector<std::string> group_names;
};

// OBJ text: `o`, then per group a `g <name>` followed by its faces (1-based indices).
std::string to_obj(const ExportMesh& mesh, const std::string& object_name);

// Binary glTF 2.0 (.glb): one glTF mesh per group, each with its material colour taken from the
// renderer's panel palette as the previews colour it (render::panel_palette_slots: groups sewn
// together in different colours) so files and previews agree; smooth
// normals. Quads are split along their shorter diagonal. Throws std::runtime_error if assimp's
// exporter fails.
std::string to_glb(const ExportMesh& mesh, const std::string& object_name);

}  // namespace sd::app
