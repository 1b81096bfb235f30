#pragma once
// The garment stage `mesh` and `run` share (and `batch`, which runs them): a sketch's garment as
// stitched quads and their checked 4-8 mesh, or an imported triangle garment as its 4-8 mesh.
// `mesh` writes what this stage makes; `run` builds the cloth it drapes from it (cloth_scene).

#include <string>
#include <vector>

#include "garment/body.hpp"
#include "garment/garment_mesh.hpp"
#include "meshing/mesh48.hpp"
#include "meshing/tri_mesh.hpp"
#include "scene/sketch_file.hpp"

namespace sd::app {

// A sketch's panels meshed on its body and stitched.
struct MeshedGarment {
  garment::Body body;
  garment::Garment garment;
  // Groups: a panel's own id, or its join's (a join's panels share one group).
  std::vector<std::string> group_names;
  std::vector<int> panel_group;  // per panel of `garment`: index into group_names
  meshing::Mesh48 mesh48;        // the garment's quads as a 4-8 mesh, validated
  double body_ms = 0;            // loading the body and its search structure
  double meshing_ms = 0;         // build_garment
};

// The garment's quads as a checked 4-8 mesh. A quad of no area (corners in a line or on one
// spot: the simulator cannot use it) fails as garment::SketchError at its panel's path, naming
// the place and the nearest body landmark, after logging the quality gate's warnings.
meshing::Mesh48 garment_mesh48(const scene::Sketch& sketch, const garment::Body& body,
                               const garment::Garment& g);

// Loads the body and builds the garment. Throws garment::SketchError for what the designer can
// fix, std::runtime_error when the 4-8 mesh fails its check (an internal error).
MeshedGarment mesh_garment(const scene::Sketch& sketch);

// A sketch's "garment_mesh": the triangles as read and their 4-8 mesh by the sqrt3 conversion.
struct ImportedGarment {
  meshing::TriMesh triangles;  // the file's faces, polygons fanned into triangles
  long file_faces = 0;         // the faces the file writes (a quad is one)
  meshing::Mesh48 mesh48;      // validated
  meshing::Sqrt3Stats stats;
};

// Throws garment::SketchError at /garment_mesh when the file cannot be read or the triangles
// cannot become a 4-8 mesh.
ImportedGarment import_garment(const scene::Sketch& sketch);

}  // namespace sd::app
