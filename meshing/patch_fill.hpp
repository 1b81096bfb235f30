#pragma once
// Filling an n-sided region with a quad mesh of minimal distortion (Nasri, Sabin & Yasseen
// 2009; Yasseen et al. 2010; see docs/meshing.md): first the topology from the edge counts of
// the sides, then the geometry from the sides' 3D points (Coons interpolation, relaxation,
// optional projection).

#include <Eigen/Core>
#include <array>
#include <functional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "meshing/quad_mesh.hpp"
#include "meshing/quad_quality.hpp"

namespace sd::meshing {

// Side counts or side points that no quad mesh can fill (a zero count, an odd total, ...).
class FillError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct PatchTopology {
  QuadMesh mesh;  // positions in a 2D parameter layout (z = 0), for display
  // side i: vertex indices from corner i to corner i+1 inclusive (l_i + 1 entries)
  std::vector<std::vector<int>> side_vertices;
  // "nasri" (centre of valence n; for n = 4 a plain grid), "yasseen" (large-length partition)
  // or "shifted-corners" (a Nasri partition or a grid on a polygon whose corners were moved
  // along the boundary: some corners dropped, some side vertices promoted)
  std::string partition;
  int distortion = 0;  // Σ |valence − regular| (4 inside, 3 on a side, 2 at a corner)
  int irregular_vertices = 0;

  // Corner i is side_vertices[i].front().
  std::vector<int> corner_vertices() const;
};

// The least distorted topology this filler knows for sides with these edge counts, sides in
// counter-clockwise order. n >= 2, every count >= 1, even total (and a total of at least 4);
// otherwise throws FillError with a sentence.
PatchTopology fill_region(std::span<const int> side_counts);

struct FilledPatch;

struct FillGeometryOptions {
  // Sweeps of interior smoothing after Coons interpolation (0 keeps the Coons positions).
  int relax_iterations = 10;
  // Optional: moves an interior point onto the target surface (e.g. the body's offset surface);
  // applied after every relaxation sweep and at the end.
  std::function<Eigen::Vector3d(const Eigen::Vector3d&)> project;
  // Optional: places the interior on the target surface before the relaxation, instead of
  // `project` vertex by vertex. Given the fill's #V positions (boundary exact, interior where
  // the layout's interpolation put it), its #Q counter-clockwise quads and #V fixed flags
  // (nonzero: boundary), it moves the free positions in place. A panel wrapping a limb needs it:
  // its interpolated interior runs through the limb, where the nearest surface point can be on
  // either side (garment_mesh.cpp).
  std::function<void(std::vector<Eigen::Vector3d>&, std::span<const std::array<int, 4>>,
                     std::span<const char>)>
      place;
  // When no plan comes out clean, fill_region has two last resorts, each a full relaxation more
  // for one plan: the search again with its first plan relaxed to the end, and the best plan
  // relaxed again with the reference normals of its unguarded sweeps. Over the examples, designs
  // and reproducers they ran 57 times and gave a clean fill twice, but were a third of the
  // raglan top's meshing time. Optional: a
  // caller with its own way of mending a fill (garment/panel_fill.cpp smooths and unfolds along
  // the body) is offered the search's best patch before them; when it returns true that patch
  // is the result (without the planar placement that follows on an unprojected fill), otherwise
  // the fill goes on as without it, to the same result.
  std::function<bool(const FilledPatch&)> good_enough;
  // Optional: the unit normal of the surface the panel lies on near a boundary point (zero when
  // unknown there). The boundary's turn at each vertex, which decides where the layout puts its
  // corners and reflex vertices (docs/meshing.md, "Reflex vertices where the boundary turns"), is
  // then measured about it instead of about the loop's overall normal: seen from the front, a
  // strap running round the back of the neck turns the wrong way.
  std::function<Eigen::Vector3d(const Eigen::Vector3d&)> surface_normal;
  // With `surface_normal`: which boundary vertices are reflex or flat (a layout corner there
  // folds or is flat: the fold penalty, padding) is judged about it as well, not only the turns.
  // Off by default: about the body's normals most garments' plans change, some for the worse
  // (docs/meshing.md, "Reflex vertices where the boundary turns"); a caller tries it as a second
  // fill of a region whose first fill has flaws (garment/panel_fill.cpp, docs/meshing.md,
  // "Round 44").
  bool flags_about_surface = false;
  // When the fill has a quad whose mean side is more than twice the boundary's mean edge or
  // less than half of it, and the region has a long thin arm that widens (find_arm_cut,
  // meshing/arm_widening.hpp), the region is also filled cut across the arm, each part on its
  // own, and that fill is kept when its worst quad size is better and it folds no more quads and
  // has no new sliver (docs/meshing.md, "Round 42: an arm that widens"). A caller that makes that
  // choice itself (garment/panel_fill.cpp, with its own finishing of each part) turns it off.
  bool widen_arms = true;
};

struct FilledPatch {
  PatchTopology topology;
  QuadMesh mesh;  // 3D; same connectivity and vertex indices as topology.mesh
  QuadQuality quality;
};

// side_points[i] is (l_i + 1) by 3: the exact boundary vertices of side i, from corner i to
// corner i+1, and side_points[i].row(last) == side_points[i+1].row(0). The result's boundary
// vertices are these points (bitwise) and topology.side_vertices gives their indices, so
// panels that share a side can be stitched. Throws FillError on bad input.
FilledPatch fill_region(const std::vector<Eigen::MatrixX3d>& side_points,
                        const FillGeometryOptions& options = {});

// Sides as 3D polylines from corner to corner (each at least 2 points, consecutive sides
// sharing their end point) with the edge count of each; boundary vertices are placed along
// each polyline at equal arc-length steps.
FilledPatch fill_region(const std::vector<Eigen::MatrixX3d>& side_polylines,
                        std::span<const int> side_counts, const FillGeometryOptions& options = {});

// Boundary vertices of one side: count + 1 points at equal arc-length steps along the
// polyline (#P by 3, at least 2 points), the first and last exactly the polyline's ends.
Eigen::MatrixX3d resample_by_arc_length(const Eigen::MatrixX3d& polyline, int count);

}  // namespace sd::meshing
