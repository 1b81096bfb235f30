#pragma once
// Small scenes shared by the simulator tests.

#include <Eigen/Core>
#include <random>
#include <string>
#include <vector>

#include "sim/cloth_model.hpp"
#include "sim/fabric.hpp"
#include "sim/sheet.hpp"
#include "sim/simulation.hpp"

namespace sd::sim::testing {

struct SheetSetup {
  SheetScene scene;
  ClothModel model;
};

// A horizontal sheet of `size` metres with n×n quads centred at `centre`, free unless `pins`
// names corners or edges (SheetSpec::pins).
inline SheetSetup horizontal_sheet(int n, double size, const Eigen::Vector3d& centre,
                                   const FabricParameters& fabric = fabric_preset("cotton"),
                                   std::vector<std::string> pins = {}) {
  SheetSpec spec;
  spec.orientation = SheetOrientation::horizontal;
  spec.size = {size, size};
  spec.columns = n;
  spec.rows = n;
  spec.centre = centre;
  spec.pins = std::move(pins);
  SheetSetup s{build_sheet(spec), {}};
  s.model = build_cloth_model(s.scene.input, fabric);
  return s;
}

// The Cusick drape test's specimen (ISO 9073-9): a horizontal 30 cm disc with `cells` quads
// across its diameter, clamped at its centre by the 18 cm support (pin "centre:0.09").
inline SheetScene cusick_disc(int cells) {
  SheetSpec spec;
  spec.shape = SheetShape::disc;
  spec.size = {0.3, 0.3};
  spec.columns = spec.rows = cells;
  spec.orientation = SheetOrientation::horizontal;
  spec.centre = {0.0, 1.0, 0.0};
  spec.pins = {"centre:0.09"};
  return build_sheet(spec);
}

inline std::vector<Pin> fixed_pins(const SheetScene& scene) {
  std::vector<Pin> pins;
  for (int v : scene.pinned_vertices) pins.push_back({v, {}});
  return pins;
}

// A random smooth deformation of the rest shape (rotation, anisotropic stretch, a bend and
// noise), so conditions are stretched, compressed, sheared and folded at once.
inline Eigen::VectorXd random_configuration(const Eigen::MatrixX3d& rest, std::mt19937& rng,
                                            double noise = 0.05) {
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::Matrix3d deformation = Eigen::Matrix3d::Identity();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) deformation(r, c) += 0.3 * uniform(rng);
  const double bend = 2.0 * uniform(rng);
  Eigen::VectorXd x(3 * rest.rows());
  for (Eigen::Index i = 0; i < rest.rows(); ++i) {
    Eigen::Vector3d p = rest.row(i).transpose();
    p.z() += bend * p.x() * p.x();
    p = deformation * p;
    for (int k = 0; k < 3; ++k) p[k] += noise * uniform(rng);
    x.segment<3>(3 * i) = p;
  }
  return x;
}

}  // namespace sd::sim::testing
