#pragma once
// The Cusick drape test's measures (BS 5058, ISO 9073-9; Cusick 1968): a disc of fabric of
// radius R held between two discs of radius r drapes into folds; its shadow seen along the
// vertical gives the drape coefficient DC = (shadow − πr²) / (πR² − πr²) and the folds' count
// (nodes). docs/fabrics.md, "Cusick drape".

#include <Eigen/Core>
#include <vector>

namespace sd::sim {

struct DrapeShadowOptions {
  double specimen_radius = 0.15;  // m, R
  double support_radius = 0.09;   // m, r
  double pixel = 1e-3;            // m, side of the raster's square pixels
  int angle_bins = 360;           // the shadow's outline r(θ) is sampled in this many sectors
};

struct DrapeShadow {
  double shadow_area = 0.0;        // m², the union of the projected triangles
  double drape_coefficient = 0.0;  // (shadow − πr²) / (πR² − πr²)
  int nodes = 0;                   // folds: the outline's crests (see count_nodes)
  std::vector<double> outline;     // m, the shadow's largest radius in each angular sector
};

// Projects the cloth (positions #V by 3, triangles #F by 3) along `up` onto the plane through
// `centre` and rasterises the union of its triangles (a pixel counts when its centre lies in a
// projected triangle). The pixel error of the area is about perimeter × pixel / 10 for a smooth
// outline (< 0.1 % of the specimen at 1 mm).
DrapeShadow measure_drape_shadow(const Eigen::MatrixX3d& positions,
                                 const Eigen::MatrixX3i& triangles, const Eigen::Vector3d& centre,
                                 const Eigen::Vector3d& up, const DrapeShadowOptions& options = {});

// The crests of a closed outline r(θ): after a circular moving average over 3 % of the circle
// (narrower ripples are not folds), the number of times it climbs from below mean − δ to above
// mean + δ, with δ = 10 % of its half range and at least 1 mm (a flat outline has no nodes).
int count_nodes(const std::vector<double>& outline);

}  // namespace sd::sim
