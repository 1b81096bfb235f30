#pragma once
// Where a meshed garment lies inside the body before the drape: its vertices, and the middle
// of its quads and of their edges (a quad whose corners sit on the offset surface can still cut
// through a knee or an elbow that bulges between them), deeper than a tolerance below the
// body's surface. The simulator pushes such a start out (at most 1 m/s, docs/collision.md), so
// the drape does not fail, but the designer's sketch is not what hangs: the quality gate names
// the panel and the place.

#include <Eigen/Core>
#include <vector>

#include "garment/body_surface.hpp"
#include "garment/garment_mesh.hpp"

namespace sd::garment {

struct PanelInsideBody {
  int panel = -1;        // index into Garment::panels
  int quads = 0;         // quads with a corner, an edge middle or the centre inside the body
  int vertices = 0;      // of them, mesh vertices inside
  double deepest = 0.0;  // m below the body's surface
  Eigen::Vector3d where = Eigen::Vector3d::Zero();  // m, the deepest sample
};

// Panels of `garment` with a sample deeper than `tolerance` (m) inside `body`, by panel index.
std::vector<PanelInsideBody> find_panels_inside_body(const Garment& garment,
                                                     const BodySurface& body, double tolerance);

}  // namespace sd::garment
