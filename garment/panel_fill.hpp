#pragma once
// One panel of a garment filled with quads (the third stage of build_garment, garment_mesh.hpp):
// its sides' points go to the quad filler, and the interior is laid on the body's offset surface
// or spans a hollow between its curves (docs/garment.md, "Panel surfaces"); the fill, its
// smoothing along the body and their unfolded versions compete on the quality gate's measures.

#include <Eigen/Core>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "garment/body_surface.hpp"
#include "garment/curve_network.hpp"
#include "garment/garment_mesh.hpp"
#include "garment/garment_request.hpp"
#include "garment/panel_loop.hpp"
#include "meshing/patch_fill.hpp"

namespace sd::garment {

// Where a filled panel's vertices would lie on their own walls of the body's narrow creases
// (crease_wall.hpp): each moved vertex (patch vertex, position) and the panel's quality with
// them. Not applied by fill_panel: build_garment applies them only to panels that pass through
// another where they are (the t-shirts' underarms move by 1-2 mm and no longer rest at 2 cm
// edges); empty when no vertex moves or the moves would fold a quad or make a sliver.
struct CreaseMoves {
  std::vector<std::pair<int, Eigen::Vector3d>> moves;
  meshing::QuadQuality quality;
};

// An original panel's (not a mirror copy's) quads: the fill of its sides (`side_points`, corner to
// corner), laid on the body's offset surface or spanning a hollow (sets panel.fit and
// panel.span_gap), then the best of the fill, its smoothing along the body and their unfolded
// versions; `crease` (if given) receives its narrow-crease moves. Throws SketchError at the
// panel's path when the filler cannot fill it.
meshing::FilledPatch fill_panel(const GarmentRequest& sketch, const PanelSpec& spec,
                                const PanelLoop& loop, const CurveNetwork& net,
                                const std::vector<Eigen::MatrixX3d>& side_points,
                                const BodySurface& body, GarmentPanel& panel,
                                CreaseMoves* crease = nullptr);

// The projection a filled panel's vertices are moved with (fit "body": onto the body's offset
// surface when less than an edge length outside it; "free": out of the body only), as
// fill_panel projects them but without its cache and its far-side test: for the repair of folds
// after stitching (garment_mesh.cpp), which moves a few vertices near a seam. Holds `body`.
std::function<Eigen::Vector3d(const Eigen::Vector3d&)> panel_projection(
    const GarmentRequest& sketch, const PanelSpec& spec, const PanelLoop& loop,
    const CurveNetwork& net, const BodySurface& body, const std::string& fit);

}  // namespace sd::garment
