#pragma once
// One panel of a garment filled with quads (the third stage of build_garment, garment_mesh.hpp):
// its sides' points go to the quad filler, and the interior is laid on the body's offset surface
// or spans a hollow between its curves (docs/garment.md, "Panel surfaces"); the fill, its
// smoothing along the body and their unfolded versions compete on the quality gate's measures.

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "garment/body_surface.hpp"
#include "garment/curve_network.hpp"
#include "garment/garment_mesh.hpp"
#include "garment/garment_request.hpp"
#include "garment/panel_loop.hpp"
#include "meshing/patch_fill.hpp"

namespace sd::garment {

// An original panel's (not a mirror copy's) quads: the fill of its sides (`side_points`, corner to
// corner), laid on the body's offset surface or spanning a hollow (sets panel.fit and
// panel.span_gap), then the best of the fill, its smoothing along the body and their unfolded
// versions. Throws SketchError at the panel's path when the filler cannot fill it.
meshing::FilledPatch fill_panel(const GarmentRequest& sketch, const PanelSpec& spec,
                                const PanelLoop& loop, const CurveNetwork& net,
                                const std::vector<Eigen::MatrixX3d>& side_points,
                                const BodySurface& body, GarmentPanel& panel);

// The projection a filled panel's vertices are moved with (fit "body": onto the body's offset
// surface when less than an edge length outside it; "free": out of the body only), as
// fill_panel projects them but without its cache and its far-side test: for the repair of folds
// after stitching (garment_mesh.cpp), which moves a few vertices near a seam. Holds `body`.
std::function<Eigen::Vector3d(const Eigen::Vector3d&)> panel_projection(
    const GarmentRequest& sketch, const PanelSpec& spec, const PanelLoop& loop,
    const CurveNetwork& net, const BodySurface& body, const std::string& fit);

}  // namespace sd::garment
