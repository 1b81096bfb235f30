#pragma once
// Panels as closed loops of network edges: the boundary curves in the order the designer listed
// them, each run in the direction that closes the loop (a curve split by a T-junction may
// contribute only part of itself), oriented counter-clockwise seen from outside the body, cut
// into sides at the corners.

#include <string>
#include <vector>

#include "garment/body_surface.hpp"
#include "garment/curve_network.hpp"
#include "garment/garment_request.hpp"

namespace sd::garment {

struct LoopEdge {
  int edge = -1;        // NetworkEdge index
  bool forward = true;  // traversed from edge.from to edge.to
  int boundary = -1;    // position in the panel's boundary list (-1 for "auto" loops)
};

struct PanelLoop {
  std::string id;         // "front", or "front.mirror" for a copy
  std::string json_path;  // of the panel spec
  int spec = -1;          // index into Sketch::panels
  bool mirror_copy = false;
  int original = -1;                // PanelLoop index of the panel a copy mirrors; itself otherwise
  std::vector<LoopEdge> edges;      // loop order, starting at corner 0
  std::vector<int> side_begin;      // index into edges where side i starts (side_begin[0] = 0)
  std::vector<double> turning_deg;  // turning angle at the start of each edge, degrees
  // Its own vote on its orientation (which side of its boundary it lies on, along the body's
  // normals), over its largest possible value: from -1 to 1, positive when it agrees with the
  // orientation taken. Near 0 for a half-tube round a limb.
  double vote = 0;
  // Oriented by the panels sewn to it, against its own vote (resolve_panels).
  bool turned_by_seams = false;

  int side_count() const { return static_cast<int>(side_begin.size()); }
  // Edges of side i: [side_begin[i], side_begin[i+1]) (wrapping to edges.size()).
  int side_end(int i) const;
};

// Start node of a loop edge in its traversal direction, and end node.
int loop_start_node(const CurveNetwork& net, const LoopEdge& e);
int loop_end_node(const CurveNetwork& net, const LoopEdge& e);

// Resolves every panel (and the mirror copy of each mirrored panel, which follows its original
// in the result), each oriented counter-clockwise seen from outside: a panel sewn to oriented
// panels the way its seams agree with them, the others by their own vote (panel_loop.cpp). Corners:
// the junctions turning more than the file's corner_angle, or the panel's explicit corners; at
// least 3 (the sharpest junctions are promoted). Throws SketchError with the panel's path when
// curves do not meet, the loop does not close or a panel has fewer than 3 junctions.
std::vector<PanelLoop> resolve_panels(const GarmentRequest& sketch, const CurveNetwork& net,
                                      const BodySurface& body);

// Ids of curves that need mirror copies: those of mirrored panels and every "<id>.mirror"
// reference, by base id.
std::set<std::string> curves_to_mirror(const GarmentRequest& sketch);

}  // namespace sd::garment
