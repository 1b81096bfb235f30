#pragma once
// The faces of the curve network drawn on the body, for panels with "boundary": "auto". The
// network is embedded on the body's surface: at every junction the curves leaving it are ordered
// by angle in the body's tangent plane (around the outward normal), and each face is traced by
// turning, at every junction, onto the next curve clockwise from the one it arrived on, so the
// face lies on the left of each of its edges seen from outside. On a closed surface every face
// is bounded (a shirt's neck hole is a face too), so a panel picks its face with a seed point
// inside it: the face on the seed's side of the curve nearest to the seed.

#include <Eigen/Core>
#include <set>
#include <string>
#include <vector>

#include "garment/body_surface.hpp"
#include "garment/curve_network.hpp"
#include "garment/garment_request.hpp"
#include "garment/panel_loop.hpp"

namespace sd::garment {

struct NetworkFaces {
  // Loop edges of each face, counter-clockwise seen from outside (the face on the left).
  std::vector<std::vector<LoopEdge>> faces;
  // Face on the left of each half-edge: index 2·e for edge e run from `from` to `to`, 2·e + 1
  // for it run backwards.
  std::vector<int> face_left;
};

NetworkFaces trace_faces(const CurveNetwork& net, const BodySurface& body);

// The seed of an "auto" panel in world coordinates: a view point cast onto the body along its
// view ray (the first hit), or point3d as written. Throws SketchError when the ray misses.
Eigen::Vector3d seed_position(const GarmentRequest& sketch, const PanelSpec& panel,
                              const BodySurface& body);

// The loop of an "auto" panel: the face containing its seed. Throws SketchError (at the seed's
// path) when the seed lies on a curve, or the face is not one closed loop (a curve with a free
// end inside it, or curves inside it not connected to its boundary).
std::vector<LoopEdge> auto_panel_loop(const GarmentRequest& sketch, const CurveNetwork& net,
                                      const NetworkFaces& faces, const BodySurface& body,
                                      const PanelSpec& panel);

// Base ids of the curves used by the loops of mirrored "auto" panels (they need mirror copies,
// which the network only makes for curves it knows to be mirrored).
std::set<std::string> auto_panel_curves_to_mirror(const GarmentRequest& sketch,
                                                  const CurveNetwork& net, const BodySurface& body);

}  // namespace sd::garment
