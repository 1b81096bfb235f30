// Rectilinear layouts placed by the boundary's shape (issue 18, docs/meshing.md "Reflex vertices
// where the boundary turns"): a region whose boundary turns inwards in the middle of one side
// gets its layout's reflex vertices (valence 4 on the boundary, three quads) at those turns, not
// wherever the edge counts alone would put them.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <vector>

#include "meshing/patch_fill.hpp"
#include "meshing/quad_mesh.hpp"

namespace sd::meshing {
namespace {

// Unit-spaced points along the lattice path through `corners` (each step axis-aligned).
Eigen::MatrixX3d lattice_path(const std::vector<Eigen::Vector2i>& corners) {
  std::vector<Eigen::Vector3d> points{Eigen::Vector3d(corners[0].x(), corners[0].y(), 0)};
  for (size_t k = 1; k < corners.size(); ++k) {
    Eigen::Vector2i at = corners[k - 1];
    const Eigen::Vector2i step = (corners[k] - at).cwiseSign();
    while (at != corners[k]) {
      at += step;
      points.emplace_back(at.x(), at.y(), 0);
    }
  }
  Eigen::MatrixX3d matrix(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t r = 0; r < points.size(); ++r)
    matrix.row(static_cast<Eigen::Index>(r)) = points[r].transpose();
  return matrix;
}

// A U: the w × h rectangle less a c × d notch from its top edge, starting a from the left. Six
// sides, the notch's three edges one side, so both of its concave corners are side vertices of
// that side and the six real corners turn 6 quarter turns where a disk turns 4: a rectilinear
// layout needs two reflex vertices. Of these 200 regions, 86 are filled by one (the rest by
// other constructions); each must put both at the notch's corners. Ranked by the edge counts alone
// (most quads, then the longest shortest run), 34 of the regions were filled by a rectilinear
// layout with them elsewhere (and none with them at the notch).
TEST(RectilinearLayout, ReflexVerticesGoWhereTheSideTurnsInwards) {
  int rectilinear = 0;
  for (int w = 3; w <= 6; ++w)
    for (int h = 2; h <= 5; ++h)
      for (int a = 1; a + 1 < w; ++a)
        for (int c = 1; a + c < w; ++c)
          for (int d = 1; d < h; ++d) {
            const std::vector<Eigen::MatrixX3d> sides{
                lattice_path({{0, 0}, {w, 0}}),
                lattice_path({{w, 0}, {w, h}}),
                lattice_path({{w, h}, {a + c, h}}),
                lattice_path({{a + c, h}, {a + c, h - d}, {a, h - d}, {a, h}}),
                lattice_path({{a, h}, {0, h}}),
                lattice_path({{0, h}, {0, 0}})};
            const FilledPatch patch = fill_region(sides);
            if (patch.topology.partition != "rectilinear") continue;
            ++rectilinear;
            const Eigen::VectorXi valence = vertex_valences(patch.mesh);
            const auto& notch = patch.topology.side_vertices[3];
            EXPECT_EQ(valence(notch[static_cast<size_t>(d)]), 4)
                << w << " x " << h << " less " << c << " x " << d << " from " << a;
            EXPECT_EQ(valence(notch[static_cast<size_t>(d + c)]), 4)
                << w << " x " << h << " less " << c << " x " << d << " from " << a;
            EXPECT_EQ(patch.quality.inverted_quads, 0);
          }
  EXPECT_GE(rectilinear, 80);  // 86: the check is not vacuous
}

}  // namespace
}  // namespace sd::meshing
