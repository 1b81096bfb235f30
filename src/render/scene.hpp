#pragma once
// What to draw, independent of where the meshes came from: meshes with a role and colours, an
// optional wireframe overlay with explicit edges, a ground plane and shadows. Colours are sRGB
// in [0, 1] (what a designer picks); lighting is computed in linear space.

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "meshing/tri_mesh.hpp"

namespace sd::render {

// How a mesh is lit.
enum class MeshRole {
  kBody,   // opaque, closed, smooth shaded, one-sided
  kCloth,  // two-sided lighting; back faces (seen from inside) get `back_colour`
};

// Maps a scalar to a colour.
enum class ColourMap {
  kViridis,  // continuous, perceptually uniform; value range [min_value, max_value] → [0, 1]
  kLevels,   // discrete: integer levels (e.g. 4-8 refinement levels) get distinct colours;
             // value v is rounded and level min_value gets the first colour
};

// sRGB colour of `t` in [0, 1] (clamped) on the continuous map, or of level index
// round(t) >= 0 on the discrete one (cycling after its 10 colours).
Eigen::Vector3f colour_map(ColourMap map, double t);

// A line overlay drawn on top of a mesh's surface (hidden lines stay hidden).
struct Wireframe {
  // #E by 2 vertex indices into the mesh's vertices. Explicit, so a quad mesh drawn as
  // triangles can show its quad edges and not the diagonals.
  Eigen::MatrixX2i edges;
  // Optional scalar per edge (#E) or per triangle of the mesh (#F); at most one non-empty.
  // A per-triangle value colours each edge with the largest value of the triangles that use it.
  Eigen::VectorXd edge_values;
  Eigen::VectorXd face_values;
  ColourMap colour_map = ColourMap::kViridis;
  // Range mapped onto the colour map; when min_value >= max_value the data's range is used.
  double min_value = 0;
  double max_value = 0;
  Eigen::Vector3f colour{0.08f, 0.08f, 0.1f};  // edges without a value
  float width_px = 1.2f;                       // line width in output pixels
};

struct SceneMesh {
  meshing::TriMesh mesh;  // metres; faces counter-clockwise seen from the front side
  MeshRole role = MeshRole::kBody;
  Eigen::Vector3f colour{0.80f, 0.74f, 0.68f};       // used when face_colours is empty
  Eigen::MatrixX3f face_colours;                     // optional, #F by 3
  Eigen::Vector3f back_colour{0.55f, 0.55f, 0.60f};  // cloth back faces
  std::optional<Wireframe> wireframe;
};

struct Scene {
  std::vector<SceneMesh> meshes;
  bool ground = true;   // a floor at the lowest point of the meshes, fading into the background
  bool shadows = true;  // soft key-light shadows on the meshes and the ground
  Eigen::Vector3f background{0.94f, 0.95f, 0.97f};
  Eigen::Vector3f ground_colour{0.86f, 0.86f, 0.85f};
};

// Per-face colours for panel ids (#F, ids >= 0) from a fixed palette of distinct fabric-like
// colours; the same id always gets the same colour. Returns #F by 3.
Eigen::MatrixX3f panel_colours(const Eigen::VectorXi& panel_ids);

// The palette's colour `slot` (taken modulo the palette's size, slot >= 0).
Eigen::Vector3f panel_palette_colour(int slot);

// A palette slot for each panel id 0 .. max(panel_ids) such that two panels sewn together (whose
// faces share an edge of `faces`: #F by k >= 3 corners in order, rows in step with `panel_ids`)
// differ while the palette lasts. Greedy, in id order: a panel takes its own slot (id modulo the
// palette's size) when no sewn neighbour coloured before it has it, else the first free slot
// after it. So a garment of up to 8 panels keeps the colours by id, and its 9th panel is not
// given the colour of the 1st when they are sewn (trial 39: skirt_front had bodice_front's
// colour, the waist seam was invisible). Deterministic; unsewn panels may share a colour.
std::vector<int> panel_palette_slots(const Eigen::VectorXi& panel_ids,
                                     const Eigen::MatrixXi& faces);

// Per-face colours (#F by 3) by panel_palette_slots: sewn panels in different colours.
Eigen::MatrixX3f panel_colours(const Eigen::VectorXi& panel_ids, const Eigen::MatrixXi& faces);

// Every edge of the triangles once, as #E by 2 (smaller index first), sorted.
Eigen::MatrixX2i triangle_edges(const meshing::TriMesh& mesh);

// Every edge of the quads once (#Q by 4 vertex indices, in order around each quad), as #E by 2.
Eigen::MatrixX2i quad_edges(const Eigen::MatrixX4i& quads);

// The triangles (0,1,2) and (0,2,3) of each quad: #2Q by 3.
Eigen::MatrixX3i triangulate_quads(const Eigen::MatrixX4i& quads);

// Per-edge values from per-triangle ones: for each edge, the largest value of the triangles
// having both its end points; NaN for an edge used by no triangle. #E.
Eigen::VectorXd edge_values_from_faces(const meshing::TriMesh& mesh, const Eigen::MatrixX2i& edges,
                                       const Eigen::VectorXd& face_values);

// Axis-aligned bounds of every mesh in the scene (the ground is not included).
meshing::BoundingBox scene_bounds(const Scene& scene);

// Checks shapes and indices (face colours #F by 3, edge indices in range, one kind of values
// with the right length, finite vertices). Throws std::invalid_argument naming the mesh.
void validate_scene(const Scene& scene);

}  // namespace sd::render
